#!/usr/bin/python3
"""The 1-DOF scenes with Siconos (Debian python3-siconos 4.4): Moreau–Jean time-stepping.

Model: ẍ + x = f sin ωt, y = x − x0 ≥ 0, Newton impact law with restitution r (the paper's
non-dimensional oscillator, MODEL §1.2). Time-stepping has no events: the sticking fraction is
measured as the fraction of the steps of the last 5 periods with a positive contact impulse
(λ of the LCP), and compared with vibro's exact engine. The external
force is a Python override of computeFExt (SWIG director).

Usage: benchmarks/peers/siconos_peer.py [--vibro build/vibro]   (about a minute)
"""
import argparse
import json
import math
import os
import resource
import subprocess

import numpy as np
import siconos.kernel as sk

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENES = [("Fig. 8", 0.75, 2.8, 1.2, 1.0), ("Fig. 5", 0.75, 10.0, 1.1, 1.0), ("Fig. 11", 0.0, 1.4, 10.0, -1.0)]
PERIODS = 20


def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def moreau_jean(r, w, f, x0, steps_per_period):
    class Forced(sk.LagrangianLinearTIDS):
        def computeFExt(self, time, fExt=None):
            value = f * math.sin(w * time)
            if fExt is not None:
                fExt[0] = value
            else:
                self.fExt()[0] = value

    start = np.array([x0 if x0 > 0 else 0.0])
    ds = Forced(start, np.array([0.0]), np.eye(1), np.eye(1), np.zeros((1, 1)))
    ds.setFExtPtr(np.zeros(1))
    inter = sk.Interaction(sk.NewtonImpactNSL(r), sk.LagrangianLinearTIR(np.eye(1), np.array([-x0])))
    T = 2 * math.pi / w
    nsds = sk.NonSmoothDynamicalSystem(0.0, PERIODS * T)
    nsds.insertDynamicalSystem(ds)
    nsds.link(inter, ds)
    s = sk.TimeStepping(nsds, sk.TimeDiscretisation(0.0, T / steps_per_period), sk.MoreauJeanOSI(0.5),
                        sk.LCP())
    on, total = 0, 0
    t_last = (PERIODS - 5) * T
    while s.hasNextEvent():
        s.computeOneStep()
        t = s.nextTime()
        if t > t_last:
            total += 1
            if inter.lambda_(1)[0] > 0:  # the contact impulse of the step: on the stop
                on += 1
        s.nextStep()
    return on / max(total, 1)


def vibro_sp(vibro, r, w, f, x0):
    out = subprocess.run([vibro, "simulate", os.path.join(ROOT, "data", "scenes", "fig08_preload.toml"),
                          "--json", "--set", f"stop.restitution={r}", "--set", f"excitation.frequency={w}",
                          "--set", f"excitation.amplitude={f}", "--set", f"stop.position={x0}",
                          "--set", f"run.periods={PERIODS}", "--set", "run.samples_per_period=0"],
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout)["attractor"]["sticking_fraction"]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--vibro", default=os.path.join(ROOT, "build", "vibro"))
    args = ap.parse_args()
    print(f"{'scene':8s} {'steps/T':>8s} {'CPU [s]':>8s} {'SP':>10s} {'SP error':>9s}")
    for name, r, w, f, x0 in SCENES:
        ref = vibro_sp(args.vibro, r, w, f, x0)
        print(f"{name:8s} {'vibro':>8s} {'':>8s} {ref:10.6f} {'exact':>9s}")
        for n in (100, 1000, 10000):
            c0 = cpu()
            sp = moreau_jean(r, w, f, x0, n)
            print(f"{name:8s} {n:8d} {cpu() - c0:8.2f} {sp:10.6f} {abs(sp - ref):9.1e}", flush=True)


if __name__ == "__main__":
    main()
