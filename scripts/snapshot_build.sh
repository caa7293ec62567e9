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
# The build's vibro finds libvibro through its RUNPATH, the build folder: the copy would load the
# remade library, not its own (and a benchmark "before against after" would time the same code).
# The copy's RUNPATH becomes $ORIGIN (its own folder), written over the old string in place.
/usr/bin/python3 - "$dir/vibro" <<'PY'
import re, subprocess, sys
path = sys.argv[1]
dyn = subprocess.run(["readelf", "-d", path], capture_output=True, text=True, check=True).stdout
m = re.search(r"\((?:RUNPATH|RPATH)\)\s+Library r(?:un)?path: \[(.*)\]", dyn)
if m:
    old = m.group(1).encode() + b"\0"
    data = open(path, "rb").read()
    if data.count(old) != 1 or len(old) < len(b"$ORIGIN\0"):
        sys.exit(f"snapshot_build.sh: cannot rewrite the RUNPATH {m.group(1)!r} of {path}")
    open(path, "wb").write(data.replace(old, b"$ORIGIN".ljust(len(old), b"\0")))
PY
lib=$(ldd "$dir/vibro" | awk '/libvibro\.so/ {print $3}')
[ "$(dirname "$(readlink -f "$lib")")" = "$(readlink -f "$dir")" ] ||
  { echo "snapshot_build.sh: the copy loads $lib, not its own libvibro" >&2; exit 1; }
echo "$dir: $(ls "$dir" | tr '\n' ' ')"
