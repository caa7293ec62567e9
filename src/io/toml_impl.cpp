// toml++'s compiled part (what libtomlplusplus.so holds) built into libvibro, which exports it as
// the shared library does (TOML_SHARED_LIB), so that libvibro needs no libtomlplusplus.so: one
// shared library fewer for every process to map at start-up, and one whose symbols were all bound
// at load rather than lazily (docs/performance.md, "Start-up"). src/io/scene_toml.cpp and
// scene_file.cpp include toml++ as before.
#define TOML_IMPLEMENTATION
#include <toml++/toml.h>
