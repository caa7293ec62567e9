#!/usr/bin/env bash
# The installed vibro, as a user gets it: `cmake --install` into a fresh prefix, which is then
# moved (nothing may point back into the build or source tree), and
#  1. a separate CMake project (tests/consumer) finds it with find_package(vibro), links
#     vibro::vibro, and its program checks release phases against the closed form;
#  2. the installed `vibro` simulates a shipped scene from share/vibro/scenes and `vibro plot`
#     draws it with the plotting code in share/vibro/;
#  3. the installed Python package imports from the prefix and simulates;
#  4. the CSV tools docs/validation.md uses are installed and work: `vibro-branch-to-csv` exports a
#     branch that `vibro validate` then confirms point by point, `vibro-events-to-csv` gives each
#     reference problem's events exactly as shipped, and `vibro score` against the installed
#     share/vibro/benchmarks agrees;
#  5. without that plotting code, `vibro plot` fails with exit 1 and says what is missing.
# Usage: install_test.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build=$1 source=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/staged" >/dev/null
mv "$work/staged" "$work/prefix"
prefix=$work/prefix

# Nothing installed refers to the build or source tree (rpaths, script paths).
for f in "$prefix"/bin/vibro* "$prefix"/lib/libvibro*.so* "$prefix"/share/vibro/vibro_plot.py; do
  if grep -q -F -e "$build" -e "$source" "$f"; then
    echo "FAIL: $f refers to $build or $source" >&2
    exit 1
  fi
done

# 1. The consumer project.
cmake -S "$source/tests/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/consumer" >/dev/null
"$work/consumer/release_phase" "$prefix/share/vibro/scenes/fig08_preload.toml"

# 2. The installed command and its plots.
"$prefix/bin/vibro" simulate "$prefix/share/vibro/scenes/fig08_preload.toml" --set run.periods=10 \
  --out "$work/run.h5" >/dev/null
"$prefix/bin/vibro" plot "$work/run.h5" --out "$work/run"
for png in run_xB run_phase run_section; do
  [ -s "$work/$png.png" ] || { echo "FAIL: vibro plot made no $png.png" >&2; exit 1; }
done

# 3. The installed Python package (python3 and the prefix's site-packages directory).
site=$(cd "$prefix" && ls -d lib/python3*/site-packages)
PYTHONPATH="$prefix/$site" /usr/bin/python3 - "$prefix" <<'PY'
import math, sys, vibro
prefix = sys.argv[1]
assert vibro.__file__.startswith(prefix), vibro.__file__
scene = vibro.load_scene(prefix + "/share/vibro/scenes/fig08_preload.toml",
                         set={"stop.restitution": 0, "run.periods": 10})
run = vibro.simulate(scene)
releases = run.events[run.events["kind"] == 4]["t"]
phi1 = math.asin(1 / 1.2)  # MODEL §6.1: sin φ1 = 1/f
worst = max(abs(math.remainder(2.8 * t - phi1, 2 * math.pi)) for t in releases)
assert len(releases) >= 9 and worst < 1e-9, (len(releases), worst)
PY

# 4. The CSV tools and the reference problems (docs/validation.md).
diff -r "$source/data/benchmarks" "$prefix/share/vibro/benchmarks" >/dev/null ||
  { echo "FAIL: share/vibro/benchmarks differs from data/benchmarks" >&2; exit 1; }
scenes=$prefix/share/vibro/scenes
"$prefix/bin/vibro" continue "$scenes/fig08_preload.toml" --set stop.restitution=0.0 \
  --param excitation.amplitude --to 1.3 --out "$work/branch.h5" >/dev/null
"$prefix/bin/vibro-branch-to-csv" "$work/branch.h5" "$work/branch.csv"
rows=$(($(wc -l <"$work/branch.csv") - 1))
[ "$rows" -ge 5 ] || { echo "FAIL: vibro-branch-to-csv wrote $rows rows" >&2; exit 1; }
"$prefix/bin/vibro" validate "$scenes/fig08_preload.toml" "$work/branch.csv" \
  --set stop.restitution=0.0 --param excitation.amplitude >"$work/validate.txt" ||
  { echo "FAIL: vibro validate did not confirm vibro's own branch:" >&2; cat "$work/validate.txt" >&2; exit 1; }
grep -q "^$rows of $rows points confirmed" "$work/validate.txt" ||
  { echo "FAIL: not all $rows rows confirmed: $(tail -1 "$work/validate.txt")" >&2; exit 1; }
"$prefix/bin/vibro-auto-to-csv" --help >/dev/null ||
  { echo "FAIL: vibro-auto-to-csv --help" >&2; exit 1; }
bench=$prefix/share/vibro/benchmarks
for name in chain_3dof two_flights_1dof; do
  "$prefix/bin/vibro-events-to-csv" "$bench/$name.h5" | cmp -s - "$bench/$name.csv" ||
    { echo "FAIL: vibro-events-to-csv $name.h5 differs from the shipped $name.csv" >&2; exit 1; }
  "$prefix/bin/vibro" score "$bench/$name.toml" "$bench/$name.csv" >"$work/score.txt" ||
    { echo "FAIL: vibro score $name: $(tail -1 "$work/score.txt")" >&2; exit 1; }
done

# 5. Plotting code missing: exit 1 (not "bad input"), with a message naming where it looked.
rm "$prefix/share/vibro/vibro_plot.py"
set +e
msg=$("$prefix/bin/vibro" plot "$work/run.h5" --out "$work/again" 2>&1)
rc=$?
set -e
if [ $rc -ne 1 ] || ! grep -q "share/vibro/vibro_plot.py" <<<"$msg"; then
  echo "FAIL: without the plotting code, vibro plot gave exit $rc: $msg" >&2
  exit 1
fi
echo "install test: ok"
