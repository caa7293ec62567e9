#!/usr/bin/env bash
# Installs what is missing for the tests too, builds with the tests, and runs the whole suite with ctest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh" test
"$root/scripts/build.sh" test
cd "$root/build"
ctest --output-on-failure -j "$(nproc)" "$@"
