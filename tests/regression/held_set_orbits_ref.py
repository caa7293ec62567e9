#!/usr/bin/env python3
"""Return maps and their Jacobians from the independent mpmath reference (tests/reference/contacts/
reference.py): the state z = (q, q̇) at time t0 is flown one map period (q forcing periods) by the
event-driven 60-digit-capable simulator, and the Jacobian is taken by central differences.

Used by held_set_orbits_test.py; run alone it prints a scene's fixed point and multipliers:
    held_set_orbits_ref.py SCENE.toml T0 Q q1,q2,... v1,v2,... [--held j,k] [--dps 40]
"""
import os
import sys

import mpmath as mp

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "reference", "contacts"))
import reference as ref  # noqa: E402


def flow(text, t0, q, v, periods):
    """(q, q̇) after `periods` forcing periods from (t0, q, v), and the events on the way."""
    sc = ref.Scene("map", text=text)
    sc.t0, sc.q0, sc.v0 = mp.mpf(t0), [mp.mpf(x) for x in q], [mp.mpf(x) for x in v]
    sim = ref.Simulation(sc)
    m = sim.model
    t = sc.t0
    t_end = t + periods * m.T
    # as Simulation.run, keeping the final state
    eta, etad = sim.initial_state()
    sim.vscale = 1 + max(abs(x) for x in etad + [mp.mpf(1)])
    orders, S, Z0 = {}, set(), []
    for j in range(m.m):
        g, gv = m.gap(j, eta), m.gapvel(j, etad)
        if abs(g) <= sim.gtol():
            if gv > sim.vtol():
                orders[j] = 1
            else:
                Z0.append(j)
    if Z0:
        S, orders, eta, etad = sim.enter(t, Z0, set(), orders, eta, etad)
    while t < t_end:
        t, eta, etad, S, orders = sim.step(t, t_end, eta, etad, S, orders)
    Phi = m.Phi
    n = m.n
    qq = [mp.fsum(Phi[i][k] * eta[k] for k in range(n)) for i in range(n)]
    vv = [mp.fsum(Phi[i][k] * etad[k] for k in range(n)) for i in range(n)]
    return qq, vv, sim.events


def jacobian(text, t0, z, periods, directions, h):
    """Columns dF·d for each direction d (2n-vectors), by central differences of step h."""
    n = len(z) // 2
    cols = []
    for d in directions:
        zp = [z[i] + h * d[i] for i in range(2 * n)]
        zm = [z[i] - h * d[i] for i in range(2 * n)]
        qp, vp, _ = flow(text, t0, zp[:n], zp[n:], periods)
        qm, vm, _ = flow(text, t0, zm[:n], zm[n:], periods)
        cols.append([(a - b) / (2 * h) for a, b in zip(qp + vp, qm + vm)])
    return cols


def fixed_point(text, t0, z, periods, directions, h, iterations=3):
    """Newton on F(z) − z restricted to z + span(directions) (the held manifold, or all of R^2n)."""
    k = len(directions)
    n = len(z) // 2
    for _ in range(iterations):
        q1, v1, _ = flow(text, t0, z[:n], z[n:], periods)
        r = [a - b for a, b in zip(q1 + v1, z)]
        cols = jacobian(text, t0, z, periods, directions, h)
        # least squares on the directions: (DF − I) D y = −r
        A = mp.matrix(2 * n, k)
        for c in range(k):
            for i in range(2 * n):
                A[i, c] = cols[c][i] - directions[c][i]
        y = mp.lu_solve(A.T * A, A.T * mp.matrix([-x for x in r]))
        z = [z[i] + mp.fsum(y[c] * directions[c][i] for c in range(k)) for i in range(2 * n)]
    q1, v1, events = flow(text, t0, z[:n], z[n:], periods)
    res = max(abs(a - b) for a, b in zip(q1 + v1, z))
    return z, res, events


def reduced_multipliers(text, t0, z, periods, directions, h):
    """Eigenvalues of DF restricted to span(directions) (DF maps it into itself: the held manifold)."""
    k = len(directions)
    n = len(z) // 2
    cols = jacobian(text, t0, z, periods, directions, h)
    D = mp.matrix(2 * n, k)
    J = mp.matrix(2 * n, k)
    for c in range(k):
        for i in range(2 * n):
            D[i, c] = directions[c][i]
            J[i, c] = cols[c][i]
    # coordinates of DF d_c in the basis: least squares
    B = (D.T * D) ** -1 * (D.T * J)
    ev = mp.eig(B, left=False, right=False)
    return sorted(ev, key=lambda x: -abs(x)), cols
