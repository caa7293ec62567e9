#!/usr/bin/env bash
# Quick start: install what running needs (no test tools), build, and simulate the default scene
# (Fig. 8 of the paper: 1-DOF preload, r = 0.75, omega = 2.8, f = 1.2).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh" run
"$root/scripts/build.sh" run
"$root/build/vibro" model "$root/data/scenes/default.toml"
"$root/build/vibro" simulate "$root/data/scenes/default.toml" --out "$root/default.h5"
