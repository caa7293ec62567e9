#!/usr/bin/env bash
# Configures and builds vibro (Release, warnings as errors, MPI studies) into ./build.
#   build.sh run    the library, the `vibro` command and the Python package (no tests, no
#                   benchmarks: what scripts/install-deps.sh run provides is enough)
#   build.sh test   all of that and the test suite and the benchmarks (the default)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
mode=${1:-test}
case $mode in
  run) extras=OFF ;;
  test) extras=ON ;;
  *) echo "usage: build.sh [run|test] (not '$mode')" >&2; exit 2 ;;
esac
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release -DVIBRO_WERROR=ON -DVIBRO_MPI=ON \
      -DVIBRO_BUILD_TESTS=$extras -DVIBRO_BUILD_BENCHMARKS=$extras \
      -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build "$root/build" -j "$(nproc)"
