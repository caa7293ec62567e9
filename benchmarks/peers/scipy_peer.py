#!/usr/bin/python3
"""The scenes with SciPy's solve_ivp and events (Debian python3-scipy 1.10), against vibro.

The model is the modal system of problem.py (any number of modes and contacts). SciPy has no
impact, sticking or chattering treatment, so this is what an experienced user of a general ODE
solver writes:
  * flight: DOP853 with one terminal event per open contact (direction −1). After a contact's
    impact its event is the gap divided by (t − t_impact), after it leaves the stop at zero
    velocity by (t − t_leave)², after a release by (t − t_release)³: the known root at the restart
    is divided out, so it is not found again and the next root is not masked (at t = t_impact
    itself the event returns the positive limit's sign);
  * impact: the generalised Newton law on the contacts at zero gap (the held ones and the one
    that hits), an LCP solved exactly by enumeration (problem.py), the state put back on the
    stops; below |ġ⁻| = 1e-6 the impact is plastic (the threshold treatment of chattering, O(v));
    restitution 0: every impact is plastic;
  * a contact at rest (ġ = 0) sticks if the acceleration LCP gives it a positive force and is
    held while that force λ_j is positive (the constrained dynamics Ẍ = a + Σ T_j λ_j with
    W_SS λ_S = −C_S a), with one terminal event per held contact on λ_j (direction −1) = its
    release; max_step T/16 while something is held, so that a held flow without motion (one DOF)
    still samples λ;
  * atol = rtol·1e-2.

Standalone: benchmarks/peers/scipy_peer.py [--vibro build/vibro] [--scenes a.toml,b.toml]
(benchmarks/peers/run_all.py runs it beside vibro and Siconos and writes the table.)
"""
import argparse
import math
import os
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from problem import PeerResult, Problem, solve_lcp  # noqa: E402

REST = 1e-12  # |ġ| below which a contact at zero gap after an impact is at rest


def run(p, rtol, plastic_below=1e-6, max_impacts=500000, wall_limit=60.0):
    """One solve_ivp run of Problem p over its periods; returns a PeerResult."""
    res = PeerResult()
    w0 = time.time()
    n, m = p.n, p.m
    t = 0.0
    X, V = p.X0.copy(), p.V0.copy()
    held = []  # contacts held (sticking)
    start = [(0.0, 0)] * m  # per open contact: (t of its last event, zeros divided out)

    def gap_event(j):
        t_j, order = start[j]
        c, e = p.C[j], p.e[j]

        def ev(t, y):
            g = float(c @ y[:n]) - e
            if order == 0:
                return g
            return 1.0 if t == t_j else g / (t - t_j) ** order
        ev.terminal, ev.direction = True, -1
        return ev

    w2, D, TA, f, omega = p.w2, p.D, p.TA, p.f, p.omega

    def acc(t, y):  # the free acceleration (problem.py's acc_free, inlined)
        return -w2 * y[:n] - D * y[n:] + TA * (f * math.sin(omega * t))

    def reaction_event(k, R):
        r = R[k]

        def ev(t, y):
            return float(r @ acc(t, y))
        ev.terminal, ev.direction = True, -1
        return ev

    def settle(t, X, V, resting):
        """The acceleration LCP on the contacts at rest: those with λ > 0 are held, the others
        leave at zero velocity."""
        a = p.acc_free(t, X, V)
        lam = solve_lcp(p.W[np.ix_(resting, resting)], p.C[resting] @ a)
        now = [j for j, lj in zip(resting, lam) if lj > 0]
        for j in resting:
            if j not in now:
                start[j] = (t, 2)
        return now

    def update_held(t, new):
        for j in new:
            if j not in held:
                res.stick(t, j)
        for j in held:
            if j not in new:
                res.release(t, j)  # pushed off its stop
        return sorted(new)

    g0, v0 = p.gaps(X), p.C @ V
    resting = [j for j in range(m) if abs(g0[j]) <= 1e-12 * max(1.0, abs(p.e[j])) and abs(v0[j]) <= REST]
    if resting:
        X = p.onto_stops(X, resting)
        held = update_held(0.0, settle(0.0, X, V, resting))
    opts = dict(method="DOP853", rtol=rtol, atol=rtol * 1e-2)
    while t < p.t_end:
        if time.time() - w0 > wall_limit:
            res.status = f"gave up after {wall_limit:.0f} s ({res.impacts} impacts, t = {t:.6g})"
            break
        S = list(held)
        free = [j for j in range(m) if j not in S]
        # The held set's operators, factored once per segment: λ_S = R a, held acceleration a + P a.
        R, P = p.held_operators(S) if S else (None, None)
        events = [gap_event(j) for j in free] + [reaction_event(k, R) for k in range(len(S))]

        if S:
            def rhs(t, y):
                a = acc(t, y)
                return np.concatenate((y[n:], a + P @ a))
        else:
            def rhs(t, y):
                return np.concatenate((y[n:], acc(t, y)))
        extra = dict(max_step=p.T / 16) if S else {}
        sol = solve_ivp(rhs, (t, p.t_end), np.concatenate((X, V)), events=events, **opts, **extra)
        if sol.status == -1:
            res.status = "solver failure: " + sol.message
            break
        if sol.status == 0:  # reached t_end
            t = p.t_end
            X, V = sol.y[:n, -1], sol.y[n:, -1]
            res.end = (X.copy(), V.copy())
            break
        fired = [(float(te[0]), i) for i, te in enumerate(sol.t_events) if len(te)]
        t, i = min(fired)
        y = sol.y_events[i][0]
        X, V = y[:n].copy(), y[n:].copy()
        if i >= len(free):  # a held contact's force reached zero: it is released
            j = S[i - len(free)]
            res.release(t, j)
            held = [k for k in held if k != j]
            start[j] = (t, 3)
            if held:
                X = p.onto_stops(X, held)
            continue
        j = free[i]
        res.impacts += 1
        if res.impacts > max_impacts:
            res.status = f"stalled: {res.impacts} impacts, t = {t:.12g} (chattering not resolved)"
            break
        Z = S + [j]
        X = p.onto_stops(X, Z)
        v = p.C[Z] @ V
        r = np.array([p.r[k] for k in Z])
        if plastic_below and abs(v[-1]) < plastic_below:
            r[-1] = 0.0
        v[:-1] = np.minimum(v[:-1], 0.0)  # held contacts are at rest
        P = solve_lcp(p.W[np.ix_(Z, Z)], (1.0 + r) * v)
        V = V + p.Tc[Z].T @ P
        vz = p.C[Z] @ V
        resting = []
        for k, vk in zip(Z, vz):
            if vk > REST:
                start[k] = (t, 1)  # flies off: divide its gap by (t − t_impact)
            else:
                resting.append(k)
        if resting:
            V = V - p.Tc[resting].T @ np.linalg.solve(p.W[np.ix_(resting, resting)], p.C[resting] @ V)
            held = update_held(t, settle(t, X, V, resting))
        else:
            held = update_held(t, [])
    res.t_reached = t
    return res


def main():
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    from bench_common import DEFAULT_VIBRO, cpu_self, milestone_error, run_vibro  # noqa: PLC0415
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vibro", default=DEFAULT_VIBRO)
    ap.add_argument("--scenes", default="fig08_preload.toml,fig05_coexistence.toml,contacts_two_sided_1dof.toml")
    ap.add_argument("--periods", type=int, default=20)
    args = ap.parse_args()
    print(f"{'scene':34s} {'rtol':>7s} {'CPU [s]':>8s} {'error/T':>9s}  status")
    for scene in args.scenes.split(","):
        p = Problem.from_vibro(args.vibro, scene, periods=args.periods)
        ref = run_vibro(args.vibro, scene, p.periods, ['run.engine="exact"', "run.chatter_switch=1e-9"])
        for rtol in (1e-6, 1e-9, 1e-12):
            c0 = cpu_self()
            res = run(p, rtol, wall_limit=20.0)
            cpu = cpu_self() - c0
            err = milestone_error(res.times[:12], ref.milestones(12), p.T)
            print(f"{scene:34s} {rtol:7.0e} {cpu:8.3f} {err:9.1e}  {res.status}", flush=True)


if __name__ == "__main__":
    main()
