#!/usr/bin/python3
"""Work–precision study of vibro's settings (error against CPU time, log–log).

For each scene: CVODE Adams and BDF over rtol 1e-4 … 1e-12 (atol = rtol·1e-2), the exact engine,
and the chattering treatments (accumulation, threshold) over their switch velocity. The error is
the largest difference of the first stick and release event times against the exact
engine with chatter_switch = 1e-9 (the reference), relative to the forcing period. CPU time is the
child-process user+system time of one `vibro simulate` (store off), so the figures include start-up.

Usage: benchmarks/work_precision.py [--vibro build/vibro] [--out docs/work_precision] [--quick]
Writes PREFIX.csv (one row per run) and PREFIX.png (one panel per scene).
"""
import argparse
import csv
import math
import os
import resource
import subprocess
import sys
import tempfile

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = [
    ("Fig. 5 (1-DOF, r = 0.75)", "fig05_coexistence.toml", 50),
    ("Fig. 8 (1-DOF, r = 0.75)", "fig08_preload.toml", 50),
    ("clearance (Fig. 11, r = 0)", "fig11_clearance.toml", 50),
    ("2-DOF chain (r = 0.5)", "chain2.toml", 50),
    ("3-DOF chain (r = 0)", "chain3.toml", 50),
    ("10-DOF stiff chain", "chain10_stiff.toml", 2),
]


def run(vibro, scene, periods, sets, h5):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    cmd = [vibro, "simulate", os.path.join(ROOT, "data", "scenes", scene), "--out", h5, "--json",
           "--set", f"run.periods={periods}", "--set", "run.samples_per_period=0"]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if p.returncode != 0:
        return None, cpu
    with h5py.File(h5, "r") as f:
        kinds = f["events/kind"][:]
        t = f["events/t"][:]
        T = float(f.attrs["forcing_period"])
    milestones = [x for x, k in zip(t, kinds) if k in (3, 4)][:12]  # sticks and releases
    return (milestones, T), cpu


def error(ms, ref):
    (a, T), (b, _) = ms, ref
    n = min(len(a), len(b))
    if n == 0:
        return float("nan")
    return max(abs(x - y) for x, y in zip(a[:n], b[:n])) / T


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--vibro", default=os.path.join(ROOT, "build", "vibro"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "work_precision"))
    ap.add_argument("--quick", action="store_true", help="fewer settings (a smoke test)")
    args = ap.parse_args()
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    rtols = [1e-4, 1e-6, 1e-8, 1e-10, 1e-12] if not args.quick else [1e-6, 1e-10]
    switches = [1e-2, 1e-3, 1e-4, 1e-6] if not args.quick else [1e-3, 1e-6]
    rows = []
    with tempfile.TemporaryDirectory() as d:
        h5 = os.path.join(d, "run.h5")
        for label, scene, periods in SCENES:
            ref, _ = run(args.vibro, scene, periods, ['run.engine="exact"', "run.chatter_switch=1e-9"], h5)
            if ref is None:
                print(f"{label}: the reference run failed", file=sys.stderr)
                continue
            settings = [("exact", "exact", None, ['run.engine="exact"'])]
            for method in ("adams", "bdf"):
                for rtol in rtols:
                    settings.append((f"cvode {method}", method, rtol,
                                     ['run.engine="cvode"', f'run.method="{method}"', f"run.rtol={rtol:g}",
                                      f"run.atol={rtol * 1e-2:g}"]))
            for chatter in ("accumulation", "threshold"):
                for sw in switches:
                    settings.append((f"exact {chatter}", chatter, sw,
                                     ['run.engine="exact"', f'run.chatter="{chatter}"', f"run.chatter_switch={sw:g}"]))
            for name, variant, knob, sets in settings:
                ms, cpu = run(args.vibro, scene, periods, sets, h5)
                err = error(ms, ref) if ms else float("nan")
                rows.append({"scene": label, "setting": name, "knob": "" if knob is None else f"{knob:g}",
                             "cpu_seconds": f"{cpu:.4f}", "error": f"{err:.3e}", "status": "ok" if ms else "failed"})
                print(f"{label:30s} {name:22s} {rows[-1]['knob']:>8s} cpu {cpu:8.3f} s  error {err:.2e}", flush=True)
    with open(args.out + ".csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    scenes = [s[0] for s in SCENES]
    fig, axes = plt.subplots(2, 3, figsize=(15, 9))
    for ax, label in zip(axes.flat, scenes):
        for name, marker in (("cvode adams", "o-"), ("cvode bdf", "s-"), ("exact", "*"),
                             ("exact accumulation", "^-"), ("exact threshold", "v-")):
            pts = [(float(r["cpu_seconds"]), max(float(r["error"]), 1e-17)) for r in rows
                   if r["scene"] == label and r["setting"] == name and r["status"] == "ok"
                   and not math.isnan(float(r["error"]))]
            if pts:
                ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker, label=name, ms=5)
        ax.set_title(label, fontsize=10)
        ax.set_xlabel("CPU time per run [s]")
        ax.set_ylabel("event-time error / T")
        ax.grid(True, which="both", alpha=0.3)
    axes.flat[0].legend(fontsize=8)
    fig.suptitle("vibro work–precision: error against the exact engine (switch 1e-9) vs CPU time")
    fig.tight_layout()
    fig.savefig(args.out + ".png", dpi=100)
    print(args.out + ".csv")
    print(args.out + ".png")


if __name__ == "__main__":
    main()
