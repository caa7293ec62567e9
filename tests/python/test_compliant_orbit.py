"""Periodic orbits of a compliant stop (docs/compliant.md, "Periodic orbits"), against a truth written
here without vibro's code: the return map of mpmath's Taylor ODE solver (mpmath.odefun) at 30 digits,
phase by phase, and its Jacobian by central differences.

The scene: one DOF of unit mass, q'' + 2ζq' + q = F sin(ωt) (ζ = 0.05, F = 0.5, ω = 0.8), a
spring–dashpot stop below (gap g = q − x0, x0 = −0.5, k = 400, c = 2: ζ_c = 0.05): while in contact
it pushes with λ = −k g − c ġ. Both separation rules ("gap": the phase ends where g returns to 0;
"force": where λ returns to 0, the surface then relaxing as y0 e^(−k s/c) while the body flies, a
re-contact being where g = y). An isolated contact phase on this stop has the closed form of
docs/compliant.md; the orbit's phases are not isolated (the structure and the forcing act during
them), hence the integration.

vibro.orbit gives the section state (t0, q, q'), the multipliers and, per contact phase of the orbit,
its entry, duration, peak force, penetration, impulse and dissipated energy. The reference:

* the return map P over one period from vibro's section state: P(z) − z ≈ 0 (vibro's orbit is a
  fixed point of an independent map, to 1e-12);
* DP by central differences (h = 1e-10 at 30 digits: truncation 1e-20): its eigenvalues against
  vibro's multipliers (the analytic saltations of docs/compliant.md eqs. (C3)-(C7)), to 1e-9;
* each contact phase: entry and exit by bisection, the peak force from λ' = 0 (bisection), the
  penetration from ġ = 0, the impulse ∫λ dt and the dashpot's ∫c ġ² dt by mpmath.quad (plus ½k g²
  at a force-rule exit), to 1e-13 relative (measured ≤ 1.2e-15); entry and exit to 1e-12.

ctest runs this file within python.pytest, with VIBRO_CLI set to the built `vibro`.
"""
import os

import h5py
import mpmath as mp
import numpy as np
import pytest

vibro = pytest.importorskip("vibro")

X0 = -0.5
K = 400.0
C = 2.0
ZETA = 0.05
AMP = 0.5
FREQ = 0.8


def scene_text(rule, stiffness=K, damping=C):
    return f"""title = "compliant stop, periodic orbit, reference"
[structure]
mass = [[1.0]]
stiffness = [[1.0]]
damping_ratios = [{ZETA}]
forcing_dof = 0
contact_dof = 0
[stop]
position = {X0}
stiffness = {stiffness}
damping = {damping}
separation = "{rule}"
[excitation]
amplitude = {AMP}
frequency = {FREQ}
[run]
periods = 50
samples_per_period = 0
lyapunov = false
"""


@pytest.fixture(autouse=True)
def _keep_mpmath_precision():
    dps = mp.mp.dps
    yield
    mp.mp.dps = dps


def forcing(t):
    return mp.mpf(AMP) * mp.sin(mp.mpf(FREQ) * t)


def accel(t, q, v, contact, k, c):
    a = -q - 2 * mp.mpf(ZETA) * v + forcing(t)
    if contact:
        a += -k * (q - mp.mpf(X0)) - c * v
    return a


def solve(t0, y0, contact, k, c):
    return mp.odefun(lambda t, y: [y[1], accel(t, y[0], y[1], contact, k, c)], t0, y0)


def first_root(fun, a, step, t_end):
    """The first sign change of fun after a (fun > 0 just after a), by stepping, then bisection to 30
    digits; None before t_end."""
    lo, hi = a, a + step
    while fun(hi) > 0:
        lo, hi = hi, hi + step
        if hi > t_end:
            return None
    for _ in range(115):
        m = (lo + hi) / 2
        if fun(m) > 0:
            lo = m
        else:
            hi = m
    return (lo + hi) / 2


def bisect(fun, lo, hi):
    """The root of fun in [lo, hi] with fun(lo) < 0 ≤ fun(hi), to 30 digits."""
    for _ in range(115):
        m = (lo + hi) / 2
        if fun(m) < 0:
            lo = m
        else:
            hi = m
    return (lo + hi) / 2


def return_map(t0, z, rule, periods=1, loads=False, k=K, c=C):
    """The state after `periods` forcing periods from (t0, z) in a free flight, and the contact
    phases on the way (entry, exit, peak, penetration, impulse, dissipated) when `loads`."""
    mp.mp.dps = 30
    k, c, x0 = mp.mpf(k), mp.mpf(c), mp.mpf(X0)
    t_end = t0 + periods * 2 * mp.pi / mp.mpf(FREQ)
    t, y = t0, list(z)
    surface, relax_from = mp.mpf(0), t0
    phases = []
    started = False
    while True:
        sol = solve(t, y, False, k, c)

        def gap_to_surface(s):
            return sol(s)[0] - x0 - (surface * mp.exp(-k / c * (s - relax_from)) if surface else 0)

        t_in = first_root(gap_to_surface, t + mp.mpf("1e-6") if started else t, mp.mpf("0.01"), t_end)
        if t_in is None:
            return [sol(t_end)[0], sol(t_end)[1]], phases
        started = True
        y = sol(t_in)
        ph = solve(t_in, y, True, k, c)

        def lam(s):
            q, v = ph(s)
            return -k * (q - x0) - c * v

        if rule == "gap" or c == 0:
            leave = lambda s: -(ph(s)[0] - x0)  # noqa: E731
        else:
            leave = lam
        t_out = first_root(leave, t_in + mp.mpf("1e-9"), mp.mpf("0.002"), t_end + 1)
        assert t_out is not None and t_out < t_end, "the section is in a free flight"
        if loads:
            dlam = lambda s: -k * ph(s)[1] - c * accel(s, ph(s)[0], ph(s)[1], True, k, c)  # noqa: E731
            grid = [t_in + (t_out - t_in) * i / 64 for i in range(65)]
            vals = [lam(s) for s in grid]
            i = max(range(65), key=lambda j: vals[j])
            peak = vals[i]
            if 0 < i < 64:  # λ' > 0 before the peak, < 0 after
                peak = max(peak, lam(bisect(lambda s: -dlam(s), grid[i - 1], grid[i + 1])))
            gd = [ph(s)[1] for s in grid]
            i = next(j for j in range(64) if gd[j] < 0 <= gd[j + 1])
            s_min = bisect(lambda s: ph(s)[1], grid[i], grid[i + 1])
            penetration = -(ph(s_min)[0] - x0)
            impulse = mp.quad(lam, [t_in, t_out])
            dissipated = c * mp.quad(lambda s: ph(s)[1] ** 2, [t_in, t_out])
            g_out = ph(t_out)[0] - x0
            if rule == "force" and c != 0 and g_out < 0:
                dissipated += k * g_out ** 2 / 2
            phases.append(dict(entry=t_in, exit=t_out, peak_force=peak, penetration=penetration, impulse=impulse,
                               energy_dissipated=dissipated))
        y = ph(t_out)
        t = t_out
        surface = (y[0] - x0) if rule == "force" and c != 0 else mp.mpf(0)
        relax_from = t_out


def vibro_orbit(tmp_path, rule, **kw):
    scene = tmp_path / f"{rule}.toml"
    scene.write_text(scene_text(rule, **kw))
    out = tmp_path / f"{rule}.h5"
    o = vibro.orbit(vibro.load_scene(str(scene)), out=str(out))
    with h5py.File(out, "r") as f:
        a = f["orbit"].attrs
        t0 = float(a["section_time"])
        X = np.atleast_1d(a["X"])
        V = np.atleast_1d(a["V"])
    return o, t0, X, V


@pytest.mark.parametrize("rule", ["force", "gap"])
def test_compliant_orbit_against_taylor_return_map(tmp_path, rule):
    o, t0, X, V = vibro_orbit(tmp_path, rule)
    assert o["status"] == "converged", o
    phases = o["contact_phases"]
    assert len(phases) == 1 and o["period"] == 1, "the scene was chosen for one contact phase per period"
    # The orbit is a fixed point of the reference's map.
    mp.mp.dps = 30
    z = [mp.mpf(X[0]), mp.mpf(V[0])]
    T0 = mp.mpf(t0)
    Pz, ref = return_map(T0, z, rule, loads=True)
    assert max(abs(Pz[i] - z[i]) for i in range(2)) <= 1e-12, (Pz, z)
    # Its Jacobian by central differences; the multipliers.
    h = mp.mpf("1e-10")
    J = mp.matrix(2, 2)
    for j in range(2):
        zp, zm = list(z), list(z)
        zp[j] += h
        zm[j] -= h
        fp, _ = return_map(T0, zp, rule)
        fm, _ = return_map(T0, zm, rule)
        for i in range(2):
            J[i, j] = (fp[i] - fm[i]) / (2 * h)
    mu_ref = [complex(m) for m in mp.eig(J)[0]]
    mu = [complex(a, b) for a, b in o["floquet_multipliers"]]
    assert len(mu) == 2, o["floquet_multipliers"]
    for m in mu:
        assert min(abs(m - r) for r in mu_ref) <= 1e-12, (mu, mu_ref)
    assert o["stable"] == all(abs(r) < 1 for r in mu_ref)
    # The contact phase's loads, exactly.
    p, r = phases[0], ref[0]
    assert abs(p["entry"] - float(r["entry"])) <= 1e-12 * abs(float(r["entry"]))
    assert abs(p["exit"] - float(r["exit"])) <= 1e-12 * abs(float(r["exit"]))
    assert abs(p["duration"] - float(r["exit"] - r["entry"])) <= 1e-11 * float(r["exit"] - r["entry"])
    for key in ("peak_force", "penetration", "impulse", "energy_dissipated"):
        assert abs(p[key] - float(r[key])) <= 1e-13 * abs(float(r[key])), (key, p[key], r[key])


def test_orbit_json_equals_cli(tmp_path):
    """`vibro orbit --json` and vibro.orbit give the same dict on a compliant scene; the text names the
    contact phases."""
    import json
    import subprocess
    cli = os.environ.get("VIBRO_CLI", "")
    if not cli:
        pytest.skip("VIBRO_CLI is not set")
    scene = tmp_path / "s.toml"
    scene.write_text(scene_text("force"))
    got = vibro.orbit(vibro.load_scene(str(scene)))
    p = subprocess.run([cli, "orbit", str(scene), "--json"], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert got == json.loads(p.stdout)
    t = subprocess.run([cli, "orbit", str(scene)], capture_output=True, text=True, timeout=600)
    assert t.returncode == 0 and "contact phases over the orbit" in t.stdout and "peak force" in t.stdout, t.stdout
