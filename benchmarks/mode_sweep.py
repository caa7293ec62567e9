#!/usr/bin/python3
"""Cost per event against the number of modes: runs BM_BeamModes of vibro_bench (the 50-node beam
of data/scenes/large/beam50.toml truncated to its lowest n modes, 50 periods, exact engine) and
BM_BeamGapProbe (one certified probe of the gap on the same truncations), and writes
docs/mode_sweep.csv and docs/mode_sweep.png: CPU per event and per probe against n, and their
ratio, the probes per event.

Usage: /usr/bin/python3 benchmarks/mode_sweep.py [--bench build/benchmarks/vibro_bench]
       [--out docs/mode_sweep] [--min-time 0.5] [--replot]
About a minute. One run: the machine is shared, so the figure comes from a single session.
"""
import argparse
import csv
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import ROOT, pyplot, save_figure, write_csv  # noqa: E402


def measure(bench, min_time):
    p = subprocess.run([bench, "--benchmark_filter=BM_Beam(Modes|GapProbe)/",
                        f"--benchmark_min_time={min_time}", "--benchmark_format=json"],
                       capture_output=True, text=True, check=True)
    rows, probe = {}, {}
    for b in json.loads(p.stdout)["benchmarks"]:
        kind, n = b["name"].split("/")[:2]
        n = int(n)
        if kind == "BM_BeamGapProbe":
            probe[n] = 1e6 / b["probes/s"]
            continue
        events_per_s = b["events/s"]
        rows[n] = {"modes": n, "us_per_event": 1e6 / events_per_s,
                   "events_per_period": events_per_s / b["periods/s"], "events_per_s": events_per_s}
    out = []
    for n in sorted(rows):
        r = rows[n]
        out.append({"modes": n, "us_per_event": f"{r['us_per_event']:.4g}",
                    "us_per_probe": f"{probe[n]:.4g}",
                    "probes_per_event": f"{r['us_per_event'] / probe[n]:.4g}",
                    "events_per_period": f"{r['events_per_period']:.4g}",
                    "events_per_s": f"{r['events_per_s']:.4g}"})
    return out


def plot(rows, path):
    n = [int(r["modes"]) for r in rows]
    us = [float(r["us_per_event"]) for r in rows]
    probe = [float(r["us_per_probe"]) for r in rows]
    per_event = [float(r["probes_per_event"]) for r in rows]
    plt = pyplot()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax.plot(n, us, "o-", label="per event (BM_BeamModes)")
    ax.plot(n, [10 * p for p in probe], "s-", label="per probe × 10 (BM_BeamGapProbe)")
    ax.set_xlabel("modes kept n")
    ax.set_ylabel("CPU [µs]")
    ax.set_title("Cost per event and per probe (50-node beam)")
    ax.set_xlim(0, max(n) + 2)
    ax.set_ylim(0, None)
    ax.grid(True, alpha=0.3)
    ax.legend()
    bx.plot(n, per_event, "o-", color="C2")
    bx.set_xlabel("modes kept n")
    bx.set_ylabel("certified probes per event")
    bx.set_title("Probes per event (= per event / per probe)")
    bx.set_xlim(0, max(n) + 2)
    bx.set_ylim(0, None)
    bx.grid(True, alpha=0.3)
    save_figure(fig, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "benchmarks", "vibro_bench"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "mode_sweep"))
    ap.add_argument("--min-time", default="0.5")
    ap.add_argument("--replot", action="store_true", help="redraw the PNG from the CSV")
    a = ap.parse_args()
    if a.replot:
        with open(a.out + ".csv") as f:
            rows = list(csv.DictReader(f))
    else:
        rows = measure(a.bench, a.min_time)
        write_csv(rows, a.out + ".csv")
        print(a.out + ".csv")
    plot(rows, a.out + ".png")


if __name__ == "__main__":
    main()
