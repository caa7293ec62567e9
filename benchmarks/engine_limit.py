#!/usr/bin/python3
"""The exact engine against its sincos limit, measured in one run (docs/performance.md).

    benchmarks/engine_limit.py [--bench build/benchmarks/vibro_bench] [--rounds 5] [--min-time 1]
                               [--quick]

Runs, in one `vibro_bench` process, with Google Benchmark's random interleaving of the rounds:
  BM_Events1Dof    Fig. 8, 200 periods: events per CPU second, probes per event, CPU per probe
  BM_Limit_Sincos  six sincos per "event": the limit of one DOF (three probes of two sincos)
  BM_Fig8GapProbe  one certified probe of Fig. 8's gap, alone
and prints, round by round and as medians, the engine's events/s, the limit's, their ratio
(the goal is ≥ 0.25), the probes per event and the cost of a probe in sincos.
--quick: one short round, to check that the benchmarks run and report what this reads (the test
suite's check, `bench.engine_limit`); exit 1 when a counter is missing or not positive.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NAMES = ("BM_Events1Dof", "BM_Limit_Sincos", "BM_Fig8GapProbe")
COUNTERS = {"BM_Events1Dof": ("events/s", "probes/event", "s/probe"),
            "BM_Limit_Sincos": ("events/s", "s/sincos"),
            "BM_Fig8GapProbe": ("s/probe",)}


def run(bench, rounds, min_time):
    cmd = [bench, "--benchmark_filter=^(" + "|".join(NAMES) + ")$",
           f"--benchmark_repetitions={rounds}", "--benchmark_enable_random_interleaving=true",
           f"--benchmark_min_time={min_time}", "--benchmark_format=json"]
    out = subprocess.run(cmd, check=True, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    rows = {n: [] for n in NAMES}
    for b in json.loads(out.stdout)["benchmarks"]:
        if b.get("run_type") != "iteration":
            continue
        name = b["run_name"] if "run_name" in b else b["name"]
        if name in rows:
            rows[name].append(b)
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bench", default=os.path.join(ROOT, "build", "benchmarks", "vibro_bench"))
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--min-time", type=float, default=1.0)
    p.add_argument("--quick", action="store_true")
    a = p.parse_args()
    if a.quick:
        a.rounds, a.min_time = 1, 0.01
    rows = run(a.bench, a.rounds, a.min_time)
    bad = [f"{n}: {c}" for n in NAMES for c in COUNTERS[n]
           if len(rows[n]) != a.rounds or not all(r.get(c, 0) > 0 for r in rows[n])]
    if bad:
        print("engine_limit.py: missing or non-positive counters: " + ", ".join(bad), file=sys.stderr)
        return 1
    ev = [r["events/s"] for r in rows["BM_Events1Dof"]]
    lim = [r["events/s"] for r in rows["BM_Limit_Sincos"]]
    ppe = [r["probes/event"] for r in rows["BM_Events1Dof"]]
    run_probe = [r["s/probe"] for r in rows["BM_Events1Dof"]]
    probe = [r["s/probe"] for r in rows["BM_Fig8GapProbe"]]
    sc = [r["s/sincos"] for r in rows["BM_Limit_Sincos"]]
    ratio = [e / l for e, l in zip(ev, lim)]
    med = statistics.median

    def per(xs, fmt):
        return " / ".join(fmt.format(x) for x in xs)

    print(f"rounds: {a.rounds} (random interleaving, --benchmark_min_time={a.min_time}), CPU time")
    print(f"Fig. 8 events/s             {med(ev) / 1e6:.3f} M   ({per([x / 1e6 for x in ev], '{:.3f}')})")
    print(f"sincos limit events/s       {med(lim) / 1e6:.3f} M   ({per([x / 1e6 for x in lim], '{:.3f}')})")
    print(f"engine / limit              {med(ratio):.3f}     ({per(ratio, '{:.3f}')})  goal >= 0.25")
    print(f"probes per event            {med(ppe):.2f}")
    print(f"sincos                      {med(sc) * 1e9:.1f} ns")
    print(f"one probe alone             {med(probe) * 1e9:.1f} ns = {med([p / s for p, s in zip(probe, sc)]):.2f} sincos")
    print(f"run CPU per probe           {med(run_probe) * 1e9:.1f} ns = {med([p / s for p, s in zip(run_probe, sc)]):.2f} sincos")
    print(f"probes' share of the run    {med([pp * p * e for pp, p, e in zip(ppe, probe, ev)]):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
