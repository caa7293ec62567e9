"""Branch switching (`vibro continue --from FILE --point K --switch`, docs/orbits.md) against
independent truths written here in mpmath (40 digits), from the closed-form free flight of one DOF
and nothing of vibro:

(a) the symmetric two-sided oscillator x'' + x = a sin(2.5 t), stops at -1 and +1, r = 0.8, loses
    its symmetry in a pitchfork near a = 4.604. The switched branch is the asymmetric period-1 orbit:
    at a = 4.7 and a = 4.9 its two impact speeds (on +1 and on -1), their phases and its Floquet
    multipliers (eigenvalues of the impact-to-impact map's Jacobian, by central differences at 40
    digits) match the orbit solved here, to 1e-9; --side above and below give the two mirror
    halves (x -> -x, t -> t + T/2);
(b) one DOF on a stop at x0 = 1 (r = 0.5, omega = 3): the one-impact period-1 orbit flips near
    f = 7.3; the switched branch is the period-2 orbit with two impacts of different speeds,
    matched at f = 7.45 and f = 7.6 (speeds, phases, multipliers) to 1e-9;
(c) bad requests: a point with no branch-point or flip next to it, --to on the side the new branch
    does not go to: exit 2, one located line, nothing written.

Each truth is found from an event-driven simulation of its own (the closed-form flight, impacts
located by bisection) and polished by mpmath.findroot; the flights of the solved orbit are checked
to stay off the stops (admissibility).
"""
import json
import math
import os
import subprocess

import h5py
import mpmath as mp
import numpy as np
import pytest

mp.mp.dps = 40
CLI = os.environ.get("VIBRO_CLI", "")


def vibro(*args, check=True):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=900)
    if check:
        assert p.returncode == 0, p.stderr
    return p


# --- The free flight of x'' + x = a sin(w t) from (x0, v0) at t0, after time s -------------------


def flight(a, w, x0, v0, t0, s):
    U = a / (1 - w**2)
    A = x0 - U * mp.sin(w * t0)
    B = v0 - U * w * mp.cos(w * t0)
    return (A * mp.cos(s) + B * mp.sin(s) + U * mp.sin(w * (t0 + s)),
            -A * mp.sin(s) + B * mp.cos(s) + U * w * mp.cos(w * (t0 + s)))


def flight_f(a, w, x0, v0, t0, s):
    U = a / (1 - w**2)
    A = x0 - U * math.sin(w * t0)
    B = v0 - U * w * math.cos(w * t0)
    return A * math.cos(s) + B * math.sin(s) + U * math.sin(w * (t0 + s))


def stays_inside(a, w, x0, v0, t0, s_end, inside, samples=2000):
    """The flight keeps inside(x) strictly between its ends."""
    return all(inside(flight(a, w, x0, v0, t0, s_end * k / samples)[0]) for k in range(1, samples))


def simulate(a, w, r, x, v, stops, periods):
    """Event-driven simulation, float: the impacts (time, stop, arrival velocity) of `periods`
    forcing periods. stops: list of (position, side) with side +1 for a stop above (x <= pos)."""
    t, out, T = 0.0, [], 2 * math.pi / w
    while t < periods * T:
        h, s = 2e-3, 2e-3
        while True:
            xs = flight_f(a, w, x, v, t, s)
            hit = [(p, sd) for p, sd in stops if (xs - p) * sd > 0]
            if hit:
                break
            s += h
        p, sd = hit[0]
        lo, hi = s - h, s
        for _ in range(70):
            m = 0.5 * (lo + hi)
            if (flight_f(a, w, x, v, t, m) - p) * sd > 0:
                hi = m
            else:
                lo = m
        _, vs = flight(a, w, x, v, t, hi)
        t += hi
        x, v = p, -r * float(vs)
        out.append((t, p, float(vs)))
    return out


# --- (a) the asymmetric orbits of the two-sided oscillator ---------------------------------------

W2, R2 = mp.mpf("2.5"), mp.mpf("0.8")
T2 = 2 * mp.pi / W2


def asymmetric_orbit(a):
    """Impact on +1 at t1 with arrival speed V1, free flight to -1 (arrival speed V2 at t2), free
    flight back to +1 at t1 + T: four equations in (t1, V1, t2, V2)."""
    a = mp.mpf(a)
    ev = simulate(float(a), float(W2), float(R2), 0.0, 0.0, [(1.0, 1), (-1.0, -1)], 400)
    up = next(e for e in reversed(ev[:-2]) if e[1] == 1.0)
    down = next(e for e in ev if e[0] > up[0])

    def residual(t1, V1, t2, V2):
        x2, v2 = flight(a, W2, 1, -R2 * V1, t1, t2 - t1)
        x3, v3 = flight(a, W2, -1, R2 * V2, t2, t1 + T2 - t2)
        return [x2 + 1, v2 + V2, x3 - 1, v3 - V1]

    t1, V1, t2, V2 = mp.findroot(residual, (up[0], up[2], down[0], -down[2]))
    assert max(abs(x) for x in residual(t1, V1, t2, V2)) < mp.mpf(10) ** -30
    assert V1 > 0 and V2 > 0
    assert stays_inside(a, W2, 1, -R2 * V1, t1, t2 - t1, lambda x: -1 < x < 1)
    assert stays_inside(a, W2, -1, R2 * V2, t2, t1 + T2 - t2, lambda x: -1 < x < 1)

    # The impact map from +1 to +1: (t, V) -> (t', V'), its Jacobian by central differences.
    def impact_map(t, V):
        s1 = mp.findroot(lambda s: flight(a, W2, 1, -R2 * V, t, s)[0] + 1, t2 - t1)
        _, v = flight(a, W2, 1, -R2 * V, t, s1)
        s2 = mp.findroot(lambda s: flight(a, W2, -1, -R2 * v, t + s1, s)[0] - 1, t1 + T2 - t2)
        _, v2 = flight(a, W2, -1, -R2 * v, t + s1, s2)
        return mp.matrix([t + s1 + s2, v2])

    h = mp.mpf(10) ** -15
    J = mp.matrix(2, 2)
    for j, (dt, dV) in enumerate([(h, 0), (0, h)]):
        col = (impact_map(t1 + dt, V1 + dV) - impact_map(t1 - dt, V1 - dV)) / (2 * h)
        J[0, j], J[1, j] = col[0], col[1]
    mu = mp.eig(J)[0]
    phase = lambda t: float(mp.fmod(W2 * t, 2 * mp.pi))  # noqa: E731
    return {"speeds": {1: float(V1), 0: float(V2)}, "phases": {1: phase(t1), 0: phase(t2)},
            "multipliers": sorted((complex(m) for m in mu), key=lambda z: (z.real, z.imag))}


def mirror(orbit):
    """x -> -x, t -> t + T/2: the other half of the pitchfork."""
    return {"speeds": {0: orbit["speeds"][1], 1: orbit["speeds"][0]},
            "phases": {0: (orbit["phases"][1] + math.pi) % (2 * math.pi),
                       1: (orbit["phases"][0] + math.pi) % (2 * math.pi)},
            "multipliers": orbit["multipliers"]}


TWO_SIDED = """
title = "Two-sided 1-DOF, r = 0.8"
[structure]
mass = [[1.0]]
stiffness = [[1.0]]
forcing_dof = 0
[[contact]]
dof = 0
side = "below"
position = -1.0
restitution = 0.8
[[contact]]
dof = 0
side = "above"
position = 1.0
restitution = 0.8
[excitation]
amplitude = 4.0
frequency = 2.5
[run]
periods = 200
"""


def last_point(path):
    """The last point of a stored branch: value, {contact: (|v_before|, phase)}, multipliers."""
    with h5py.File(path, "r") as f:
        g = f["branch"]
        i = len(g["value"]) - 1
        lo, hi = g["impact_offsets"][i], g["impact_offsets"][i + 1]
        impacts = [(int(c), abs(v), ph) for c, v, ph in zip(g["impact_contact"][lo:hi], g["impact_v_before"][lo:hi],
                                                             g["impact_phase"][lo:hi])]
        mu = g["multipliers"][i]
        return (float(g["value"][i]), impacts, sorted((complex(m[0], m[1]) for m in mu if np.isfinite(m[0])),
                                                      key=lambda z: (z.real, z.imag)), bool(g["stable"][i]),
                int(g.attrs["period"]))


def primary_branch(tmp_path, scene, param, to, extra=()):
    out = tmp_path / "primary.h5"
    b = json.loads(vibro("continue", scene, "--param", param, "--to", to, "--out", out, "--json", *extra).stdout)
    return out, b


def point_next_to(b, kind):
    bif = [x for x in b["bifurcations"] if x["kind"] == kind]
    assert len(bif) == 1, b["bifurcations"]
    values = [p["value"] for p in b["points"]]
    k = min(range(len(values)), key=lambda i: abs(values[i] - bif[0]["value"]))
    return k, bif[0]["value"]


def angle_gap(x, y):
    d = abs(x - y) % (2 * math.pi)
    return min(d, 2 * math.pi - d)


def matches(impacts, mu, truth, tol=1e-9):
    speeds = {c: v for c, v, _ in impacts}
    phases = {c: ph for c, _, ph in impacts}
    return (len(impacts) == len(truth["speeds"]) and
            all(abs(speeds[c] - truth["speeds"][c]) < tol for c in truth["speeds"]) and
            all(angle_gap(phases[c], truth["phases"][c]) < tol for c in truth["phases"]) and
            same_multipliers(mu, truth["multipliers"], tol))


def same_multipliers(mu, truth, tol=1e-9):
    """One to one within tol (a conjugate pair in any order)."""
    left = list(mu)
    for z in truth:
        if not left:
            return False
        i = min(range(len(left)), key=lambda k: abs(left[k] - z))
        if abs(left[i] - z) >= tol:
            return False
        left.pop(i)
    return not left


def test_switch_at_the_pitchfork_follows_the_asymmetric_orbits(tmp_path):
    scene = tmp_path / "two_sided.toml"
    scene.write_text(TWO_SIDED)
    primary, b = primary_branch(tmp_path, scene, "excitation.amplitude", 5.0)
    k, a_bp = point_next_to(b, "branch-point")
    assert 4.6 < a_bp < 4.61
    for a in ("4.7", "4.9"):
        truth = asymmetric_orbit(a)
        assert abs(truth["speeds"][0] - truth["speeds"][1]) > 1e-2  # asymmetric indeed
        halves = []
        for side in ("above", "below"):
            out = tmp_path / f"switched_{a}_{side}.h5"
            p = vibro("continue", scene, "--param", "excitation.amplitude", "--to", a, "--from", primary, "--point", k,
                      "--switch", "--side", side, "--out", out)
            assert "switch       branch-point at excitation.amplitude = 4.60" in p.stdout, p.stdout
            value, impacts, mu, stable, period = last_point(out)
            assert value == float(a) and period == 1
            assert stable  # both mirror orbits are attractors there (the simulation above settles on one)
            assert abs(np.prod(mu) - 0.8**4) < 1e-10
            ok = [matches(impacts, mu, t) for t in (truth, mirror(truth))]
            assert any(ok), (a, side, impacts, mu, truth)
            halves.append(ok.index(True))
        assert sorted(halves) == [0, 1], halves  # above and below are the two mirror orbits


# --- (b) the period-2 orbit past a flip ----------------------------------------------------------

W1, R1 = mp.mpf(3), mp.mpf("0.5")
T1 = 2 * mp.pi / W1

ONE_STOP = """
title = "1-DOF on a stop at x0 = 1, r = 0.5, omega = 3"
[structure]
frequencies = [1.0]
forcing     = [1.0]
contact     = [1.0]
[stop]
position    = 1.0
restitution = 0.5
[excitation]
amplitude = 7.0
frequency = 3.0
[run]
periods = 400
"""


def period_two_orbit(f):
    """Impacts on x = 1 (arrival velocity -V) at t1 and t2 within 2T: four equations in (t1, V1, t2, V2)."""
    f = mp.mpf(f)
    ev = simulate(float(f), float(W1), float(R1), 1.0, 1.0, [(1.0, -1)], 600)
    (ta, _, va), (tb, _, vb) = ev[-2], ev[-1]

    def residual(t1, V1, t2, V2):
        x2, v2 = flight(f, W1, 1, R1 * V1, t1, t2 - t1)
        x3, v3 = flight(f, W1, 1, R1 * V2, t2, t1 + 2 * T1 - t2)
        return [x2 - 1, v2 + V2, x3 - 1, v3 + V1]

    t1, V1, t2, V2 = mp.findroot(residual, (ta, -va, tb, -vb))
    assert max(abs(x) for x in residual(t1, V1, t2, V2)) < mp.mpf(10) ** -30
    assert abs(V1 - V2) > mp.mpf("1e-2")  # a true period-2 orbit, not the period-1 one twice
    assert stays_inside(f, W1, 1, R1 * V1, t1, t2 - t1, lambda x: x > 1)
    assert stays_inside(f, W1, 1, R1 * V2, t2, t1 + 2 * T1 - t2, lambda x: x > 1)

    def impact_map(t, V):  # two impacts: (t1, V1) -> (t1 + 2T, V1)
        s1 = mp.findroot(lambda s: flight(f, W1, 1, R1 * V, t, s)[0] - 1, t2 - t1)
        _, v = flight(f, W1, 1, R1 * V, t, s1)
        s2 = mp.findroot(lambda s: flight(f, W1, 1, -R1 * v, t + s1, s)[0] - 1, t1 + 2 * T1 - t2)
        _, v2 = flight(f, W1, 1, -R1 * v, t + s1, s2)
        return mp.matrix([t + s1 + s2, -v2])

    h = mp.mpf(10) ** -15
    J = mp.matrix(2, 2)
    for j, (dt, dV) in enumerate([(h, 0), (0, h)]):
        col = (impact_map(t1 + dt, V1 + dV) - impact_map(t1 - dt, V1 - dV)) / (2 * h)
        J[0, j], J[1, j] = col[0], col[1]
    mu = sorted((complex(m) for m in mp.eig(J)[0]), key=lambda z: (z.real, z.imag))
    phase = lambda t: float(mp.fmod(W1 * t, 4 * mp.pi))  # noqa: E731
    return [(float(V1), phase(t1)), (float(V2), phase(t2))], mu


def test_switch_at_a_flip_follows_the_period_two_orbit(tmp_path):
    scene = tmp_path / "one_stop.toml"
    scene.write_text(ONE_STOP)
    primary, b = primary_branch(tmp_path, scene, "excitation.amplitude", 7.6, ("--kind", "impact", "--period", "1"))
    k, f_flip = point_next_to(b, "flip")
    assert 7.0 < f_flip < 7.4
    for f in ("7.45", "7.6"):
        impacts_true, mu_true = period_two_orbit(f)
        out = tmp_path / f"doubled_{f}.h5"
        p = vibro("continue", scene, "--param", "excitation.amplitude", "--to", f, "--from", primary, "--point", k,
                  "--switch", "--out", out)
        assert "switch       flip at excitation.amplitude = 7." in p.stdout and "(period 2)" in p.stdout, p.stdout
        value, impacts, mu, stable, period = last_point(out)
        assert value == float(f) and period == 2 and stable
        assert len(impacts) == 2
        # The same two impacts (phases mod 2 pi: the orbit and its shift by T are one orbit), the
        # same time between them.
        got = sorted((v, ph) for _, v, ph in impacts)
        want = sorted(impacts_true)
        for (v, ph), (vt, pht) in zip(got, want):
            assert abs(v - vt) < 1e-9, (f, got, want)
            assert angle_gap(ph, pht) < 1e-9, (f, got, want)
        gap = lambda pair: (pair[1][1] - pair[0][1]) % (4 * math.pi)  # noqa: E731
        assert abs(gap(got) - gap(want)) < 1e-9, (f, got, want)
        assert same_multipliers(mu, mu_true), (f, mu, mu_true)
        assert abs(np.prod(mu) - 0.5**4) < 1e-10  # two impacts: det = r^4


# --- (c) bad requests ----------------------------------------------------------------------------


def test_switch_refuses_a_point_without_a_bifurcation_and_the_wrong_side(tmp_path):
    scene = tmp_path / "two_sided.toml"
    scene.write_text(TWO_SIDED)
    primary, b = primary_branch(tmp_path, scene, "excitation.amplitude", 5.0)
    k, a_bp = point_next_to(b, "branch-point")
    out = tmp_path / "never.h5"
    p = vibro("continue", scene, "--param", "excitation.amplitude", "--to", 5.0, "--from", primary, "--point", 0,
              "--switch", "--out", out, check=False)
    assert p.returncode == 2 and "--switch: no branch-point or flip" in p.stderr and "branch-point at 4.6" in p.stderr
    assert not out.exists()
    # The asymmetric orbits exist above the pitchfork only (it is supercritical).
    p = vibro("continue", scene, "--param", "excitation.amplitude", "--to", 4.0, "--from", primary, "--point", k,
              "--switch", "--out", out, check=False)
    assert p.returncode == 2 and "towards excitation.amplitude > 4.60" in p.stderr, p.stderr
    assert not out.exists()
    p = vibro("continue", scene, "--param", "excitation.amplitude", "--to", 5.0, "--side", "above", check=False)
    assert p.returncode == 2


# --- (d) from Python -----------------------------------------------------------------------------


def test_python_switch_gives_the_cli_branch(tmp_path):
    vibro_py = pytest.importorskip("vibro")
    scene = tmp_path / "two_sided.toml"
    scene.write_text(TWO_SIDED)
    primary, b = primary_branch(tmp_path, scene, "excitation.amplitude", 5.0)
    k, _ = point_next_to(b, "branch-point")
    cli = json.loads(vibro("continue", scene, "--param", "excitation.amplitude", "--to", 4.8, "--from", primary,
                           "--point", k, "--switch", "--side", "below", "--json").stdout)
    py = vibro_py.continue_(str(scene), "excitation.amplitude", 4.8, from_=primary, point=k, switch=True, side="below")
    assert [p["value"] for p in py["points"]] == [p["value"] for p in cli["points"]]
    assert [p["x_B"] for p in py["points"]] == [p["x_B"] for p in cli["points"]]
    truth = mirror(asymmetric_orbit("4.8"))
    last = py["points"][-1]
    assert last["value"] == 4.8 and last["stable"]
    assert same_multipliers([complex(*m) for m in last["floquet_multipliers"]], truth["multipliers"])
    with pytest.raises(ValueError):
        vibro_py.continue_(str(scene), "excitation.amplitude", 4.8, switch=True)
    with pytest.raises(ValueError, match="no branch-point or flip"):
        vibro_py.continue_(str(scene), "excitation.amplitude", 4.8, from_=primary, point=0, switch=True)
