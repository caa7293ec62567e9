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
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import DEFAULT_VIBRO, ROOT, milestone_error, pyplot, run_vibro, save_figure, write_csv  # noqa: E402

SCENES = [
    ("Fig. 5 (1-DOF, r = 0.75)", "fig05_coexistence.toml", 50),
    ("Fig. 8 (1-DOF, r = 0.75)", "fig08_preload.toml", 50),
    ("clearance (Fig. 11, r = 0)", "fig11_clearance.toml", 50),
    ("2-DOF chain (r = 0.5)", "chain2.toml", 50),
    ("3-DOF chain (r = 0)", "chain3.toml", 50),
    ("10-DOF stiff chain", "chain10_stiff.toml", 2),
]


def run(vibro, scene, periods, sets):
    """(milestones, T) or None when the run failed, and the CPU time."""
    r = run_vibro(vibro, scene, periods, sets)
    return ((r.milestones(12), r.T) if r.ok else None), r.cpu


def error(ms, ref):
    (a, T), (b, _) = ms, ref
    return milestone_error(a, b, T)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--vibro", default=DEFAULT_VIBRO)
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "work_precision"))
    ap.add_argument("--quick", action="store_true", help="fewer settings (a smoke test)")
    args = ap.parse_args()
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    rtols = [1e-4, 1e-6, 1e-8, 1e-10, 1e-12] if not args.quick else [1e-6, 1e-10]
    switches = [1e-2, 1e-3, 1e-4, 1e-6] if not args.quick else [1e-3, 1e-6]
    rows = []
    for label, scene, periods in SCENES:
        ref, _ = run(args.vibro, scene, periods, ['run.engine="exact"', "run.chatter_switch=1e-9"])
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
            ms, cpu = run(args.vibro, scene, periods, sets)
            err = error(ms, ref) if ms else float("nan")
            rows.append({"scene": label, "setting": name, "knob": "" if knob is None else f"{knob:g}",
                         "cpu_seconds": f"{cpu:.4f}", "error": f"{err:.3e}", "status": "ok" if ms else "failed"})
            print(f"{label:30s} {name:22s} {rows[-1]['knob']:>8s} cpu {cpu:8.3f} s  error {err:.2e}", flush=True)
    write_csv(rows, args.out + ".csv")
    print(args.out + ".csv")
    plt = pyplot()
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
    save_figure(fig, args.out + ".png")


if __name__ == "__main__":
    main()
