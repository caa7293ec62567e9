"""Forcing as a sum of harmonics (docs/harmonics.md) against truths written here, without vibro's
code:

* a two-harmonic scene with impacts against mpmath's Taylor ODE solver (mpmath.odefun) at 30
  digits: the samples of the first flight and the times of the impacts (each flight integrated
  from the state the reference's own impact law gives, the impact located by bisection on the
  Taylor solution);
* superposition: a free flight under two harmonics is the sum of the flights under each, and each
  is its closed form (particular solution per harmonic plus the homogeneous part);
* the located errors of the [excitation] lists (exit 2, file:line:col, the key, the constraint);
* the shipped scene from the CLI (simulate, check against CVODE, the model).

ctest runs this file within python.pytest, with VIBRO_CLI set to the built `vibro`.
"""
import math
import os
import subprocess

import h5py
import mpmath as mp
import numpy as np
import pytest

CLI = os.environ.get("VIBRO_CLI", "")
SCENES = os.environ.get("VIBRO_SCENES", os.path.join(os.path.dirname(__file__), "..", "..", "data", "scenes"))

# Two modes in the paper's modal scaling (x_B = X_1 + X_2), a clearance, two harmonics at 1.3 and
# 3.25 (ratio 5/2: base pulsation 0.65), each with its own modal forcing vector and a phase.
OMEGA = [1.0, 2.7]
T_B = [0.7, 0.3]
X0 = -0.6
R = 0.8
AMP = [0.8, 0.5]
FREQ = [1.3, 3.25]
PHASE = [0.0, 0.7]
VECTORS = [[0.6, 0.4], [0.2, -0.5]]


def scene_text(amp=AMP, stop=X0, periods=2, initial=None, extra=""):
    init = ""
    if initial:
        init = "[initial]\ndisplacement = {}\nvelocity = {}\n".format(*initial)
    return f"""title = "two harmonics, reference"
[structure]
frequencies = {OMEGA}
forcing = [0.6, 0.4]
contact = {T_B}
[stop]
position = {stop}
restitution = {R}
[excitation]
amplitude = {list(amp)}
frequency = {FREQ}
phase = {PHASE}
vectors = {VECTORS}
{init}[run]
periods = {periods}
samples_per_period = 64
lyapunov = false
chatter = "none"
{extra}"""


def vibro(*args, code=0):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=900)
    assert p.returncode == code, p.stdout + p.stderr
    return p


def simulate(tmp_path, text, name="s"):
    scene = tmp_path / f"{name}.toml"
    scene.write_text(text)
    out = tmp_path / f"{name}.h5"
    vibro("simulate", scene, "--out", out)
    with h5py.File(out, "r") as f:
        kinds = h5py.check_enum_dtype(f["events/kind"].dtype)
        ev = {k: f["events"][k][:] for k in ("t", "kind", "v_before", "v_after")}
        smp = {k: f["samples"][k][:] for k in ("t", "X", "V")}
    return ev, smp, kinds


@pytest.fixture(autouse=True)
def _keep_mpmath_precision():
    dps = mp.mp.dps
    yield
    mp.mp.dps = dps


def forcing(t, i, amp=AMP, sines=None):
    """F_i(t) = Σ_h v_h,i f_h sin(ω_h t + ψ_h); `sines` the sin(ω_h t + ψ_h) when already computed."""
    sines = sines or [mp.sin(FREQ[h] * t + PHASE[h]) for h in range(2)]
    return sum(VECTORS[h][i] * amp[h] * sines[h] for h in range(2))


def flight(t0, y0):
    """The Taylor solution from (t0, y0 = [X1, X2, V1, V2]) of Ẍ_i + ω_i² X_i = F_i(t)."""
    om = [mp.mpf(w) for w in OMEGA]

    def rhs(t, y):
        # Each harmonic's sine once for both modes: odefun evaluates this at thousands of bits
        # (its Taylor coefficients come from differences), where the sines are most of its time.
        sines = [mp.sin(FREQ[h] * t + PHASE[h]) for h in range(2)]
        return [y[2], y[3], -om[0] ** 2 * y[0] + forcing(t, 0, sines=sines),
                -om[1] ** 2 * y[1] + forcing(t, 1, sines=sines)]

    return mp.odefun(rhs, t0, y0)


_REFERENCE = {}


def reference_impacts(t_end, count):
    """The first `count` impacts before t_end: times and velocities before, from rest at 0 (made
    once: the double and quad tests share it)."""
    if (t_end, count) not in _REFERENCE:
        _REFERENCE[(t_end, count)] = _reference_impacts(t_end, count)
    return _REFERENCE[(t_end, count)]


def _reference_impacts(t_end, count):
    mp.mp.dps = 30
    t0, y0 = mp.mpf(0), [mp.mpf(0)] * 4
    sol = flight(t0, y0)
    out, first_flight = [], sol
    dt = mp.mpf("0.01")
    while len(out) < count:
        def gap(t, sol=sol):
            y = sol(t)
            return y[0] + y[1] - X0
        a = t0 + dt / 100 if out else t0
        b = a + dt
        while gap(b) > 0:
            a, b = b, b + dt
            if b > t_end:
                return out, first_flight
        for _ in range(120):  # bisection to 30 digits
            m = (a + b) / 2
            if gap(m) > 0:
                a = m
            else:
                b = m
        ti = (a + b) / 2
        y = sol(ti)
        vB = y[2] + y[3]
        p = -(1 + mp.mpf(R)) * vB / sum(mp.mpf(x) for x in T_B)
        y1 = [y[0], y[1], y[2] + p * T_B[0], y[3] + p * T_B[1]]
        out.append((ti, vB))
        t0, y0 = ti, y1
        sol = flight(t0, y0)
    return out, first_flight


@pytest.mark.parametrize("precision, tol", [("double", 1e-12), ("quad", 4e-16)])
def test_two_harmonics_against_taylor_solver(tmp_path, precision, tol):
    """Double to 1e-12; the quad engine to the rounding of the times written (f64)."""
    mp.mp.dps = 30
    ev, smp, kinds = simulate(tmp_path, scene_text(periods=2, extra=f'precision = "{precision}"\n'))
    impacts = np.flatnonzero(ev["kind"] == kinds["impact"])
    assert impacts.size >= 3, "the scene was chosen to impact"
    ref, sol0 = reference_impacts(round(float(ev["t"][impacts[min(5, impacts.size - 1)]])) + 1, min(6, impacts.size))
    assert len(ref) >= 3
    for k, (ti, vB) in enumerate(ref):
        e = impacts[k]
        assert abs(ev["t"][e] - float(ti)) <= tol * max(1.0, float(ti)), (k, ev["t"][e], ti)
        assert abs(ev["v_before"][e] - float(vB)) <= 10 * tol * max(1.0, abs(float(vB))), (k, ev["v_before"][e], vB)
    # Between impacts: every sample of the first flight against the 30-digit solution.
    first = smp["t"] < float(ref[0][0])
    assert first.sum() >= 5
    for t, X, V in zip(smp["t"][first], smp["X"][first], smp["V"][first]):
        y = sol0(mp.mpf(t))
        assert np.allclose(X, [float(y[0]), float(y[1])], rtol=0, atol=2e-15)
        assert np.allclose(V, [float(y[2]), float(y[3])], rtol=0, atol=2e-15)


def closed_form(t, x0, v0, amp):
    """Ẍ_i + ω_i² X_i = Σ_h v_h,i f_h sin(ω_h t + ψ_h): Σ_h P_ih sin(ω_h t + ψ_h) + a_i cos ω_i t
    + b_i sin ω_i t, P_ih = v_h,i f_h/(ω_i² − ω_h²)."""
    X = np.zeros((len(t), 2))
    for i in range(2):
        P = [VECTORS[h][i] * amp[h] / (OMEGA[i] ** 2 - FREQ[h] ** 2) for h in range(2)]
        a = x0[i] - sum(P[h] * math.sin(PHASE[h]) for h in range(2))
        b = (v0[i] - sum(P[h] * FREQ[h] * math.cos(PHASE[h]) for h in range(2))) / OMEGA[i]
        X[:, i] = sum(P[h] * np.sin(FREQ[h] * t + PHASE[h]) for h in range(2)) + a * np.cos(OMEGA[i] * t) + \
            b * np.sin(OMEGA[i] * t)
    return X


def test_superposition(tmp_path):
    x0, v0 = [0.1, -0.05], [0.2, 0.1]
    far = -100.0  # no impact: one free flight
    _, both, _ = simulate(tmp_path, scene_text(stop=far, periods=3, initial=(x0, v0)), "both")
    _, first, _ = simulate(tmp_path, scene_text(amp=[AMP[0], 0.0], stop=far, periods=3, initial=(x0, v0)), "first")
    _, second, _ = simulate(tmp_path, scene_text(amp=[0.0, AMP[1]], stop=far, periods=3,
                                                 initial=([0.0, 0.0], [0.0, 0.0])), "second")
    assert np.array_equal(both["t"], first["t"]) and np.array_equal(both["t"], second["t"])
    scale = np.abs(both["X"]).max()
    np.testing.assert_allclose(both["X"], first["X"] + second["X"], rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(first["X"], closed_form(first["t"], x0, v0, [AMP[0], 0.0]), rtol=0,
                               atol=1e-12 * scale)
    np.testing.assert_allclose(second["X"], closed_form(second["t"], [0, 0], [0, 0], [0.0, AMP[1]]), rtol=0,
                               atol=1e-12 * scale)
    np.testing.assert_allclose(both["X"], closed_form(both["t"], x0, v0, AMP), rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("excitation, key, constraint", [
    ("amplitude = [1.0, 0.5]\nfrequency = [1.0, 2.0, 3.0]", "excitation.amplitude",
     "one entry per harmonic: 3 expected"),
    ("amplitude = [1.0, 0.5]\nfrequency = 1.0", "excitation.frequency", "a list of 2"),
    ("amplitude = [1.0, 0.5]\nfrequency = [1.0, -2.0]", "excitation.frequency[1]", "ω_1 > 0"),
    ("amplitude = [1.0, 0.5]\nfrequency = [1.0, 0.0]", "excitation.frequency[1]", "ω_1 > 0"),
    ("amplitude = [1.0, -0.5]\nfrequency = [1.0, 2.0]", "excitation.amplitude[1]", "f_1 ≥ 0"),
    ("amplitude = [1.0, 0.5]\nfrequency = [1.0, nan]", "excitation.frequency", "finite"),
    ("amplitude = [1.0, 0.5]\nfrequency = [1.0, 3.14159265358979]", "excitation.frequency",
     "commensurate"),
    ("amplitude = [1.0, 0.5]\nfrequency = [1.0, 2.0]\nphase = [0.0]", "excitation.phase",
     "one entry per harmonic: 2 expected"),
    ("amplitude = [1.0, 0.5]\nfrequency = [1.0, 2.0]\nvectors = [[1.0, 0.0, 2.0], [0.0, 1.0, 1.0]]",
     "excitation.vectors[0]", "one component per DOF or listed mode (2 expected, got 3)"),
    ("amplitude = [1.0, 0.5]\nfrequency = [1.0, 2.0]\nvectors = [[1.0, 0.0]]", "excitation.vectors",
     "one forcing vector (row) per harmonic: 2 rows expected, got 1"),
    ("amplitude = []\nfrequency = []", "excitation.amplitude", "a non-empty list"),
    # An empty forcing vector is no vector (it was taken for none: the forcing of structure.forcing).
    ("amplitude = [1.0]\nfrequency = [1.0]\nvectors = [[]]", "excitation.vectors", "row 0 is empty"),
    ("amplitude = [1.0, 0.5]\nfrequency = [1.0, 2.0]\nvectors = [[1.0, 0.0], []]", "excitation.vectors",
     "row 1 is empty"),
])
def test_located_errors(tmp_path, excitation, key, constraint):
    scene = tmp_path / "bad.toml"
    scene.write_text("[structure]\nfrequencies = [1.0, 2.7]\nforcing = [0.6, 0.4]\ncontact = [0.7, 0.3]\n"
                     "[stop]\nposition = -0.6\nrestitution = 0.8\n[excitation]\n" + excitation + "\n")
    out = tmp_path / "bad.h5"
    p = vibro("simulate", scene, "--out", out, code=2)
    assert not out.exists()
    line = next(m for m in p.stderr.splitlines() if key in m)
    assert line.startswith(f"{scene}:"), line  # file:line:col
    assert f"{scene}:9:" in line or f"{scene}:10:" in line or f"{scene}:11:" in line, line
    assert constraint in line, line


def shipped():
    return os.path.join(SCENES, "two_harmonics_chain2.toml")


def test_shipped_scene_simulates_and_checks(tmp_path):
    out = tmp_path / "run.h5"
    p = vibro("simulate", shipped(), "--out", out)
    assert "status       ok" in p.stdout
    with h5py.File(out, "r") as f:
        kinds = h5py.check_enum_dtype(f["events/kind"].dtype)
        assert (f["events/kind"][:] == kinds["impact"]).sum() > 10
        # No sample below the stop (the clearance 0.5 below x_B = 0).
        assert f["samples/x_B"][:].min() >= -0.5 - 1e-12
    vibro("check", shipped())  # the exact engine against CVODE: exit 4 if they disagree
    m = vibro("model", shipped()).stdout
    assert "harmonic 1" in m and "2·ω_b" in m


# An orbit of a commensurate two-harmonic forcing: Fig. 5's scene (x'' + x = f sin ωt, stop at
# x ≥ 1, r = 0.75, ω = 10) with a second harmonic at 2ω. The one-impact orbit of period T = 2π/ω
# solved here independently: from the impact at t_i (x = 1, ẋ = −rV), the closed-form flight of
# length T returns to x = 1 with ẋ = V.
ORBIT_R, ORBIT_W = mp.mpf("0.75"), mp.mpf(10)
ORBIT_F = [mp.mpf("1.1"), mp.mpf("0.15")]
ORBIT_M = [1, 2]
ORBIT_PSI = [mp.mpf(0), mp.mpf("0.3")]


def orbit_flight(t0, x0, v0, s):
    """x'' + x = Σ_h f_h sin(n_h ω t + ψ_h) from (x0, v0) at t0, after s: (x, x')."""
    U = [ORBIT_F[h] / (1 - (ORBIT_M[h] * ORBIT_W) ** 2) for h in range(2)]
    ph0 = [ORBIT_M[h] * ORBIT_W * t0 + ORBIT_PSI[h] for h in range(2)]
    ph1 = [ORBIT_M[h] * ORBIT_W * (t0 + s) + ORBIT_PSI[h] for h in range(2)]
    A = x0 - sum(U[h] * mp.sin(ph0[h]) for h in range(2))
    B = v0 - sum(U[h] * ORBIT_M[h] * ORBIT_W * mp.cos(ph0[h]) for h in range(2))
    return (A * mp.cos(s) + B * mp.sin(s) + sum(U[h] * mp.sin(ph1[h]) for h in range(2)),
            -A * mp.sin(s) + B * mp.cos(s) + sum(U[h] * ORBIT_M[h] * ORBIT_W * mp.cos(ph1[h]) for h in range(2)))


def orbit_truth(t_guess, v_guess):
    mp.mp.dps = 30
    T = 2 * mp.pi / ORBIT_W

    def residual(t, V):
        x, v = orbit_flight(t, 1, -ORBIT_R * V, T)
        return [x - 1, v - V]

    t, V = mp.findroot(residual, (mp.mpf(t_guess), mp.mpf(v_guess)))
    # The flight stays above the stop in between (else it is no one-impact orbit).
    for k in range(1, 400):
        assert orbit_flight(t, 1, -ORBIT_R * V, T * k / 400)[0] > 1
    return mp.fmod(t, T), V


def test_orbit_of_two_harmonics_against_periodic_solve(tmp_path):
    import json
    scene = tmp_path / "orbit.toml"
    scene.write_text(f"""[structure]
frequencies = [1.0]
forcing = [1.0]
contact = [1.0]
[stop]
position = 1.0
restitution = 0.75
[excitation]
amplitude = [1.1, 0.15]
frequency = [10.0, 20.0]
phase = [0.0, 0.3]
""")
    # The single harmonic's stable orbit (phase 1.135188, ẋ_B before −0.375077, docs/orbits.md) as the guess.
    t, V = orbit_truth(1.135188 / 10, -0.375077)
    p = vibro("orbit", scene, "--kind", "impact", "--guess", f"{float(t * ORBIT_W)},{float(-ORBIT_R * V)}",
              "--json")
    j = json.loads(p.stdout)
    assert j["status"] == "converged", j
    assert len(j["impact_phases"]) == 1, j
    assert abs(j["impact_phases"][0] - float(t * ORBIT_W)) <= 1e-10, (j["impact_phases"], t * ORBIT_W)
    assert abs(j["impact_velocities"][0] - float(V)) <= 1e-10, (j["impact_velocities"], V)
    # Found from a transient too (no guess), and stable as its multipliers say.
    j = json.loads(vibro("orbit", scene, "--kind", "impact", "--json").stdout)
    assert j["status"] == "converged" and abs(j["impact_phases"][0] - float(t * ORBIT_W)) <= 1e-10, j


def test_python_runs_the_shipped_scene_as_the_cli(tmp_path):
    """The package on the shipped scene: the same events as `vibro simulate`."""
    import vibro as pyvibro
    out = tmp_path / "cli.h5"
    vibro("simulate", shipped(), "--out", out, "--set", "run.periods=20")
    run = pyvibro.simulate(pyvibro.load_scene(shipped(), ["run.periods=20"]))
    with h5py.File(out, "r") as f:
        np.testing.assert_array_equal(run.events["t"], f["events/t"][:])
        np.testing.assert_array_equal(run.events["v_before"], f["events/v_before"][:])
    assert run.summary["status"] == "ok"


# One DOF held on its stop under a sum of harmonics: Fig. 8's preloaded oscillator (x'' + x =
# Σ f_h sin(ω_h t + ψ_h) − R, at rest on the stop x = 1, so R = 1 − Σ f_h sin(ω_h t + ψ_h)) with a
# second harmonic. Its release is searched by the engine (no closed form of the resting flow under
# a sum); CVODE had no sticking integrator for one DOF and crashed (SIGSEGV) in `simulate` with
# run.engine = "cvode" and in `vibro check` (issue 38's campaign, seed 48). Each engine's every
# release must be where the closed-form reaction vanishes and turns negative.
PRELOAD_SUM = """title = "Fig. 8's preload under two harmonics"
[structure]
frequencies = [1.0]
forcing     = [1.0]
contact     = [1.0]
[stop]
position    = 1.0
restitution = 0.75
[excitation]
amplitude = [1.2, 0.3]
frequency = [2.8, 5.6]
phase = [0.0, 0.5]
[initial]
displacement = [1.0]
velocity = [0.0]
[run]
periods = 12
"""


@pytest.mark.parametrize("engine", ["exact", "cvode"])
def test_one_dof_release_under_a_sum(tmp_path, engine):
    scene = tmp_path / "preload_sum.toml"
    scene.write_text(PRELOAD_SUM)
    out = tmp_path / f"{engine}.h5"
    vibro("simulate", scene, "--set", f'run.engine="{engine}"', "--out", out)
    with h5py.File(out, "r") as f:
        kinds = {v: k for k, v in h5py.check_enum_dtype(f["events/kind"].dtype).items()}
        t = f["events/t"][:]
        kind = [kinds[k] for k in f["events/kind"][:]]
    releases = [ti for ti, k in zip(t, kind) if k == "release"]
    assert len(releases) >= 10, kind[:20]
    mp.mp.dps = 30

    def R(s):
        return 1 - mp.mpf("1.2") * mp.sin(mp.mpf("2.8") * s) - mp.mpf("0.3") * mp.sin(mp.mpf("5.6") * s + mp.mpf("0.5"))

    tol = 1e-12 if engine == "exact" else 1e-7
    for ti in releases:
        s = mp.findroot(R, mp.mpf(ti))
        assert abs(s - ti) < tol, (engine, ti, s)
        assert mp.diff(R, s) < 0  # the reaction turns negative there: the body leaves the stop
    vibro("check", scene)  # the exact engine against CVODE (exit 4 if they disagree)
