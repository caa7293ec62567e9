#!/usr/bin/python3
"""Modal truncation: what keeping only the lowest m modes costs in accuracy and saves in time.

For the 3-DOF chain and the 10-DOF stiff chain (physical form), runs the exact engine with
structure.modes = 1 … n and compares the first 12 stick/release times and the sticking fraction
with the full model. Writes PREFIX.csv and PREFIX.png.

Usage: benchmarks/modal_truncation.py [--vibro build/vibro] [--out docs/modal_truncation]
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import DEFAULT_VIBRO, ROOT, milestone_error, pyplot, run_vibro, save_figure, write_csv  # noqa: E402

CASES = [("3-DOF chain (r = 0)", "chain3.toml", 3, 100, []),
         ("10-DOF stiff chain, 5 % damping", "chain10_stiff.toml", 10, 20,
          ["structure.damping_ratios=[0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05]"])]


def run(vibro, scene, periods, sets):
    r = run_vibro(vibro, scene, periods, sets)
    if not r.ok:
        raise SystemExit(f"vibro simulate {scene} failed: {r.stderr}")
    return r.milestones(12), r.T, r.summary, r.cpu


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--vibro", default=DEFAULT_VIBRO)
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "modal_truncation"))
    args = ap.parse_args()
    rows = []
    for label, scene, n, periods, sets in CASES:
        ref, T, jref, cref = run(args.vibro, scene, periods, sets)
        for m in range(1, n + 1):
            ms, _, j, cpu = run(args.vibro, scene, periods, sets + [f"structure.modes={m}"])
            err = milestone_error(ms, ref, T)
            sp, spr = j["attractor"]["sticking_fraction"], jref["attractor"]["sticking_fraction"]
            sp_err = abs(sp - spr) if sp is not None and spr is not None else float("nan")
            rows.append({"case": label, "modes": m, "event_error": f"{err:.3e}",
                         "sp_error": f"{sp_err:.3e}", "cpu_seconds": f"{cpu:.4f}",
                         "cpu_full": f"{cref:.4f}"})
            print(f"{label:34s} modes {m:2d}: event error/T {err:.2e}, SP error {sp_err:.2e}, "
                  f"cpu {cpu:.3f} s (full {cref:.3f} s)", flush=True)
    write_csv(rows, args.out + ".csv")
    print(args.out + ".csv")
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    for ax, (label, *_rest) in zip(axes, CASES):
        r = [x for x in rows if x["case"] == label]
        m = [x["modes"] for x in r]
        ax.semilogy(m, [max(float(x["event_error"]), 1e-17) for x in r], "o-", label="event-time error / T")
        ax.semilogy(m, [max(float(x["sp_error"]), 1e-17) for x in r], "s-", label="sticking-fraction error")
        ax2 = ax.twinx()
        ax2.plot(m, [float(x["cpu_seconds"]) for x in r], "k--", label="CPU time [s]")
        ax2.set_ylabel("CPU time per run [s]")
        ax.set_xlabel("modes kept")
        ax.set_title(label)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    save_figure(fig, args.out + ".png")


if __name__ == "__main__":
    main()
