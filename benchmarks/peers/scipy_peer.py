#!/usr/bin/python3
"""The same 1-DOF scenes with SciPy's solve_ivp and events (Debian python3-scipy), against vibro.

The model is the paper's non-dimensional oscillator (MODEL §1.2): ẍ + x = f sin ωt while x > x0;
an impact (x = x0 moving in) reverses the velocity times r. SciPy has no sticking or chattering
treatment, so the script does what users of a general ODE solver do:
  * "restart": restart the integration after every impact (DOP853, terminal event, direction −1);
    below |v| = 1e-6 the impact is made plastic and the body rests until f sin ωt > x0 (the
    threshold treatment of the paper, O(v));
  * "naive": the same without the plastic switch: chattering is followed impact by impact.
For each rtol it reports the CPU time and the error of the first 12 stick and release times
against the exact engine of vibro (stick = accumulation point), and vibro's own times.

Usage: benchmarks/peers/scipy_peer.py [--vibro build/vibro]   (about a minute)
"""
import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np
from scipy.integrate import solve_ivp

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENES = [("Fig. 8", 0.75, 2.8, 1.2, 1.0), ("Fig. 5", 0.75, 10.0, 1.1, 1.0), ("Fig. 11", 0.0, 1.4, 10.0, -1.0)]
PERIODS = 20


def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def scipy_run(r, w, f, x0, rtol, plastic_below, max_events=200000, wall_limit=60.0):
    """Returns (milestones, status). Starts at rest on the stop (preload) or at the origin."""
    T = 2 * math.pi / w
    t_end = PERIODS * T
    rhs = lambda t, y: [y[1], -y[0] + f * math.sin(w * t)]  # noqa: E731

    def hit(t, y):
        return y[0] - x0
    hit.terminal, hit.direction = True, -1
    t = 0.0
    stuck = x0 > 0
    y = [x0, 0.0] if stuck else [0.0, 0.0]
    milestones = [0.0] if stuck else []
    events, start = 0, time.time()
    while t < t_end:
        if time.time() - start > wall_limit:
            return milestones, f"gave up after {wall_limit:.0f} s ({events} impacts, t = {t:.6g})"
        if stuck:
            # Rest until f sin ωt rises through x0 (R = x0 − f sin ωt crosses zero going down).
            if abs(x0) >= f:
                return milestones, "permanent contact"
            phi = math.asin(x0 / f)
            k = math.floor((w * t - phi) / (2 * math.pi)) + 1
            t_rel = (phi + 2 * math.pi * k) / w
            if t_rel <= t:
                t_rel += T
            if t_rel >= t_end:
                break
            t, y, stuck = t_rel, [x0, 0.0], False
            milestones.append(t)
            continue
        # Step off the surface a little so that the event at the start is not found again.
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=rtol, atol=rtol * 1e-2, events=hit)
        if sol.status == -1:
            return milestones, "solver failure: " + sol.message
        if sol.status == 0:
            break
        t = float(sol.t_events[0][0])
        v = float(sol.y_events[0][0][1])
        events += 1
        if events > max_events:
            return milestones, f"stalled: {events} impacts and t = {t:.12g} (chattering not resolved)"
        if plastic_below and abs(v) < plastic_below and x0 > f * math.sin(w * t):
            stuck = True
            milestones.append(t)
            continue
        if r == 0.0:
            if x0 > f * math.sin(w * t):
                stuck = True
                milestones.append(t)
                continue
            y = [x0 + 1e-15, 0.0]
            continue
        # Restart just off the surface with the rebound velocity (x snapped to the stop).
        y = [x0, -r * v]
        t = t + 1e-14 * max(1.0, t)
    return milestones, "ok"


def vibro_run(vibro, name, r, w, f, x0):
    with tempfile.TemporaryDirectory() as d:
        h5 = os.path.join(d, "run.h5")
        cmd = [vibro, "simulate", os.path.join(ROOT, "data", "scenes", "fig08_preload.toml"),
               "--out", h5, "--json", "--set", f"stop.restitution={r}", "--set", f"excitation.frequency={w}",
               "--set", f"excitation.amplitude={f}", "--set", f"stop.position={x0}",
               "--set", f"run.periods={PERIODS}", "--set", "run.samples_per_period=0"]
        t0 = time.time()
        subprocess.run(cmd, check=True, capture_output=True)
        wall = time.time() - t0
        with h5py.File(h5) as fh:
            k, t = fh["events/kind"][:], fh["events/t"][:]
    return [x for x, kk in zip(t, k) if kk in (3, 4)], wall


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--vibro", default=os.path.join(ROOT, "build", "vibro"))
    args = ap.parse_args()
    print(f"{'scene':8s} {'method':10s} {'rtol':>7s} {'time [s]':>9s} {'error/T':>9s}  status")
    for name, r, w, f, x0 in SCENES:
        T = 2 * math.pi / w
        ref, vt = vibro_run(args.vibro, name, r, w, f, x0)
        print(f"{name:8s} {'vibro':10s} {'exact':>7s} {vt:9.3f} {0.0:9.1e}  ok (wall time, process start-up included)")
        for method, plastic in (("restart", 1e-6), ("naive", 0.0)):
            for rtol in (1e-6, 1e-9, 1e-12):
                c0 = cpu()
                ms, status = scipy_run(r, w, f, x0, rtol, plastic)
                dt = cpu() - c0
                n = min(len(ms), len(ref), 12)
                err = max((abs(a - b) for a, b in zip(ms[:n], ref[:n])), default=float("nan")) / T
                print(f"{name:8s} {method:10s} {rtol:7.0e} {dt:9.3f} {err:9.1e}  {status}", flush=True)
                if method == "naive" and status != "ok":
                    break


if __name__ == "__main__":
    main()
