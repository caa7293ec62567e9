#!/usr/bin/python3
"""Makes data/benchmarks/: reference problems for other simulators' chattering treatments
(docs/validation.md), each with its scene, its reference events (CSV with 17 significant
digits, and the vibro HDF5 run they come from) and a manifest.

    scripts/make_benchmarks.py [--vibro build/vibro] [--out data/benchmarks]

The events come from the exact (closed-form) engine in quad precision (113 bits, chattering
tails predicted to 1e-28 T; docs/chattering.md), damped sticking of two or more modes included
(docs/engines.md). Each problem is then
run with the default double engine and scored against its reference (`vibro score`): the
manifest records the reference and that error. `reference_run` takes the engine settings as an
argument, so the same problems can be rerun with another engine and compared:
    reference_run(vibro, problem, out_dir, {"run.engine": '"exact"'})
"""
import json
import argparse
import csv
import os
import subprocess
import sys

import h5py

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "data", "scenes")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from events_to_csv import rows as event_rows, write as write_events  # noqa: E402

# The reference engine: vibro's exact engine (closed-form flights, roots to the last bit) in quad
# precision.
QUAD = {"run.engine": '"exact"', "run.chatter": '"accumulation"', "run.precision": '"quad"'}

# name, scene, overrides, DOF, what it exercises.
PROBLEMS = [
    ("chatter_1dof", "fig08_preload.toml", ["run.periods=20"], 1,
     "chattering into sticking every period (Fig. 8, r = 0.75, preload)"),
    ("chatter_fast_1dof", "fig05_coexistence.toml", ["run.periods=20"], 1,
     "chattering into sticking at ω = 10 (Fig. 5, from rest on the stop)"),
    # A problem that changes the scene's values gets a title that says them (docs_test.py checks
    # every title's r, omega and f against the keys).
    ("r_near_one_1dof", "fig05_coexistence.toml",
     ["stop.restitution=0.9", "run.periods=20", 'title="Fig. 5 forcing with r = 0.9 (near one), omega = 10, f = 1.1"'], 1,
     "r → 1: long chattering sequences into sticking (r = 0.9, 134 impacts each)"),
    ("grazing_near_1dof", "fig08_preload.toml",
     ["stop.position=-1.0", "stop.restitution=0.8", "excitation.frequency=0.5",
      "excitation.amplitude=0.750075", "initial.time=0.0", "initial.displacement=[0.0]",
      "initial.velocity=[0.50005]", "run.periods=20",
      'title="1-DOF clearance near grazing, r = 0.8, omega = 0.5, f = 0.750075"'], 1,
     "near grazing: the forced response 1 + 1e-4 times the clearance, first contacts at small speed"),
    ("clearance_plastic_1dof", "fig11_clearance.toml", ["run.periods=20"], 1,
     "clearance x0 = −1 with a plastic stop (Fig. 11, r = 0)"),
    ("two_flights_1dof", "fig10_two_flights.toml", ["run.periods=20"], 1,
     "two free flights per period, plastic stop (Fig. 10)"),
    ("chain_2dof", "chain2.toml", ["run.periods=20"], 2,
     "2-DOF chain: mass 2 sticks while mass 1 keeps oscillating"),
    ("chain_damped_2dof", "chain2_damped.toml", ["run.periods=20"], 2,
     "2-DOF chain with modal damping"),
    ("chain_3dof", "chain3.toml", ["run.periods=20"], 3, "3-DOF chain"),
    # The undamped stiff chain is sensitive to its initial state (its stiff modes ring through
    # every sticking phase; near-grazing contacts amplify differences): double and quad agree to
    # 1e-11 T over its first forcing period (T = 31.4) and part by 1e-3 T within the second. One
    # period keeps the reference reproducible.
    ("chain_stiff_10dof", "chain10_stiff.toml", ["run.periods=1"], 10,
     "10-DOF stiff chain (modal frequencies from 0.32 to 198), its first period"),
]


def reference_run(vibro, problem, out_dir, engine):
    """Runs one problem with the engine settings `engine` ({scene key: TOML value}) and writes
    NAME.h5 (the vibro run), NAME.csv (its events) and NAME.toml (the scene as run). Returns the
    number of events."""
    name, scene, sets, _, _ = problem
    h5 = os.path.join(out_dir, name + ".h5")
    args = [vibro, "simulate", os.path.join(SCENES, scene), "--out", h5, "--set", "run.samples_per_period=0"]
    for s in sets + [f"{k}={v}" for k, v in engine.items()]:
        args += ["--set", s]
    p = subprocess.run(args, capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"{name}: vibro simulate failed: {p.stderr}")
    events = event_rows(h5)
    with open(os.path.join(out_dir, name + ".csv"), "w") as f:
        write_events(events, f)
    with h5py.File(h5, "r") as f:
        scene_text = f.attrs["scene"]
        scene_text = scene_text.decode() if isinstance(scene_text, bytes) else scene_text
    with open(os.path.join(out_dir, name + ".toml"), "w") as f:
        f.write(f"# Benchmark {name}, made by scripts/make_benchmarks.py: the scene as run (the\n"
                f"# reference events come from run.precision = {engine.get('run.precision', 'double')}).\n")
        # The arithmetic of the reference is not part of the problem.
        f.write("".join(l for l in scene_text.splitlines(True) if not l.startswith("precision =")))
    return len(events)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--vibro", default=os.path.join(ROOT, "build", "vibro"))
    ap.add_argument("--out", default=os.path.join(ROOT, "data", "benchmarks"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    manifest = []
    for prob in PROBLEMS:
        reference = "quad"
        n = reference_run(a.vibro, prob, a.out, QUAD)
        # The default double engine scored against the reference.
        p = subprocess.run([a.vibro, "score", os.path.join(a.out, prob[0] + ".toml"),
                            os.path.join(a.out, prob[0] + ".csv"), "--json"],
                           capture_output=True, text=True)
        if p.returncode not in (0, 4):
            raise RuntimeError(f"{prob[0]}: vibro score failed: {p.stderr}")
        err = json.loads(p.stdout)["max_time_error"]
        manifest.append({"name": prob[0], "scene": prob[0] + ".toml", "events": prob[0] + ".csv",
                         "run": prob[0] + ".h5", "dof": prob[3], "count": n, "reference": reference,
                         "double_error": f"{err:.2g}", "exercises": prob[4]})
        print(f"{prob[0]:<24} {prob[3]:>3} DOF {n:>7} events, reference {reference}, "
              f"double engine within {err:.2g} T", file=sys.stderr)
    with open(os.path.join(a.out, "manifest.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(manifest[0].keys()), lineterminator="\n")
        w.writeheader()
        w.writerows(manifest)


if __name__ == "__main__":
    main()
