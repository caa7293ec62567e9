#!/usr/bin/env bash
# Copies a build's `vibro`, libvibro and its plugins into DIR, so that the copy keeps running the
# code it was built from after the build is remade (scripts/compare_events.py, benchmarks against
# the commit before). Usage: scripts/snapshot_build.sh DIR [BUILD]   (BUILD: ./build)
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: snapshot_build.sh DIR [BUILD]" >&2; exit 2; }
dir=$1
build=${2:-$(cd "$(dirname "$0")/.." && pwd)/build}
[ -x "$build/vibro" ] || { echo "snapshot_build.sh: no vibro in $build" >&2; exit 2; }
mkdir -p "$dir"
cp -a "$build/vibro" "$build"/lib*.so* "$dir"/
echo "$dir: $(ls "$dir" | tr '\n' ' ')"
