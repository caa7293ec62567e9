"""A compliant stop (docs/compliant.md) under a sum of harmonics (docs/harmonics.md), against a
truth written here without vibro's code: mpmath's Taylor ODE solver (mpmath.odefun) at 30 digits,
phase by phase.

The scene: one DOF, q'' + q = F(t) with F(t) = Σ_h f_h sin(ω_h t + ψ_h) (two harmonics, ω = 0.8
and 1.6, a phase on the second), a spring–dashpot stop below (gap g = q − x0, x0 = −0.5): while
in contact the stop pushes with λ = −k g − c ġ. Both separation rules:

* "gap": the contact phase ends where g returns to 0;
* "force" (the default): it ends where λ returns to 0, the body leaving a surface still compressed
  by y0 = g(exit) < 0, which relaxes as y0 e^(−k s/c) while the body flies; the body touches it
  again where g = y (an entry, with λ = −k g − c ġ again).

Each entry and exit is located by bisection on the Taylor solution (30 digits). The contact phases'
peak force (the maximum of λ over the phase, from λ' = 0 by mpmath.findroot) and their impulse
∫λ dt (mpmath.quad over the phase) are compared too, as vibro reports them per phase on the exit
event (reaction_max, reaction_integral).

ctest runs this file within python.pytest, with VIBRO_CLI set to the built `vibro`.
"""
import os
import subprocess

import h5py
import mpmath as mp
import numpy as np
import pytest

CLI = os.environ.get("VIBRO_CLI", "")

X0 = -0.5
K = 400.0
C = 2.0
AMP = [1.0, 0.4]
FREQ = [0.8, 1.6]
PHASE = [0.0, 0.7]


def scene_text(rule, periods):
    return f"""title = "compliant stop, two harmonics, reference"
[structure]
mass = [[1.0]]
stiffness = [[1.0]]
forcing_dof = 0
contact_dof = 0
[stop]
position = {X0}
stiffness = {K}
damping = {C}
separation = "{rule}"
[excitation]
amplitude = {AMP}
frequency = {FREQ}
phase = {PHASE}
[run]
periods = {periods}
samples_per_period = 0
lyapunov = false
"""


@pytest.fixture(autouse=True)
def _keep_mpmath_precision():
    dps = mp.mp.dps
    yield
    mp.mp.dps = dps


def forcing(t):
    return sum(mp.mpf(AMP[h]) * mp.sin(mp.mpf(FREQ[h]) * t + mp.mpf(PHASE[h])) for h in range(2))


def solve(t0, y0, contact):
    """The Taylor solution from (t0, [q, q']): a flight, or a contact phase with the spring–dashpot."""
    k, c, x0 = mp.mpf(K), mp.mpf(C), mp.mpf(X0)
    if contact:
        return mp.odefun(lambda t, y: [y[1], -y[0] + forcing(t) - k * (y[0] - x0) - c * y[1]], t0, y0)
    return mp.odefun(lambda t, y: [y[1], -y[0] + forcing(t)], t0, y0)


def first_root(fun, a, step, t_end):
    """The first sign change of fun after a (fun(a) ≥ 0 side: fun > 0 just after a), by stepping,
    then bisection to 30 digits; None before t_end."""
    lo, hi = a, a + step
    while fun(hi) > 0:
        lo, hi = hi, hi + step
        if hi > t_end:
            return None
    for _ in range(110):
        m = (lo + hi) / 2
        if fun(m) > 0:
            lo = m
        else:
            hi = m
    return (lo + hi) / 2


def reference(rule, t_end, phases):
    """Entries and exits, each contact phase's (entry, exit, peak force, impulse), from rest at 0."""
    mp.mp.dps = 30
    k, c, x0 = mp.mpf(K), mp.mpf(C), mp.mpf(X0)
    t, y = mp.mpf(0), [mp.mpf(0), mp.mpf(0)]
    surface, relax_from = mp.mpf(0), mp.mpf(0)  # the relaxing surface y0 e^(−k (t − t_exit)/c)
    out = []
    while len(out) < phases:
        sol = solve(t, y, contact=False)

        def gap_to_surface(s):
            return sol(s)[0] - x0 - surface * mp.exp(-k / c * (s - relax_from))

        t_in = first_root(gap_to_surface, t + mp.mpf("1e-6") if out else t, mp.mpf("0.01"), t_end)
        if t_in is None:
            break
        y = sol(t_in)
        ph = solve(t_in, y, contact=True)
        if rule == "gap":
            leave = lambda s: -(ph(s)[0] - x0)  # noqa: E731  (−g > 0 while in contact)
        else:
            leave = lambda s: -k * (ph(s)[0] - x0) - c * ph(s)[1]  # noqa: E731  (λ > 0 while in contact)
        t_out = first_root(leave, t_in + mp.mpf("1e-9"), mp.mpf("0.002"), t_end)
        assert t_out is not None, "the reference's contact phase did not end"
        lam = lambda s: -k * (ph(s)[0] - x0) - c * ph(s)[1]  # noqa: E731
        # λ' = −k q' − c q'' with q'' of the contact phase.
        dlam = lambda s: -k * ph(s)[1] - c * (-ph(s)[0] + forcing(s) - k * (ph(s)[0] - x0) - c * ph(s)[1])  # noqa: E731
        grid = [t_in + (t_out - t_in) * i / 64 for i in range(65)]
        vals = [lam(s) for s in grid]
        i = max(range(65), key=lambda j: vals[j])
        peak = vals[i]
        if 0 < i < 64:
            s_peak = mp.findroot(dlam, grid[i])
            peak = max(peak, lam(s_peak))
        impulse = mp.quad(lam, [t_in, t_out])
        out.append((t_in, t_out, peak, impulse))
        y = ph(t_out)
        t = t_out
        if rule == "force":
            surface, relax_from = y[0] - x0, t_out
    return out


def simulate(tmp_path, rule, periods):
    scene = tmp_path / f"{rule}.toml"
    scene.write_text(scene_text(rule, periods))
    out = tmp_path / f"{rule}.h5"
    p = subprocess.run([CLI, "simulate", str(scene), "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    with h5py.File(out, "r") as f:
        kinds = h5py.check_enum_dtype(f["events/kind"].dtype)
        ev = {k: f["events"][k][:] for k in ("t", "kind", "reaction_max", "reaction_integral")}
    return ev, kinds


@pytest.mark.parametrize("rule", ["gap", "force"])
def test_compliant_stop_under_two_harmonics_against_taylor_solver(tmp_path, rule):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    ev, kinds = simulate(tmp_path, rule, periods=3)
    entries = np.flatnonzero(ev["kind"] == kinds["stick"])
    exits = np.flatnonzero(ev["kind"] == kinds["release"])
    assert entries.size >= 3 and exits.size >= 3, "the scene was chosen to hit the stop each period"
    n = 3
    ref = reference(rule, mp.mpf(ev["t"][exits[n - 1]]) + 1, n)
    assert len(ref) == n
    for j, (t_in, t_out, peak, impulse) in enumerate(ref):
        e_in, e_out = entries[j], exits[j]
        assert abs(ev["t"][e_in] - float(t_in)) <= 1e-13 * max(1.0, float(t_in)), (j, ev["t"][e_in], t_in)
        assert abs(ev["t"][e_out] - float(t_out)) <= 1e-13 * max(1.0, float(t_out)), (j, ev["t"][e_out], t_out)
        assert abs(ev["reaction_max"][e_out] - float(peak)) <= 1e-12 * abs(float(peak)), (j, ev["reaction_max"][e_out], peak)
        assert abs(ev["reaction_integral"][e_out] - float(impulse)) <= 1e-12 * abs(float(impulse)), \
            (j, ev["reaction_integral"][e_out], impulse)


def test_second_harmonic_matters(tmp_path):
    """The same scene with the second harmonic's amplitude 0 is a different run (the sum is used in
    the contact phase, not dropped)."""
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    ev, kinds = simulate(tmp_path, "gap", periods=3)
    one = tmp_path / "one.toml"
    one.write_text(scene_text("gap", 3).replace(f"amplitude = {AMP}", f"amplitude = [{AMP[0]}, 0.0]"))
    out = tmp_path / "one.h5"
    p = subprocess.run([CLI, "simulate", str(one), "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    with h5py.File(out, "r") as f:
        t1 = f["events"]["t"][:]
    assert abs(ev["t"][1] - t1[1]) > 1e-3
