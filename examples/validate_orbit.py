#!/usr/bin/python3
"""Validate a periodic orbit three ways: solve it with the Poincaré solver (vibro.orbit),
simulate the scene until it settles (vibro.simulate), and compare both with the paper's closed
form for a plastic stop (r = 0, MODEL §6.1–6.2): release at sin ωt'1 = 1/f, free flight landing
at t'0, and sticking fraction SP = 1 − ω(t'0 − t'1)/(2π q). Exits 1 when they disagree.

    examples/validate_orbit.py [--amplitude 1.2]
"""
import argparse
import math
import os
import sys


import vibro

here = os.path.dirname(os.path.abspath(__file__))
p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
p.add_argument("--amplitude", type=float, default=1.2, help="forcing amplitude f > 1 (default 1.2)")
p.add_argument("--scene", default=os.path.join(here, "..", "data", "scenes", "fig08_preload.toml"))
args = p.parse_args()
f, w = args.amplitude, 2.8

scene = vibro.load_scene(args.scene, set={"stop.restitution": 0.0, "excitation.amplitude": f,
                                          "excitation.frequency": w, "run.periods": 100})
solved = vibro.orbit(scene)
run = vibro.simulate(scene)

# Closed form (ω_1 = x0 = T_A = 1): release phase φ1 with sin φ1 = 1/f, cos φ1 > 0; the flight
# x(t) of eq. (33) lands at the first s = t − t'1 > 0 where x = 1; it sticks there when the
# reaction is positive, f sin ωt'0 < 1.
phi1 = math.asin(1 / f)
c = math.sqrt(f * f - 1) / f


def gap(s):
    t = phi1 / w + s
    return (f * math.sin(w * t) - w * w * math.cos(s) - w * f * c * math.sin(s)) / (1 - w * w) - 1


s, ds = 1e-3, 1e-3
while gap(s) > 0:
    s += ds
lo, hi = s - ds, s
for _ in range(200):  # bisection to machine precision
    mid = 0.5 * (lo + hi)
    lo, hi = (mid, hi) if gap(mid) > 0 else (lo, mid)
flight = 0.5 * (lo + hi)
if not f * math.sin(w * (phi1 / w + flight)) < 1:
    sys.exit(f"f = {f}: the flight does not end in sticking (R(t'0) < 0): no one-flight sticking orbit")
q = math.ceil(w * flight / (2 * math.pi))
sp_exact = 1 - w * flight / (2 * math.pi * q)

rows = [("sticking fraction", sp_exact, solved["sticking_fraction"], run.summary["attractor"]["sticking_fraction"]),
        ("release phase", phi1 % (2 * math.pi), solved["stick_phases"][0][1] % (2 * math.pi),
         run.summary["attractor"]["stick_phases"][0][1] % (2 * math.pi))]
print(f"f = {f}, ω = {w}, r = 0: period {q}; orbit solver: {solved['status']} "
      f"({solved['newton_iterations']} Newton iterations)")
print(f"{'':<20} {'closed form':>20} {'vibro.orbit':>20} {'vibro.simulate':>20}")
worst = 0.0
for name, exact, orb, sim in rows:
    print(f"{name:<20} {exact:>20.15f} {orb:>20.15f} {sim:>20.15f}")
    worst = max(worst, abs(orb - exact), abs(sim - exact))
print(f"largest difference {worst:.2e}")
sys.exit(0 if solved["status"] == "converged" and solved["period"] == q and worst < 1e-9 else 1)
