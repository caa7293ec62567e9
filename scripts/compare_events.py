#!/usr/bin/python3
"""Events to the bit: run every shipped scene with two `vibro` binaries and compare their /events.

    scripts/compare_events.py OLD_VIBRO NEW_VIBRO [--periods 60] [--quad-periods N]
                              [--precision double,quad] [--scenes GLOB ...] [--keep DIR]

Each scene (by default every data/scenes/**/*.toml and data/benchmarks/*.toml) is simulated by
both binaries with `--out`, double and quad precision, the same overrides; every /events column
of the two files is compared bit for bit (NaN equal to NaN). Prints one line per scene and
precision: `identical`, or the columns that differ with their largest relative difference.
Exit 0 when every column of every scene is identical, 1 otherwise, 2 on bad arguments.

  --periods N       run.periods of every run (default 60).
  --quad-periods N  run.periods of the quad runs only (default: --periods). Quad costs ~100× double:
                    the 50-mode beam takes over 13 minutes at 60 periods on a loaded machine, so a
                    quick check may run quad shorter, e.g. `--quad-periods 5`; the full default
                    stays the release check.
  --scenes GLOB ... only the scenes these globs match (`**` recursive; a relative glob is taken from
                    the current folder, else from the repository), e.g.
                    `--scenes 'data/scenes/*chain*.toml' data/benchmarks/fig8.toml`.
  --precision LIST  double, quad or both (default double,quad).
  --keep DIR        keep the HDF5 files in DIR.

Each binary runs with the libvibro.so beside it (LD_LIBRARY_PATH = its folder): compare copies
made by scripts/snapshot_build.sh, or build folders. A change to the engine or the automaton that should leave single-stop scenes untouched is checked
with it against the commit before (docs/performance.md, "Events to the bit").
"""
import argparse
import glob
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(vibro, scene, precision, periods, out):
    cmd = [vibro, "simulate", scene, "--out", out, "--set", f"run.periods={periods}"]
    if precision != "double":
        cmd += ["--set", f'run.precision="{precision}"', "--set", 'run.engine="exact"']
    # The binary finds libvibro through its RUNPATH (its build folder): a copy of a build, with its
    # libraries beside it, must use those, so the folder of the binary comes first.
    env = dict(os.environ, LD_LIBRARY_PATH=os.path.dirname(os.path.abspath(vibro)))
    r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
    return r.returncode, r.stderr.strip().splitlines()[-1:] if r.stderr else []


def columns(path):
    with h5py.File(path, "r") as f:
        if "events" not in f:
            return {}
        return {k: f["events"][k][()] for k in f["events"]}


def compare(a, b):
    diffs = []
    for k in sorted(set(a) | set(b)):
        if k not in a or k not in b:
            diffs.append(f"{k}: only in {'old' if k in a else 'new'}")
            continue
        x, y = a[k], b[k]
        if x.shape != y.shape:
            diffs.append(f"{k}: {x.shape[0]} vs {y.shape[0]} events")
            continue
        if x.dtype.kind == "f":
            same = (x.view(np.uint64 if x.itemsize == 8 else np.uint32) ==
                    y.view(np.uint64 if y.itemsize == 8 else np.uint32)) | (np.isnan(x) & np.isnan(y))
            if not same.all():
                with np.errstate(invalid="ignore", divide="ignore"):
                    rel = np.abs(x - y) / np.maximum(np.maximum(np.abs(x), np.abs(y)), 1e-300)
                rel = rel[~same]
                diffs.append(f"{k}: {int((~same).sum())} differ, max rel {np.nanmax(rel) if rel.size else 0:.2e}")
        elif not np.array_equal(x, y):
            diffs.append(f"{k}: {int((x != y).sum())} differ")
    return diffs


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("old")
    p.add_argument("new")
    p.add_argument("--periods", type=int, default=60)
    p.add_argument("--quad-periods", type=int, help="run.periods of the quad runs (default: --periods)")
    p.add_argument("--precision", default="double,quad")
    p.add_argument("--scenes", nargs="*")
    p.add_argument("--keep", help="keep the HDF5 files in this folder")
    a = p.parse_args()
    for exe in (a.old, a.new):
        if not os.access(exe, os.X_OK):
            print(f"compare_events: {exe}: not an executable", file=sys.stderr)
            return 2
        if not glob.glob(os.path.join(os.path.dirname(os.path.abspath(exe)), "libvibro.so*")):
            print(f"compare_events: {exe}: no libvibro.so beside it (copy a build with "
                  "scripts/snapshot_build.sh, not the binary alone)", file=sys.stderr)
            return 2
    for n in (a.periods, a.quad_periods):
        if n is not None and n < 1:
            print(f"compare_events: periods must be >= 1, not {n}", file=sys.stderr)
            return 2
    bad_prec = [q for q in a.precision.split(",") if q not in ("double", "quad")]
    if bad_prec:
        print(f"compare_events: --precision: {','.join(bad_prec)} is not double or quad", file=sys.stderr)
        return 2
    patterns = a.scenes or [os.path.join(ROOT, "data/scenes/**/*.toml"),
                            os.path.join(ROOT, "data/benchmarks/*.toml")]

    def matches(pat):
        found = glob.glob(pat, recursive=True)
        if not found and not os.path.isabs(pat):
            found = glob.glob(os.path.join(ROOT, pat), recursive=True)
        return [os.path.abspath(f) for f in found]

    scenes = sorted({s for pat in patterns for s in matches(pat)})
    if not scenes:
        print("compare_events: no scene matches", file=sys.stderr)
        return 2
    tmp = a.keep or tempfile.mkdtemp(prefix="compare_events.")
    os.makedirs(tmp, exist_ok=True)
    bad = 0
    for scene in scenes:
        name = os.path.relpath(scene, ROOT)
        for prec in a.precision.split(","):
            outs = []
            for tag, exe in (("old", a.old), ("new", a.new)):
                out = os.path.join(tmp, f"{os.path.basename(scene)}.{prec}.{tag}.h5")
                if os.path.exists(out):
                    os.remove(out)
                periods = a.quad_periods if prec == "quad" and a.quad_periods else a.periods
                rc, last = run(exe, scene, prec, periods, out)
                outs.append((rc, out, last))
            (rc0, o0, l0), (rc1, o1, l1) = outs
            if rc0 != rc1:
                print(f"{name} [{prec}]: exit {rc0} vs {rc1} {l0} {l1}")
                bad += 1
                continue
            if not (os.path.exists(o0) and os.path.exists(o1)):
                print(f"{name} [{prec}]: no file (exit {rc0}) {l0}")
                continue
            d = compare(columns(o0), columns(o1))
            n = len(columns(o1).get("t", []))
            print(f"{name} [{prec}]: " + ("identical" if not d else "DIFFERS " + "; ".join(d)) + f" ({n} events)")
            bad += bool(d)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
