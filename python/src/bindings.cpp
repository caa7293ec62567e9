#include <pybind11/pybind11.h>
PYBIND11_MODULE(_vibro, m) { m.attr("version") = VIBRO_VERSION; }
