"""`vibro curve` (docs/diagram.md, "Two-parameter curves") against independent truths written here in
mpmath, from closed-form free flights of one DOF and nothing of vibro:

(a) Fig. 8's end of sticking f_max(omega) (1-DOF preload, r = 0.75): the sticking-lost curve traced in
    (omega, f) passes within 1e-10 of f_max at three of its points, f_max computed here by an
    event-driven chattering simulation at 30 digits (release at sin(omega t1) = 1/f, flight, impacts
    v+ = -r v-, until the speeds fall below 1e-18, then the accumulation point) and bisection on "the
    sequence accumulates before the next release" (the sticking phase exists);
(b) r = 0: the flat-flight threshold f_ff(omega) of the paper, derived below, at every point of the
    traced curve within 1e-10 (relative), and checked here to be a first return;
(c) the symmetric two-sided oscillator (stops at -1 and +1, r = 0.8): the fold curve of its symmetric
    period-1 orbit, traced in (a, omega) from a fold stored by `vibro continue --out`, matches the
    discriminant of the closed form of the symmetric orbit within 1e-10 at every point, and there the
    symmetry-reduced impact map G (impact on +1 -> impact on -1, mirrored), computed here at 40 digits,
    has tr DG = 1 + r^2 (det DG = r^2: a multiplier +1);
(d) the HDF5 file holds the curves as the JSON says; bad input is refused (exit 2, nothing written);
(e) Python: vibro.curve returns numpy arrays, the same curve as the CLI.

Derivation of f_ff (preload, omega_1 = T_A = T_B = x0 = 1, r = 0). Sticking ends at the release
sin(phi1) = 1/f, cos(phi1) = sqrt(f^2 - 1)/f. From x = 1, x' = 0 at t1 the flight is
x = U sin(omega t) + A cos(t - t1) + B sin(t - t1), U = f/(1 - omega^2), A = 1 - U/f,
B = -U omega cos(phi1). The sticking phase shrinks to nothing when the (plastic) landing falls on the
next release, x(t1 + T) = 1 with T = 2 pi/omega: U/f + A cos T + B sin T = 1, i.e.
(1 - U/f)(1 - cos T) = B sin T. With 1 - U/f = -omega^2/(1 - omega^2) and
B = -omega sqrt(f^2 - 1)/(1 - omega^2): sqrt(f^2 - 1) = omega (1 - cos T)/sin T = omega tan(pi/omega),
valid where tan(pi/omega) > 0 (omega > 2 for period 1).
"""
import json
import math
import os
import subprocess

import h5py
import mpmath as mp
import numpy as np
import pytest

CLI = os.environ.get("VIBRO_CLI", "")
HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.join(HERE, "..", "..", "data", "scenes")
FIG08 = os.path.join(SCENES, "fig08_preload.toml")
TWO_SIDED = os.path.join(SCENES, "contacts_two_sided_1dof.toml")
TWO_SIDED_SETS = ["--set", "contact[0].restitution=0.8", "--set", "contact[1].restitution=0.8",
                  "--set", "excitation.frequency=2.5", "--set", "excitation.amplitude=1.0",
                  "--set", "initial.velocity=[2.0]"]


def vibro(*args, check=True):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=1800)
    if check:
        assert p.returncode == 0, p.stderr
    return p


# ---- (a) f_max of the 1-DOF preload oscillator with chattering (r = 0.75) ----

def s3(w, s):
    """sin(w s) - w sin(s), by its series where the two terms cancel (|s| < 1e-3)."""
    if abs(s) > mp.mpf("1e-3"):
        return mp.sin(w * s) - w * mp.sin(s)
    tw, t1, tot, k = w * s, s, mp.mpf(0), 1
    eps = mp.mpf(10) ** (-mp.mp.dps - 5)
    while True:
        tw *= -(w * s) ** 2 / ((2 * k) * (2 * k + 1))
        t1 *= -s**2 / ((2 * k) * (2 * k + 1))
        term = tw - w * t1
        tot += term
        if abs(term) <= eps * abs(tot):
            return tot
        k += 1


def flight_preload(f, w, t0, v0, s):
    """x'' + x = f sin(w t) from x = 1, x' = v0 at t0: (x - 1, x') after a time s, by Duhamel's integral
    written without cancellation (near the stop x - 1 is O(v0 s) while x is O(1))."""
    U = f / (1 - w**2)
    sw, cw = mp.sin(w * t0), mp.cos(w * t0)
    prod = mp.sin((w + 1) * s / 2) * mp.sin((w - 1) * s / 2)  # (cos s - cos ws)/2
    x = -2 * mp.sin(s / 2) ** 2 + v0 * mp.sin(s) + U * (-2 * sw * prod + cw * s3(w, s))
    v = -mp.sin(s) + v0 * mp.cos(s) + U * (sw * (mp.sin(s) - w * mp.sin(w * s)) - 2 * w * cw * prod)
    return x, v


def root(g, lo, hi):
    """The root of g in [lo, hi] (g(lo) > 0 > g(hi)): Illinois, bisection when it does not converge."""
    try:
        return mp.findroot(g, (lo, hi), solver="illinois")
    except ValueError:
        for _ in range(200):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if g(mid) > 0 else (lo, mid)
        return (lo + hi) / 2


def sticks(f, w, r):
    """True when the flight after the release at sin(w t1) = 1/f chatters to rest before the next
    release t1 + T, so that the period-1 sticking orbit exists."""
    T = 2 * mp.pi / w
    t1 = mp.asin(1 / f) / w
    end = t1 + T
    n = 200
    for k in range(1, n + 1):
        if flight_preload(f, w, t1, 0, T * k / n)[0] < 0:
            break
    else:
        return False
    s = mp.findroot(lambda s: flight_preload(f, w, t1, 0, s)[0], (T * (k - 1) / n, T * k / n), solver="anderson")
    t, v = t1 + s, -r * flight_preload(f, w, t1, 0, s)[1]
    for _ in range(5000):
        a = 1 - f * mp.sin(w * t)  # the pull onto the stop at rest: the reaction
        if t >= end or a <= 0:
            return False
        guess = 2 * v / a
        if v < mp.mpf("1e-18"):
            return t + guess / (1 - r) < end  # the rest of the sequence: a geometric series
        g = lambda s: flight_preload(f, w, t, v, s)[0] / s
        lo, hi = guess / 2, guess * 1.5
        while g(hi) > 0:
            hi *= 2
            if hi > T:
                return False
        while g(lo) < 0:
            lo /= 2
        s = root(g, lo, hi)
        t, v = t + s, -r * flight_preload(f, w, t, v, s)[1]
    return False


def f_max(w, lo, hi, r):
    """Bisection of f on sticks() inside [lo, hi], checked to bracket the end of sticking."""
    with mp.workdps(30):
        w, lo, hi, r = mp.mpf(w), mp.mpf(lo), mp.mpf(hi), mp.mpf(r)
        assert sticks(lo, w, r) and not sticks(hi, w, r), "not a bracket of f_max"
        while hi - lo > mp.mpf("1e-13"):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if sticks(mid, w, r) else (lo, mid)
        return float((lo + hi) / 2)


def test_fig08_end_of_sticking_curve(tmp_path):
    out = tmp_path / "fmax.h5"
    p = vibro("curve", FIG08, "--param", "excitation.frequency,excitation.amplitude", "--kind", "sticking-lost",
              "--range1", "1.5,10", "--range2", "1,1.5", "--toward", "2.8,1.5", "--json", "--out", out)
    c = json.loads(p.stdout)["curves"][0]
    assert c["kind"] == "sticking-lost" and c["status"] == "ok"
    pts = c["points"]
    w = np.array([q["value1"] for q in pts])
    f = np.array([q["value2"] for q in pts])
    assert w.min() < 1.6 and w.max() > 9.9, (w.min(), w.max())  # the whole box
    assert np.all(np.diff(w) != 0)
    # the traced curve at three of its points, against f_max computed here
    for target in (2.0, 4.5, 9.0):
        i = int(np.argmin(abs(w - target)))
        truth = f_max(w[i], f[i] - 1e-9, f[i] + 1e-9, "0.75")
        assert abs(f[i] - truth) < 1e-10, (w[i], f[i], truth)
    with h5py.File(out, "r") as h:
        g = h["curves/000"]
        assert g.attrs["kind"] in (b"sticking-lost", "sticking-lost")
        assert np.array_equal(g["value1"][:], w) and np.array_equal(g["value2"][:], f)
        assert h["curves"].attrs["count"] == 1
        assert g["X"].shape == (len(w), 1)


# ---- (b) r = 0: the flat-flight threshold ----

def f_ff(w):
    return math.sqrt(1 + (w * math.tan(math.pi / w)) ** 2)


def test_flat_flight_threshold_r0():
    p = vibro("curve", FIG08, "--set", "stop.restitution=0", "--param", "excitation.frequency,excitation.amplitude",
              "--kind", "sticking-lost", "--range1", "2.2,20", "--range2", "1,12", "--toward", "2.8,8", "--json")
    c = json.loads(p.stdout)["curves"][0]
    pts = c["points"]
    assert len(pts) > 20
    w = np.array([q["value1"] for q in pts])
    f = np.array([q["value2"] for q in pts])
    assert w.max() > 19.9 and w.min() < 2.35  # from the edge ω = 20 to where f_ff leaves the box (f = 12)
    err = np.abs(f - np.array([f_ff(x) for x in w])) / f
    assert err.max() < 1e-10, (err.max(), w[err.argmax()])
    # the closed form is a first return: the flight from the release stays above the stop until T
    with mp.workdps(30):
        for x in (w[0], w[len(w) // 2], w[-1]):
            x = mp.mpf(x)
            ff = mp.sqrt(1 + (x * mp.tan(mp.pi / x)) ** 2)
            T, t1 = 2 * mp.pi / x, mp.asin(1 / ff) / x
            assert abs(flight_preload(ff, x, t1, 0, T)[0]) < mp.mpf("1e-25")
            assert all(flight_preload(ff, x, t1, 0, T * k / 400)[0] > 0 for k in range(1, 400))


# ---- (c) the fold of the symmetric orbit of the two-sided oscillator ----

R2 = mp.mpf("0.8")


def fold_amplitude(w, r=R2, delta=1):
    """The closed form of the symmetric period-1 orbit (impact at +1 at phase phi, arrival speed V,
    exactly T/2 of flight to -1): matching the flight at T/2 gives U sin(phi) = 1 - k1 V,
    U cos(phi) = k2 V, k1 = (1 + r) tan(pi/(2 omega))/2, k2 = (1 - r)/(2 omega), U = a/(1 - omega^2);
    so (k1^2 + k2^2) V^2 - 2 k1 V + 1 - U^2 = 0, whose two orbits merge (the fold) where the
    discriminant vanishes: U^2 = k2^2/(k1^2 + k2^2). Returns (a, phi, V) there."""
    w = mp.mpf(w)
    k1 = (1 + r) * mp.tan(mp.pi / (2 * w)) / 2
    k2 = (1 - r) / (2 * w)
    U = -delta * k2 / mp.sqrt(k1**2 + k2**2)  # U < 0 for omega > 1 (a > 0)
    V = delta * k1 / (k1**2 + k2**2)
    phi = mp.atan2((delta - k1 * V) / U, k2 * V / U)
    return U * (1 - w**2), phi, V


def reduced_map(a, w, r, t, u):
    """G: the state just after an impact on +1 at time t with velocity u < 0 -> the next impact on -1,
    mirrored (x -> -x, t -> t - T/2): (t', r * arrival velocity)."""
    U = a / (1 - w**2)
    A = 1 - U * mp.sin(w * t)
    B = u - U * w * mp.cos(w * t)
    x = lambda s: A * mp.cos(s) + B * mp.sin(s) + U * mp.sin(w * (t + s))
    v = lambda s: -A * mp.sin(s) + B * mp.cos(s) + U * w * mp.cos(w * (t + s))
    s = mp.findroot(lambda s: x(s) + 1, mp.pi / w)
    return t + s - mp.pi / w, r * v(s)


def test_two_sided_fold_curve(tmp_path):
    branch = tmp_path / "branch.h5"
    vibro("continue", TWO_SIDED, *TWO_SIDED_SETS, "--param", "excitation.amplitude", "--to", "0.2", "--out", branch)
    with h5py.File(branch, "r") as h:
        kinds = [k.decode() if isinstance(k, bytes) else k for k in h["bifurcations/kind"][:]]
    k = kinds.index("fold")
    p = vibro("curve", TWO_SIDED, *TWO_SIDED_SETS, "--param", "excitation.amplitude,excitation.frequency",
              "--from", branch, "--point", k, "--range1", "0,3", "--range2", "1.5,4", "--json")
    c = json.loads(p.stdout)["curves"][0]
    assert c["kind"] == "fold"
    pts = c["points"]
    assert len(pts) > 8
    a = np.array([q["value1"] for q in pts])
    w = np.array([q["value2"] for q in pts])
    assert w.min() < 1.6 and w.max() > 3.9  # across the box in omega
    with mp.workdps(40):
        for ai, wi in zip(a, w):
            truth, phi, V = fold_amplitude(wi)
            assert abs(ai - float(truth)) < 1e-10, (wi, ai, truth)
        # the symmetry-reduced map: the closed-form orbit is its fixed point, and tr DG = 1 + r^2 there
        for wi in (w[0], w[len(w) // 2], w[-1]):
            wm = mp.mpf(wi)
            am, phi, V = fold_amplitude(wm)
            t0, u0 = phi / wm, -R2 * V
            t1, u1 = reduced_map(am, wm, R2, t0, u0)
            assert abs(t1 - t0) < mp.mpf("1e-30") and abs(u1 - u0) < mp.mpf("1e-30")
            h = mp.mpf("1e-12")
            cols = []
            for dt, du in ((h, 0), (0, h)):
                pl = reduced_map(am, wm, R2, t0 + dt, u0 + du)
                mi = reduced_map(am, wm, R2, t0 - dt, u0 - du)
                cols.append([(pl[0] - mi[0]) / (2 * h), (pl[1] - mi[1]) / (2 * h)])
            tr = cols[0][0] + cols[1][1]
            det = cols[0][0] * cols[1][1] - cols[1][0] * cols[0][1]
            assert abs(tr - (1 + R2**2)) < mp.mpf("1e-15"), tr
            assert abs(det - R2**2) < mp.mpf("1e-15"), det


# ---- (d) bad input ----

@pytest.mark.parametrize("args, where", [
    (["--param", "excitation.frequency", "--kind", "fold", "--toward", "1,1"], "--param"),
    (["--param", "excitation.frequency,excitation.nothing", "--kind", "fold", "--toward", "1,1"], "excitation.nothing"),
    (["--param", "excitation.frequency,excitation.amplitude", "--kind", "wobble", "--toward", "1,1"], "--kind wobble"),
    (["--param", "excitation.frequency,excitation.amplitude", "--kind", "fold"], "--toward"),
    (["--param", "excitation.frequency,excitation.amplitude", "--kind", "fold", "--toward", "1,1", "--step", "0"], "--step"),
])
def test_bad_input(tmp_path, args, where):
    out = tmp_path / "bad.h5"
    base = ["curve", FIG08, "--range1", "1,20", "--range2", "1,2", "--out", out]
    p = vibro(*base, *args, check=False)
    assert p.returncode == 2, p.stderr
    assert where in p.stderr
    assert not out.exists()


def test_range_refused(tmp_path):
    p = vibro("curve", FIG08, "--param", "excitation.frequency,excitation.amplitude", "--kind", "fold", "--toward", "3,1",
              "--range1", "5,1", "--range2", "1,2", check=False)
    assert p.returncode == 2 and "--range1" in p.stderr


# ---- (e) Python ----

def test_python_curve_matches_cli():
    vibro_mod = pytest.importorskip("vibro")
    p = vibro("curve", FIG08, "--set", "stop.restitution=0", "--param", "excitation.frequency,excitation.amplitude",
              "--kind", "sticking-lost", "--range1", "4,10", "--range2", "1,12", "--toward", "5,8", "--json")
    cli = json.loads(p.stdout)["curves"][0]
    scene = vibro_mod.load_scene(FIG08, set=["stop.restitution=0"])
    curves = vibro_mod.curve(scene, ("excitation.frequency", "excitation.amplitude"), (4, 10), (1, 12),
                             kind="sticking-lost", toward=(5, 8))
    c = curves[0]
    assert c["kind"] == "sticking-lost"
    assert isinstance(c["value1"], np.ndarray) and isinstance(c["value2"], np.ndarray)
    assert np.array_equal(c["value1"], [q["value1"] for q in cli["points"]])
    assert np.array_equal(c["value2"], [q["value2"] for q in cli["points"]])
    err = np.abs(c["value2"] - np.array([f_ff(x) for x in c["value1"]])) / c["value2"]
    assert err.max() < 1e-10
