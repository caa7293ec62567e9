#!/usr/bin/python3
"""The scenes with SciPy's solve_ivp and events (Debian python3-scipy 1.10), against vibro.

The model is the modal system of problem.py (any number of modes, from `vibro model --json`).
SciPy has no impact, sticking or chattering treatment, so the script does what users of a general
ODE solver do:
  * free flight: DOP853 with a terminal event on the gap x_B − x0 (direction −1);
  * impact: the restitution law, x_B snapped back onto the stop, and a restart 1e-14 (relative)
    later so that the event at the start is not found again;
  * "restart": below |ẋ_B⁻| = 1e-6 the impact is made plastic (the threshold treatment of the
    paper, O(v)); r = 0: every impact is plastic;
  * plastic impact: the impulsive projection; stick if R > 0, else leave at zero velocity;
  * sticking: the constrained dynamics Ẍ = a − T_B(1ᵀa)/s_B (a = free acceleration) with a
    terminal event on the reaction R (direction −1) = release (max_step T/16 so that a 1-DOF
    sticking phase, whose state does not move, still samples R);
  * "naive": the same without the plastic switch: chattering is followed impact by impact.

Standalone: benchmarks/peers/scipy_peer.py [--vibro build/vibro] [--scenes a.toml,b.toml]
(benchmarks/peers/run_all.py runs it beside vibro and Siconos and writes the table.)
"""
import argparse
import os
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from bench_common import DEFAULT_VIBRO, cpu_self, milestone_error, run_vibro  # noqa: E402
from problem import PeerResult, Problem  # noqa: E402


def run(p, rtol, plastic_below=1e-6, max_impacts=200000, wall_limit=60.0):
    """One solve_ivp run of Problem p over its periods; returns a PeerResult."""
    res = PeerResult()
    c0, w0 = cpu_self(), time.time()
    n = p.n

    def free(t, y):
        return np.concatenate((y[n:], p.acc_free(t, y[:n], y[n:])))

    def stuck(t, y):
        return np.concatenate((y[n:], p.acc_stuck(t, y[:n], y[n:])))

    def hit(t, y):
        return y[:n].sum() - p.x0
    hit.terminal, hit.direction = True, -1

    def release(t, y):
        return p.reaction(t, y[:n], y[n:])
    release.terminal, release.direction = True, -1

    t = 0.0
    X, V = p.X0.copy(), p.V0.copy()
    is_stuck = p.x0 > 0 and p.reaction(0.0, X, V) > 0
    if is_stuck:
        res.stick(0.0)
    opts = dict(method="DOP853", rtol=rtol, atol=rtol * 1e-2)
    while t < p.t_end:
        if time.time() - w0 > wall_limit:
            res.status = f"gave up after {wall_limit:.0f} s ({res.impacts} impacts, t = {t:.6g})"
            break
        y = np.concatenate((X, V))
        if is_stuck:
            sol = solve_ivp(stuck, (t, p.t_end), y, events=release, max_step=p.T / 16, **opts)
        else:
            sol = solve_ivp(free, (t, p.t_end), y, events=hit, **opts)
        if sol.status == -1:
            res.status = "solver failure: " + sol.message
            break
        if sol.status == 0:  # reached t_end
            t = p.t_end
            X, V = sol.y[:n, -1], sol.y[n:, -1]
            res.end = (X.copy(), V.copy())
            break
        t = float(sol.t_events[0][0])
        ye = sol.y_events[0][0]
        X, V = ye[:n].copy(), ye[n:].copy()
        if is_stuck:  # release: R crossed zero going down
            res.release(t)
            is_stuck = False
            continue
        res.impacts += 1
        if res.impacts > max_impacts:
            res.status = f"stalled: {res.impacts} impacts, t = {t:.12g} (chattering not resolved)"
            break
        v = V.sum()
        X = p.onto_stop(X)
        if p.r == 0.0 or (plastic_below and abs(v) < plastic_below):
            V = p.impact(V, 0.0)
            if p.reaction(t, X, V) > 0:
                is_stuck = True
                res.stick(t)
            else:
                X = X + p.TB * (1e-15 / p.sB)  # leave at zero velocity, just off the stop
            continue
        V = p.impact(V, p.r)
        t = t + 1e-14 * max(1.0, t)
    res.t_reached = t
    res.cpu = cpu_self() - c0
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vibro", default=DEFAULT_VIBRO)
    ap.add_argument("--scenes", default="fig08_preload.toml,fig05_coexistence.toml,fig11_clearance.toml")
    ap.add_argument("--periods", type=int, default=20)
    args = ap.parse_args()
    print(f"{'scene':24s} {'method':8s} {'rtol':>7s} {'CPU [s]':>8s} {'error/T':>9s}  status")
    for scene in args.scenes.split(","):
        p = Problem(args.vibro, scene, periods=args.periods)
        ref = run_vibro(args.vibro, scene, p.periods, ['run.engine="exact"', "run.chatter_switch=1e-9"])
        print(f"{scene:24s} {'vibro':8s} {'exact':>7s} {ref.cpu:8.3f} {0.0:9.1e}  (whole process)")
        for method, plastic in (("restart", 1e-6), ("naive", 0.0)):
            if method == "naive" and p.r == 0.0:
                continue
            for rtol in (1e-6, 1e-9, 1e-12):
                res = run(p, rtol, plastic, wall_limit=20.0)
                err = milestone_error(res.times[:12], ref.milestones(12), p.T)
                print(f"{scene:24s} {method:8s} {rtol:7.0e} {res.cpu:8.3f} {err:9.1e}  {res.status}", flush=True)
                if method == "naive" and res.status != "ok":
                    break


if __name__ == "__main__":
    main()
