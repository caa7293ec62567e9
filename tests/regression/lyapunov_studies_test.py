#!/usr/bin/python3
"""Lyapunov exponents in `vibro basin`, `attractors` and `sweep` (docs/studies.md, docs/output.md)
against independent truths, through the real binary:

- each periodic attractor of Fig. 5's basin: the exponents equal ln|μ_i| / (q·T) from the Floquet
  multipliers that `vibro orbit` finds (Newton started leaving the stop at the attractor's impact,
  --guess), within
  2e-3 per unit time and within their 95 % intervals; its 1-DOF sticking attractor is superstable
  (every exponent −∞, JSON null); none is called chaotic;
- the chaotic 2-DOF sticking response (as Fig. 16): the first not-periodic cell of a basin and every
  run of a sweep are chaotic (largest exponent positive beyond its interval), and a sweep's first
  run has to the bit the exponents of `vibro simulate` of the same scene and length;
- the same numbers in the HDF5 columns (/attractors, /sweep) as in the JSON and the text tables;
- run.lyapunov = false removes them (JSON keys absent, HDF5 NaN and chaotic −1).

usage: lyapunov_studies_test.py VIBRO SCENES_DIR
"""
import json
import math
import os
import subprocess
import sys
import tempfile
import tomllib

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

vibro, scenes = sys.argv[1], sys.argv[2]
fig5 = os.path.join(scenes, "fig05_coexistence.toml")
chaos = os.path.join(scenes, "chaotic", "chain2_sticking.toml")


def run(*args):
    p = subprocess.run([vibro, *args], capture_output=True, text=True, timeout=600)
    check(f"vibro {' '.join(args)}: exit 0", p.returncode == 0, p.stderr)
    return p


def run_json(*args):
    p = run(*args, "--json")
    return json.loads(p.stdout) if p.returncode == 0 else {}


def same(a, b):
    """Equal numbers, nulls as NaN or ±inf in HDF5."""
    return (a is None and not math.isfinite(b)) or (a is not None and a == b)


with tempfile.TemporaryDirectory() as d:
    # --- Fig. 5's three coexisting attractors against vibro orbit --------------------------------
    with open(fig5, "rb") as f:
        toml = tomllib.load(f)
    T, r = 2 * math.pi / toml["excitation"]["frequency"], toml["stop"]["restitution"]
    h5 = os.path.join(d, "basin.h5")
    basin = run_json("basin", fig5, "--grid", "12,12", "--set", "run.periods=1000", "--out", h5)
    kinds = sorted(a["kind"] for a in basin.get("attractors", []))
    check("Fig. 5: a sticking and two impact attractors", kinds == ["impact-periodic"] * 2 + ["sticking-periodic"],
          kinds)
    for k, a in enumerate(basin.get("attractors", [])):
        label = f"Fig. 5 attractor {k} ({a['kind']}, period {a['period']})"
        check(f"{label}: not chaotic", a.get("chaotic") is False, a)
        check(f"{label}: measured over the second half of run.periods", a.get("lyapunov_periods") == 500, a)
        if a["kind"] == "sticking-periodic":
            check(f"{label}: superstable (every exponent -inf)", a["lyapunov_exponents"] == [None, None], a)
            continue
        q = a["period"]
        # --guess: leaving the stop at the impact's phase with the velocity after it (−r·before).
        orbit = run_json("orbit", fig5, "--kind", "impact", "--period", str(q), "--guess",
                         f"{a['impact_phases'][0]},{-r * a['impact_velocities'][0]}")
        check(f"{label}: vibro orbit converges at its impact", orbit.get("status") == "converged", orbit)
        moduli = sorted((math.hypot(*m) for m in orbit.get("floquet_multipliers", [])), reverse=True)
        want = [math.log(m) / (q * T) for m in moduli]
        got = a["lyapunov_exponents"]
        check(f"{label}: one exponent per multiplier", len(got) == len(want), (got, want))
        for i, (g, w) in enumerate(zip(got, want)):
            lo, hi = a["lyapunov_ci"][i]
            check(f"{label}: exponent {i} = ln|mu|/(qT) = {w:.6f}", abs(g - w) <= 2e-3, (g, w))
            check(f"{label}: ln|mu|/(qT) within the 95 % interval of exponent {i}", lo - 1e-9 <= w <= hi + 1e-9,
                  (w, lo, hi))
    with h5py.File(h5, "r") as f:
        t = f["attractors"]
        for k, a in enumerate(basin.get("attractors", [])):
            check(f"HDF5 /attractors row {k}: lyapunov_max as the JSON",
                  same(a["lyapunov_exponents"][0], t["lyapunov_max"][k]), (a["lyapunov_exponents"], t["lyapunov_max"][k]))
            check(f"HDF5 /attractors row {k}: interval as the JSON",
                  same(a["lyapunov_ci"][0][0], t["lyapunov_max_ci_low"][k]) and
                  same(a["lyapunov_ci"][0][1], t["lyapunov_max_ci_high"][k]))
            check(f"HDF5 /attractors row {k}: chaotic 0", t["chaotic"][k] == 0, t["chaotic"][k])
        check("no unresolved cell: no unresolved exponents", "unresolved_lyapunov_max" not in t.attrs,
              dict(t.attrs))
    text = run("basin", fig5, "--grid", "12,12", "--set", "run.periods=1000").stdout
    check("basin text: a lyapunov line per attractor", text.count("  lyapunov     ") == 3, text)

    # --- The chaotic 2-DOF sticking response (as Fig. 16) ------------------------------------------
    h5 = os.path.join(d, "chaos_basin.h5")
    cb = run_json("basin", chaos, "--grid", "3,3", "--set", "run.periods=600", "--out", h5)
    u = cb.get("unresolved_lyapunov", {})
    check("chaotic basin: every cell unresolved", cb.get("unresolved_fraction") == 1.0, cb)
    check("chaotic basin: the first not-periodic cell is chaotic", u.get("chaotic") is True and
          u["lyapunov_ci"][0][0] > 0, u)
    check("chaotic basin: sticking collapses two directions", u.get("lyapunov_exponents", [0])[2:] == [None, None], u)
    with h5py.File(h5, "r") as f:
        a = f["attractors"].attrs
        check("chaotic basin: HDF5 unresolved_lyapunov_max and unresolved_chaotic",
              a.get("unresolved_lyapunov_max") == u.get("lyapunov_exponents", [None])[0] and
              a.get("unresolved_chaotic") == 1, dict(a))
    text = run("basin", chaos, "--grid", "3,3", "--set", "run.periods=600").stdout
    check("chaotic basin text: the unresolved cell's exponents, chaotic",
          "unresolved: the first not-periodic cell" in text and ": chaotic" in text, text)

    h5 = os.path.join(d, "sweep.h5")
    sweep = run_json("sweep", chaos, "--param", "excitation.frequency", "--from", "1.6", "--to", "1.601",
                     "--steps", "1", "--out", h5)
    points = sweep.get("points", [])
    check("chaotic sweep: 3 runs", len(points) == 3, points)
    check("chaotic sweep: every run chaotic", all(p.get("chaotic") is True for p in points),
          [p.get("lyapunov_exponents") for p in points])
    sim = run_json("simulate", chaos)  # run.periods = 2000 ≥ 4·max_period + 1: the sweep's first run
    check("chaotic sweep: the first run's exponents are simulate's, to the bit",
          points and points[0]["lyapunov_exponents"] == sim.get("lyapunov_exponents") and
          points[0]["lyapunov_ci"] == sim.get("lyapunov_ci"), (points[:1], sim.get("lyapunov_exponents")))
    with h5py.File(h5, "r") as f:
        s = f["sweep"]
        check("HDF5 /sweep lyapunov_max as the JSON",
              [float(x) for x in s["lyapunov_max"][()]] == [p["lyapunov_exponents"][0] for p in points])
        check("HDF5 /sweep chaotic", list(s["chaotic"][()]) == [1, 1, 1], s["chaotic"][()])
    text = run("sweep", chaos, "--param", "excitation.frequency", "--from", "1.6", "--to", "1.601",
               "--steps", "1").stdout
    rows = [line.split() for line in text.splitlines()[1:]]
    check("sweep text: lambda_1 and chaotic columns", text.split("\n")[0].split()[-2:] == ["lambda_1", "chaotic"] and
          all(r[-1] == "yes" and float(r[-2]) == float(f"{p['lyapunov_exponents'][0]:.4g}")
              for r, p in zip(rows, points)), text)

    # --- run.lyapunov = false ------------------------------------------------------------------------
    off = ["--set", "run.lyapunov=false"]
    h5 = os.path.join(d, "off.h5")
    b = run_json("basin", fig5, "--grid", "6,6", *off, "--out", h5)
    check("run.lyapunov=false: no exponents in basin's JSON",
          all("lyapunov_exponents" not in a and "chaotic" not in a for a in b.get("attractors", [])), b)
    with h5py.File(h5, "r") as f:
        check("run.lyapunov=false: HDF5 NaN and chaotic -1",
              np.isnan(f["attractors/lyapunov_max"][()]).all() and (f["attractors/chaotic"][()] == -1).all())
    s = run_json("sweep", chaos, "--param", "excitation.frequency", "--from", "1.6", "--to", "1.601", "--steps", "1",
                 "--one-way", *off)
    check("run.lyapunov=false: no exponents in sweep's JSON",
          all("lyapunov_exponents" not in p for p in s.get("points", [])), s)
    a = run_json("attractors", chaos, "--samples", "4", *off)
    check("run.lyapunov=false: no unresolved exponents", "unresolved_lyapunov" not in a, a)

finish()
