#!/usr/bin/env bash
# Configures and builds vibro (Release, warnings as errors, MPI studies) into ./build.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release -DVIBRO_WERROR=ON -DVIBRO_MPI=ON \
      -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build "$root/build" -j "$(nproc)"
