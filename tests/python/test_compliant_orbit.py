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


class Ref:
    """The scene the reference integrates (physical): m q'' + 2ζ√(k_s m) q' + k_s q = F sin ωt + λ, the
    stop's gap g = q − x0, λ = −k g − c ġ in contact; `entry_step` and `exit_step` the stepping of
    the root searches (below a flight's and a contact phase's shortest excursion)."""

    def __init__(self, rule, m=1, ks=1, zeta=ZETA, x0=X0, k=K, c=C, amp=AMP, freq=FREQ, entry_step="0.01",
                 exit_step="0.002", skip="1e-6"):
        self.rule = rule
        self.m, self.ks, self.zeta, self.x0 = mp.mpf(m), mp.mpf(ks), mp.mpf(zeta), mp.mpf(x0)
        self.k, self.c, self.amp, self.freq = mp.mpf(k), mp.mpf(c), mp.mpf(amp), mp.mpf(freq)
        self.entry_step, self.exit_step, self.skip = mp.mpf(entry_step), mp.mpf(exit_step), mp.mpf(skip)

    def accel(self, t, q, v, contact):
        f = -self.ks * q - 2 * self.zeta * mp.sqrt(self.ks * self.m) * v + self.amp * mp.sin(self.freq * t)
        if contact:
            f += -self.k * (q - self.x0) - self.c * v
        return f / self.m

    def solve(self, t0, y0, contact):
        return mp.odefun(lambda t, y: [y[1], self.accel(t, y[0], y[1], contact)], t0, y0)


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


def return_map(t0, z, ref, periods=1, loads=False):
    """The state (q, q') after `periods` forcing periods from (t0, z) in a free flight, and the contact
    phases on the way (entry, exit, peak, penetration, impulse, dissipated) when `loads`."""
    mp.mp.dps = 30
    k, c, x0 = ref.k, ref.c, ref.x0
    t_end = t0 + periods * 2 * mp.pi / ref.freq
    t, y = t0, list(z)
    surface, relax_from = mp.mpf(0), t0
    phases = []
    started = False
    while True:
        sol = ref.solve(t, y, False)

        def gap_to_surface(s):
            return sol(s)[0] - x0 - (surface * mp.exp(-k / c * (s - relax_from)) if surface else 0)

        t_in = first_root(gap_to_surface, t + ref.skip if started else t, ref.entry_step, t_end)
        if t_in is None:
            return [sol(t_end)[0], sol(t_end)[1]], phases
        started = True
        y = sol(t_in)
        ph = ref.solve(t_in, y, True)

        def lam(s):
            q, v = ph(s)
            return -k * (q - x0) - c * v

        if ref.rule == "gap" or c == 0:
            leave = lambda s: -(ph(s)[0] - x0)  # noqa: E731
        else:
            leave = lam
        t_out = first_root(leave, t_in + ref.exit_step / 1000, ref.exit_step, t_end + 1)
        assert t_out is not None and t_out < t_end, "the section is in a free flight"
        if loads:
            dlam = lambda s: -k * ph(s)[1] - c * ref.accel(s, ph(s)[0], ph(s)[1], True)  # noqa: E731
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
            if ref.rule == "force" and c != 0 and g_out < 0:
                dissipated += k * g_out ** 2 / 2
            phases.append(dict(entry=t_in, exit=t_out, peak_force=peak, penetration=penetration, impulse=impulse,
                               energy_dissipated=dissipated))
        y = ph(t_out)
        t = t_out
        surface = (y[0] - x0) if ref.rule == "force" and c != 0 else mp.mpf(0)
        relax_from = t_out


def vibro_orbit(tmp_path, rule, path=None):
    if path is None:
        path = tmp_path / f"{rule}.toml"
        path.write_text(scene_text(rule))
    out = tmp_path / f"{rule}.h5"
    o = vibro.orbit(vibro.load_scene(str(path)), out=str(out))
    with h5py.File(out, "r") as f:
        a = f["orbit"].attrs
        t0 = float(a["section_time"])
        X = np.atleast_1d(a["X"])
        V = np.atleast_1d(a["V"])
    return o, t0, X, V


def check_against_reference(o, t0, X, V, ref, loads_tol=1e-13):
    """vibro's orbit a fixed point of the reference's map (one DOF: the modal coordinate is q, mode
    shape 1 and modal mass m, `vibro model`); the multipliers against the eigenvalues of its Jacobian
    by central differences; each contact phase's loads."""
    assert o["status"] == "converged", o
    mp.mp.dps = 30
    z = [mp.mpf(X[0]), mp.mpf(V[0])]
    T0 = mp.mpf(t0)
    Pz, phases = return_map(T0, z, ref, periods=o["period"], loads=True)
    scale = max(abs(z[0]), abs(z[1]))
    # vibro's Newton stops at |F(z) − z|∞ ≤ 1e-12 (1 + |z|∞) (docs/orbits.md).
    assert max(abs(Pz[i] - z[i]) for i in range(2)) <= 1e-12 * (1 + scale), (Pz, z)
    h = mp.mpf("1e-10") * scale
    J = mp.matrix(2, 2)
    for j in range(2):
        zp, zm = list(z), list(z)
        zp[j] += h
        zm[j] -= h
        fp, _ = return_map(T0, zp, ref, periods=o["period"])
        fm, _ = return_map(T0, zm, ref, periods=o["period"])
        for i in range(2):
            J[i, j] = (fp[i] - fm[i]) / (2 * h)
    mu_ref = [complex(m) for m in mp.eig(J)[0]]
    mu = [complex(a, b) for a, b in o["floquet_multipliers"]]
    assert len(mu) == 2, o["floquet_multipliers"]
    errors = [min(abs(m - r) for r in mu_ref) for m in mu]
    assert max(errors) <= 1e-12, (mu, mu_ref)
    got = o["contact_phases"]
    assert len(got) == len(phases), (got, phases)
    worst = 0.0
    for p, r in zip(got, phases):
        assert abs(p["entry"] - float(r["entry"])) <= 1e-12 * abs(float(r["entry"]))
        assert abs(p["exit"] - float(r["exit"])) <= 1e-12 * abs(float(r["exit"]))
        assert abs(p["duration"] - float(r["exit"] - r["entry"])) <= 1e-11 * float(r["exit"] - r["entry"])
        for key in ("peak_force", "penetration", "impulse", "energy_dissipated"):
            want = float(r[key])
            err = abs(p[key] - want) / abs(want) if want != 0 else abs(p[key])
            worst = max(worst, err)
            assert err <= loads_tol, (key, p[key], want)
    return max(errors), worst, mu_ref


@pytest.mark.parametrize("rule", ["force", "gap"])
def test_compliant_orbit_against_taylor_return_map(tmp_path, rule):
    o, t0, X, V = vibro_orbit(tmp_path, rule)
    assert len(o["contact_phases"]) == 1 and o["period"] == 1, "the scene was chosen for one contact phase per period"
    _, _, mu_ref = check_against_reference(o, t0, X, V, Ref(rule))
    assert o["stable"] == all(abs(r) < 1 for r in mu_ref)


def test_sdnd121_penalty_orbit_against_taylor_return_map(tmp_path):
    """The shipped SDND121 penalty scene (m = 156 kg, k = 2e6 N/m, the stop 1e-3 m below, K = 1e10 N/m
    undamped, F = 3000 sin 10πt N): four contact phases of 0.4 ms per period, multipliers on the unit
    circle (nothing dissipates)."""
    scenes = os.environ.get("VIBRO_SCENES") or os.path.join(os.path.dirname(__file__), "..", "..", "data", "scenes")
    o, t0, X, V = vibro_orbit(tmp_path, "gap", path=os.path.join(scenes, "sdnd121_compliant.toml"))
    assert o["period"] == 1 and len(o["contact_phases"]) == 4, o
    ref = Ref("gap", m=156, ks=2e6, zeta=0, x0=-1e-3, k=1e10, c=0, amp=3000, freq=10 * mp.pi,
              entry_step="0.001", exit_step="0.00002", skip="0.00001")
    # The orbit is a fixed point to 8e-12 relative (Newton's tolerance; the reference's map agrees to
    # that), and at K = 1e10 the loads move with it: 2.6e-13 measured on the peak force.
    err, worst, _ = check_against_reference(o, t0, X, V, ref, loads_tol=1e-11)
    print(f"SDND121: multipliers {err:.2g}, loads {worst:.2g}")
    assert all(abs(abs(complex(a, b)) - 1) < 1e-12 for a, b in o["floquet_multipliers"])


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
