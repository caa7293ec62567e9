#!/usr/bin/python3
"""Lyapunov exponents of `vibro simulate` against an independent truth (docs/model.md §5.8).

The largest exponent of the chaotic 2-DOF sticking response (data/scenes/chaotic/chain2_sticking.toml,
as the paper's Fig. 16) is compared with the growth rate of the distance between two runs of the
113-bit reference engine started 1e-20 apart, which shares nothing with the tangent map: no
Jacobian, no saltation matrix, no QR. Eight pairs start from points of the attractor (section
points of a long double run, in an equivalent modal scene so that a modal velocity can be set
to 0 and to 1e-20 exactly); each pair's rate is the slope of ln(distance) over the section points
where the distance lies between 1e-12 and 1e-4 (resolved in double, still infinitesimal). The
mean rate must lie within 25 % of the exponent, and the exponent must be positive beyond its
95 % interval. Also: `run.lyapunov = false` removes the exponents, and the text summary says
"chaotic" only for that scene.

usage: lyapunov_test.py VIBRO SCENES_DIR
"""
import json
import math
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

vibro, scenes = sys.argv[1], sys.argv[2]
failures = []


def check(name, ok, detail=""):
    print(("ok    " if ok else "FAIL  ") + name + ("" if ok else f": {detail}"))
    if not ok:
        failures.append(name)


def run(*args):
    p = subprocess.run([vibro, *args], capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        raise SystemExit(f"vibro {' '.join(args)} failed ({p.returncode}): {p.stderr}")
    return p


physical = os.path.join(scenes, "chaotic", "chain2_sticking.toml")
work = tempfile.mkdtemp(prefix="vibro_lyapunov_")
model = json.loads(run("model", physical, "--json").stdout)
modal = os.path.join(work, "modal.toml")
with open(modal, "w") as f:
    f.write(f"[structure]\nfrequencies = {model['frequencies']!r}\nforcing = {model['forcing']!r}\n"
            f"contact = {model['contact']!r}\n[stop]\nposition = 1.0\nrestitution = 0.5\n"
            "[excitation]\namplitude = 0.6\nfrequency = 1.6\n")

ref_out = os.path.join(work, "ref.h5")
ref = json.loads(run("simulate", modal, "--set", "run.periods=6000", "--set", "run.samples_per_period=0",
                     "--out", ref_out, "--json").stdout)
lam, (lo, hi) = ref["lyapunov_exponents"][0], ref["lyapunov_ci"][0]
check("the largest exponent is positive beyond its 95 % interval", ref["chaotic"] and lo > 0, (lam, lo, hi))
check("sticking collapses two directions (null = -inf)", ref["lyapunov_exponents"][2:] == [None, None],
      ref["lyapunov_exponents"])
check("the run sticks", ref["counts"]["sticks"] > 100, ref["counts"])

with h5py.File(ref_out) as f:
    X, V, t, mode = f["section/X"][:], f["section/V"][:], f["section/t"][:], f["section/mode"][:]

rates = []
for k in range(1000, 6000, 500):
    if mode[k] != 0 or len(rates) == 8:
        continue
    sections = []
    for v0 in (0.0, 1e-20):
        out = os.path.join(work, f"q{k}_{v0}.h5")
        run("simulate", modal, "--set", 'run.precision="quad"', "--set", "run.periods=150", "--set",
            "run.samples_per_period=0", "--set", "run.lyapunov=false", "--set", f"initial.time={t[k]!r}",
            "--set", f"initial.displacement=[{X[k][0]!r}, {X[k][1]!r}]",
            "--set", f"initial.velocity=[{v0!r}, {V[k][1]!r}]", "--out", out)
        with h5py.File(out) as f:
            sections.append((f["section/t"][:], np.hstack([f["section/X"][:], f["section/V"][:]])))
    (ta, za), (_, zb) = sections
    n = min(len(za), len(zb))
    dist = np.abs(za[:n] - zb[:n]).max(axis=1) / (1 + np.abs(za[:n]).max(axis=1))
    idx = np.nonzero((dist > 1e-12) & (dist < 1e-4))[0]
    if len(idx) < 10:
        check(f"pair from section {k} separates", False, f"only {len(idx)} points in range")
        continue
    i0, i1 = idx[0], idx[-1]
    rates.append(np.polyfit(ta[i0:i1 + 1], np.log(dist[i0:i1 + 1]), 1)[0])

mean = float(np.mean(rates)) if rates else float("nan")
print(f"lambda_1 = {lam:.5g} [{lo:.5g}, {hi:.5g}]; quad divergence rates {np.round(rates, 4).tolist()}, mean {mean:.5g}")
check("eight quad pairs measured", len(rates) == 8, len(rates))
check("the mean quad divergence rate is within 25 % of the largest exponent", abs(mean - lam) <= 0.25 * lam,
      (mean, lam))

off = json.loads(run("simulate", physical, "--set", "run.lyapunov=false", "--set", "run.periods=20", "--json").stdout)
check("run.lyapunov = false measures nothing", "lyapunov_exponents" not in off and "chaotic" not in off, off)
text = run("simulate", physical, "--set", "run.periods=400").stdout
check("the text summary says chaotic", "lyapunov" in text and text.rstrip().endswith("chaotic"), text[-300:])
text = run("simulate", os.path.join(scenes, "fig08_preload.toml")).stdout
check("a 1-DOF sticking orbit: every exponent -inf, not chaotic",
      "lyapunov     -inf, -inf" in text and "chaotic" not in text, text[-300:])
p = subprocess.run([vibro, "simulate", physical, "--set", "run.lyapunov=1"], capture_output=True, text=True)
check("run.lyapunov = 1 is refused (a boolean)", p.returncode == 2 and "run.lyapunov" in p.stderr, p.stderr)

print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
