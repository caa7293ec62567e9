#!/usr/bin/python3
"""The distance between a compliant stop's trajectory and the rigid model's, against the stiffness
(docs/loads.md, "The distance to the rigid model"; docs/compliant.md).

    scripts/compliant_convergence.py VIBRO [--scene data/scenes/sdnd121_compliant.toml]
                                           [--periods 2] [--csv OUT.csv] [--png OUT.png]

Runs `vibro simulate SCENE --rigid-beside --json` at stiffnesses 1e8 … 1e14 (the scene's
[stop].stiffness replaced) and prints, per stiffness, the largest distance between the two
trajectories over the run's dense samples and the fitted slope of log distance against log k
(−1/2 expected: the penetration scales as v/ω_c, ω_c = √(k/m)). --png draws it with the k^(−1/2) line.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("vibro")
    ap.add_argument("--scene", default=os.path.join(ROOT, "data/scenes/sdnd121_compliant.toml"))
    ap.add_argument("--periods", type=int, default=2)
    ap.add_argument("--csv")
    ap.add_argument("--png")
    a = ap.parse_args()
    rows = []
    for e in range(8, 15):
        k = 10.0 ** e
        out = subprocess.run([a.vibro, "simulate", a.scene, "--set", f"stop.stiffness={k:g}", "--set",
                              f"run.periods={a.periods}", "--set", "run.samples_per_period=2000", "--rigid-beside",
                              "--json"], capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit(f"k = {k:g}: vibro exited {out.returncode}: {out.stderr.strip()}")
        r = json.loads(out.stdout)["rigid_model"]
        c = r["contacts"][0]
        rows.append((k, r["distance"]["max"], r["distance"]["time_of_max"], c["peak_force_max"], c["duration_mean"],
                     c["phases"]))
        print(f"k = {k:8.1e}  distance {rows[-1][1]:.4g} (t = {rows[-1][2]:.6g})  peak force {rows[-1][3]:.6g}  "
              f"duration {rows[-1][4]:.4g}  phases {rows[-1][5]}")
    # The slope over the asymptotic range k ≥ 1e10 (below, the compliant run's impacts differ in
    # number from the rigid one's within the window, and the distance is of the clearance's order).
    fit = [r for r in rows if r[0] >= 1e10]
    xs = [math.log10(r[0]) for r in fit]
    ys = [math.log10(r[1]) for r in fit]
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    print(f"slope of log distance against log k over k >= 1e10: {slope:.4f} (k^(-1/2): -0.5)")
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["stiffness", "distance", "time_of_max", "peak_force_max", "duration_mean", "phases"])
            w.writerows(rows)
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6, 4))
        ks = [r[0] for r in rows]
        ax.loglog(ks, [r[1] for r in rows], "o-", label="vibro: max |x_compliant − x_rigid|")
        ref = rows[-1][1]
        ax.loglog(ks, [ref * (k / rows[-1][0]) ** -0.5 for k in ks], "k--", lw=0.8, label="k^(−1/2)")
        ax.set_xlabel("stop stiffness k [N/m]")
        ax.set_ylabel("distance to the rigid model [m]")
        ax.set_title(f"SDND121 scene, first {a.periods} period(s): slope {slope:.3f} (k ≥ 1e10)")
        ax.grid(True, which="both", lw=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
