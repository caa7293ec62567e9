"""Contact loads along a continued branch of a compliant stop (docs/compliant.md, "Along a continued
branch"), against the truth of tests/python/test_compliant_orbit.py, written without vibro's code:
the return map of mpmath's Taylor ODE solver at 30 digits, phase by phase, each entry and exit by
bisection, the peak force from λ' = 0, the impulse and the dashpot's energy by mpmath.quad.

The scene: test_compliant_orbit's one-DOF structure (unit mass, ζ = 0.05, F = 0.5 sin ωt) on a
spring–dashpot stop at −0.5 (k = 400, c = 2), both separation rules, continued in ω from 0.8 to 1.0
(the peak force falls from 15.8 to 14.7 near ω = 0.9, then rises). At the first, a middle and the
last point of the branch, from the point's stored section state (/branch/section_time, X, V):

* the state is a fixed point of the reference's map at that ω (to Newton's 1e-12);
* each contact phase of the point (vibro.continue_()["points"][i]["contact_phases"]): entry and exit
  to 1e-12, peak force, penetration, impulse and dissipated energy to 1e-13 relative;
* ``contact_phases["peak_force"]`` and ``["duration"]`` (per contact) are the largest of them, and
  the HDF5 file's /branch/contact_phases holds the same numbers as the JSON; the CLI's --json equals
  the Python dict.

A rigid scene's branch has none of these keys (its outputs unchanged).
"""
import json
import os
import subprocess

import h5py
import mpmath as mp
import numpy as np
import pytest

vibro = pytest.importorskip("vibro")

from test_compliant_orbit import Ref, return_map, scene_text  # noqa: E402  (the same reference)


@pytest.fixture(autouse=True)
def _keep_mpmath_precision():
    dps = mp.mp.dps
    yield
    mp.mp.dps = dps


@pytest.mark.parametrize("rule", ["force", "gap"])
def test_branch_contact_phases_against_taylor_return_map(tmp_path, rule):
    path = tmp_path / f"{rule}.toml"
    path.write_text(scene_text(rule))
    out = tmp_path / f"{rule}.h5"
    b = vibro.continue_(vibro.load_scene(str(path)), "excitation.frequency", 1.0, out=str(out))
    pts = b["points"]
    assert b["end"] == "reached the end value" and len(pts) > 5, b["end"]
    cp = b["contact_phases"]
    with h5py.File(out, "r") as f:
        g = f["/branch"]
        t0s, Xs, Vs = g["section_time"][:], g["X"][:], g["V"][:]
        h = f["/branch/contact_phases"]
        np.testing.assert_array_equal(h["peak_force"][:], cp["peak_force"])
        np.testing.assert_array_equal(h["duration"][:], cp["duration"])
        np.testing.assert_array_equal(h["phases"][:], cp["phases"])
        np.testing.assert_array_equal(h["rigid_distance"][:], cp["rigid_distance"])
        offsets = h["offsets"][:]
        for i, p in enumerate(pts):
            rows = range(offsets[i], offsets[i + 1])
            assert [h["phase_peak_force"][r] for r in rows] == [c["peak_force"] for c in p["contact_phases"]]
            assert [h["phase_duration"][r] for r in rows] == [c["duration"] for c in p["contact_phases"]]
    worst = 0.0
    for i in (0, len(pts) // 2, len(pts) - 1):
        p = pts[i]
        omega = p["value"]
        mp.mp.dps = 30
        ref = Ref(rule, freq=mp.mpf(omega))
        z = [mp.mpf(float(Xs[i][0])), mp.mpf(float(Vs[i][0]))]
        Pz, phases = return_map(mp.mpf(float(t0s[i])), z, ref, periods=b["period"], loads=True)
        scale = max(abs(z[0]), abs(z[1]))
        assert max(abs(Pz[k] - z[k]) for k in range(2)) <= 1e-12 * (1 + scale), (omega, Pz, z)
        got = p["contact_phases"]
        assert len(got) == len(phases) == 1, (got, phases)
        for c, r in zip(got, phases):
            assert abs(c["entry"] - float(r["entry"])) <= 1e-12 * abs(float(r["entry"]))
            assert abs(c["exit"] - float(r["exit"])) <= 1e-12 * abs(float(r["exit"]))
            assert abs(c["duration"] - float(r["exit"] - r["entry"])) <= 1e-11 * float(r["exit"] - r["entry"])
            for key in ("peak_force", "penetration", "impulse", "energy_dissipated"):
                want = float(r[key])
                err = abs(c[key] - want) / abs(want)
                worst = max(worst, err)
                assert err <= 1e-13, (omega, key, c[key], want)
        assert cp["peak_force"][i, 0] == max(c["peak_force"] for c in got)
        assert cp["duration"][i, 0] == max(c["duration"] for c in got)
        assert cp["phases"][i, 0] == len(got)
        # The same point's long-run keys as numpy arrays (vibro.COMPLIANT_LOAD_FIELDS): one phase per
        # period, so its mean peak force and duration are that phase's, checked above against the
        # reference; NaN nowhere.
        ld = b["loads"]
        assert ld["contact_phases_per_period"][i, 0] == len(got) / b["period"]
        assert abs(ld["peak_force_mean"][i, 0] - float(phases[0]["peak_force"])) <= 1e-13 * ld["peak_force_mean"][i, 0]
        assert abs(ld["peak_force_max"][i, 0] - float(phases[0]["peak_force"])) <= 1e-13 * ld["peak_force_max"][i, 0]
        want_d = float(phases[0]["exit"] - phases[0]["entry"])
        assert abs(ld["contact_duration_mean"][i, 0] - want_d) <= 1e-11 * want_d
    for k in vibro.COMPLIANT_LOAD_FIELDS:
        assert b["loads"][k].shape == (len(pts), 1) and not np.isnan(b["loads"][k]).any(), k
        assert list(b["loads"][k][:, 0]) == [q["loads"][0][k] for q in pts], k
        # The rigid model's orbit beside it: found at every point of this branch, within the clearance.
        assert 0 < cp["rigid_distance"][i] < 0.5, cp["rigid_distance"][i]
    print(f"{rule}: loads along the branch within {worst:.2g} of the 30-digit reference")


def test_branch_json_equals_cli_and_rigid_unchanged(tmp_path):
    cli = os.environ.get("VIBRO_CLI", "")
    if not cli:
        pytest.skip("VIBRO_CLI is not set")
    scene = tmp_path / "s.toml"
    scene.write_text(scene_text("force"))
    got = vibro.continue_(vibro.load_scene(str(scene)), "excitation.frequency", 0.85)
    p = subprocess.run([cli, "continue", str(scene), "--param", "excitation.frequency", "--to", "0.85", "--json"],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    want = json.loads(p.stdout)
    assert got["points"] == want["points"]
    t = subprocess.run([cli, "continue", str(scene), "--param", "excitation.frequency", "--to", "0.85"],
                       capture_output=True, text=True, timeout=600)
    assert t.returncode == 0 and "peak_force" in t.stdout and "rigid_dist" in t.stdout, t.stdout
    # A rigid stop: no contact phases, no new keys or columns.
    rigid = tmp_path / "r.toml"
    rigid.write_text(scene_text("force").replace("stiffness = 400.0\ndamping = 2.0\nseparation = \"force\"\n",
                                                 "restitution = 0.8\n"))
    r = vibro.continue_(vibro.load_scene(str(rigid)), "excitation.frequency", 0.85)
    assert "contact_phases" not in r and all("contact_phases" not in q and "rigid_distance" not in q
                                             for q in r["points"])
    assert set(r["loads"]) == set(vibro.LOAD_FIELDS)
    t = subprocess.run([cli, "continue", str(rigid), "--param", "excitation.frequency", "--to", "0.85"],
                       capture_output=True, text=True, timeout=600)
    assert t.returncode == 0 and "peak_force" not in t.stdout, t.stdout


def test_orbit_file_holds_contact_phases(tmp_path):
    """`vibro orbit --out` (vibro.orbit(out=...)) stores the orbit's contact phases in
    /orbit/contact_phases, the JSON's numbers."""
    path = tmp_path / "s.toml"
    path.write_text(scene_text("force"))
    out = tmp_path / "o.h5"
    o = vibro.orbit(vibro.load_scene(str(path)), out=str(out))
    assert o["attractor_kind"] == "contact-periodic"
    with h5py.File(out, "r") as f:
        g = f["/orbit/contact_phases"]
        for key in ("contact", "entry", "exit", "duration", "entry_velocity", "exit_velocity", "peak_force",
                    "peak_time", "penetration", "impulse", "energy_dissipated"):
            assert list(g[key][:]) == [p[key] for p in o["contact_phases"]], key


def test_branch_in_the_stiffness_approaches_the_rigid_model():
    """Continued in the stop's stiffness (k = 400 to 40000, c = 2), the orbit's distance to the rigid
    model's orbit beside it (restitution e(ζ) of each point's ζ = c/(2√k)) falls like k^(−1/2), the
    rate of docs/loads.md's convergence (the penetration scales as v/ω_c): the fitted slope over the
    last decade in log-log, and the peak force grows like √k (F_max ≈ √(k m) v for a small ζ)."""
    import tempfile
    with tempfile.TemporaryDirectory() as work:
        path = os.path.join(work, "s.toml")
        with open(path, "w") as f:
            f.write(scene_text("force"))
        b = vibro.continue_(vibro.load_scene(path), "stop.stiffness", 40000.0)
    assert b["end"] == "reached the end value", b["end"]
    k = np.array([p["value"] for p in b["points"]])
    d = b["contact_phases"]["rigid_distance"]
    peak = b["contact_phases"]["peak_force"][:, 0]
    assert np.all(np.isfinite(d)) and np.all(np.diff(d) < 0), d
    last = k >= 4000
    slope = np.polyfit(np.log(k[last]), np.log(d[last]), 1)[0]
    assert abs(slope + 0.5) < 0.05, slope
    slope_peak = np.polyfit(np.log(k[last]), np.log(peak[last]), 1)[0]
    assert abs(slope_peak - 0.5) < 0.1, slope_peak
    print(f"distance slope {slope:.3f}, peak-force slope {slope_peak:.3f}")


def _two_harmonic_tube(frequency="0.9"):
    """tube_compliant_support.toml under two harmonics (docs/compliant.md, "Along a continued
    branch"): amplitude [0.3, 0.1], phase [0.0, 0.5], frequency [ω, 2ω]."""
    base = open(os.path.join(os.environ.get("VIBRO_SCENES", os.path.join(os.path.dirname(__file__), "..", "..",
                                                                           "data", "scenes")),
                             "tube_compliant_support.toml")).read()
    second = repr(2 * float(frequency))
    text = base.replace("\namplitude = 0.3\n", "\namplitude = [0.3, 0.1]\nphase = [0.0, 0.5]\n") \
               .replace("\nfrequency = 0.9\n", f"\nfrequency = [{frequency}, {second}]\n")
    assert text != base and text.count("[0.3, 0.1]") == 1 and text.count(f"[{frequency}, {second}]") == 1
    return text


def test_rigid_model_followed_along_a_two_harmonic_branch(tmp_path):
    """The rigid model beside a branch is followed from point to point (docs/compliant.md, "Along a
    continued branch"). On the tube of tube_compliant_support.toml under two harmonics, Newton from
    the compliant section state alone reached, when phases were compared mod 2π, an image of the rigid
    orbit beside it (the same orbit met at the section a forcing period later, distance 0.10) at 9 of
    38 points and none at 11, on a compliant branch that is smooth throughout
    (test_rigid_model_beside_against_an_independent_reference). Followed from the previous point,
    every point has the near one: a distance at every point, continuous in ω (consecutive values
    within 1e-3, where the old selection jumped by 0.085), 0.0169 at ω = 0.9 as `vibro orbit` gives."""
    path = tmp_path / "tube2h.toml"
    path.write_text(_two_harmonic_tube())
    b = vibro.continue_(vibro.load_scene(str(path)), "excitation.frequency", 0.9015)
    d = b["contact_phases"]["rigid_distance"]
    values = [p["value"] for p in b["points"]]
    assert len(d) == len(values) > 30 and values[-1] == 0.9015, (len(d), values[-1])
    assert np.isfinite(d).all(), [(v, x) for v, x in zip(values, d) if not np.isfinite(x)]
    assert np.abs(np.diff(d)).max() < 1e-3, np.abs(np.diff(d)).max()
    assert 0.0168 < d.min() and d.max() < 0.0175, (d.min(), d.max())
    o = vibro.orbit(vibro.load_scene(str(path)))
    assert abs(o["rigid_model"]["distance"]["max"] - d[0]) <= 1e-9, (o["rigid_model"]["distance"], d[0])


def _compliant_samples(text, t0, q0, v0, omega, periods, path):
    """vibro's dense samples of the compliant orbit from its section state (the instants of
    src/studies/rigid_model.cpp's distance: t0 + i T/1024 over the orbit's periods)."""
    import re
    sc = re.sub(r"\[initial\].*?\n\n", f"[initial]\ntime = {t0!r}\ndisplacement = [{q0[0]!r}, {q0[1]!r}]\n"
                f"velocity = [{v0[0]!r}, {v0[1]!r}]\n\n", text, flags=re.S)
    sc = re.sub(r"^frequency = \[[^\]]*\]", f"frequency = [{omega!r}, {2 * omega!r}]", sc, flags=re.M)
    sc = sc.replace("\nperiods = 200", f"\nperiods = {periods}\nsamples_per_period = 1024")
    assert sc.count(f"periods = {periods}\n") == 1 and sc.count(f"time = {t0!r}") == 1
    path.write_text(sc)
    return vibro.simulate(vibro.load_scene(str(path)))


def test_rigid_model_beside_against_an_independent_reference(tmp_path):
    """The rigid model beside the two-harmonic tube's branch (docs/compliant.md, "Along a continued
    branch") against tests/python/rigid_stops_reference.py, written without vibro's code: the rigid
    scene's exact flow (eigen-decomposition plus one particular solution per harmonic), impacts
    bisected to the last bit on a grid of T/2048 (checked by a grid 4 times finer), Newton on the
    period-4 stroboscopic map from the compliant section state, from the end of a rigid transient and
    from perturbed starts, and every orbit's images under P, P², P³ (the same closed curve through the
    section at another forcing period: also a fixed point of P⁴).

    The restitution of each stop is e(ζ) of the "force" rule, ζ = c/(2√(k m)), m = 1/W_jj = 1 (DOF 1
    of M = diag(2, 1)), computed by the reference from the contact phase's closed form and compared
    with the docs' formula and vibro's. The reference finds one rigid orbit and its three images at
    every point checked; only one of the four is beside the compliant orbit (one impact per contact
    phase on each contact, each impact inside its contact phase widened by the phase's duration on
    either side, in time over the orbit's 4 periods); the images have 5 and 4 impacts on the two
    contacts too, and their impacts fall inside the widened phases modulo one forcing period, at
    distances 0.094 to 0.117 (the "far orbit at 0.10" of the old selection). At points of the branch
    from 0.9 up to 0.9015 and of the branch from 0.9015 down to 0.9 — whose first point has no
    previous point to follow — vibro's rigid_distance
    is the reference's distance to the orbit beside (the max over the same sample instants of the
    physical DOFs' difference, the compliant orbit from vibro's samples), within 1e-9 relative; the
    measured agreement is 3.4e-12 relative or better (the images' distances 0.094 to 0.098).

    On 6403c6d, where "beside" compared forcing phases mod 2π, the branch from 0.9015 read 0.0979931 at
    its first point: the distance to an image (Newton from the compliant state reaches it there, and
    no previous point gives the orbit beside), and this test failed there (relative error 4.6)."""
    import math
    from rigid_stops_reference import Rigid, restitution_force_rule

    k, c = 1000.0, 2.0
    M, K = np.array([[2.0, 0.0], [0.0, 1.0]]), np.array([[4.0, -1.0], [-1.0, 1.0]])
    W11 = np.linalg.inv(M)[1, 1]
    zeta = c / (2 * math.sqrt(k / W11))
    e, _ = restitution_force_rule(zeta)
    s = math.sqrt(1 - zeta * zeta)
    assert abs(e - math.exp(-zeta / s * (math.pi - math.atan2(2 * zeta * s, 1 - 2 * zeta * zeta)))) <= 1e-14
    period = 4
    checked, worst = [], 0.0
    for start, to, picks in (("0.9", 0.9015, (0, 20, -1)), ("0.9015", 0.9, (0, 20))):
        text = _two_harmonic_tube(start)
        path = tmp_path / f"tube2h_{start}.toml"
        path.write_text(text)
        scene = vibro.load_scene(str(path))
        out = tmp_path / f"branch_{start}.h5"
        b = vibro.continue_(scene, "excitation.frequency", to, out=str(out))
        assert b["end"] == "reached the end value" and b["period"] == period, (b["end"], b["period"])
        d = b["contact_phases"]["rigid_distance"]
        with h5py.File(out, "r") as f:
            t0s, Xs, Vs = f["/branch/section_time"][:], f["/branch/X"][:], f["/branch/V"][:]
        model = vibro.model(scene)
        # vibro's restitution of each stop (its rigid model), the reference's e(ζ).
        assert np.abs(np.array(vibro.orbit(scene)["rigid_model"]["restitution"]) - e).max() <= 1e-14
        # The modal coordinates' shapes (rows): K φ = ω² M φ, the physical state q = Σ X_i φ_i.
        shapes = np.array(model["mode_shapes"])
        for w, phi in zip(model["frequencies"], shapes):
            assert np.abs(K @ phi - w * w * M @ phi).max() <= 1e-12
        for i in picks:
            i = i % len(b["points"])
            pt = b["points"][i]
            omega, t0 = pt["value"], float(t0s[i])
            q0, v0 = Xs[i] @ shapes, Vs[i] @ shapes
            ref = Rigid(M, K, [0.02, 0.02], [1.0, 0.0], [0.3, 0.1], [1, 2], [0.0, 0.5], omega,
                        [([0.0, 1.0], -0.1, e), ([0.0, -1.0], -0.1, e)])
            run = _compliant_samples(text, t0, q0, v0, omega, period, tmp_path / "compliant.toml")
            ts, qc = run.samples["t"], run.samples["X"] @ shapes
            assert len(ts) == 1024 * period and abs(ts[0] - t0) <= 1e-12 * t0
            assert np.abs(ts - (t0 + np.arange(len(ts)) * ref.T / 1024)).max() <= 1e-10
            sec = run.section["X"]
            assert np.abs(sec[-1] - sec[0]).max() <= 1e-10  # the compliant orbit closes
            z0 = np.concatenate([q0, v0])
            rng = np.random.default_rng(43)
            found = ref.orbits_from(t0, [z0] + [z0 + rng.normal(0.0, 0.02, 4) for _ in range(2)], period)
            phases = pt["contact_phases"]
            counts = [sum(p["contact"] == j for p in phases) for j in (0, 1)]
            span = period * ref.T
            beside, images = [], []
            for z, res in found:
                assert res <= 1e-11, res
                impacts, segments, _ = ref.run(t0, z, t0 + span)
                dist = np.abs(ref.states_at(segments, ts)[:, :2] - qc).max()

                def inside(ti, j, modulo):
                    return any(p["contact"] == j and
                               (ti - (p["entry"] - p["duration"])) % modulo <= p["exit"] - p["entry"] + 2 * p["duration"]
                               for p in phases)

                same_counts = [sum(j == a for _, j, _ in impacts) for a in (0, 1)] == counts
                if same_counts and all(inside(ti, j, span) for ti, j, _ in impacts):
                    beside.append((dist, z, impacts))
                elif same_counts and all(inside(ti, j, ref.T) for ti, j, _ in impacts):
                    images.append(dist)
            assert len(beside) == 1, (omega, [x[0] for x in beside])
            want, z, impacts = beside[0]
            # The grid is fine enough: 4 times finer, the same impacts to the bit.
            if not checked:
                fine = Rigid(M, K, [0.02, 0.02], [1.0, 0.0], [0.3, 0.1], [1, 2], [0.0, 0.5], omega,
                             [([0.0, 1.0], -0.1, e), ([0.0, -1.0], -0.1, e)], h=ref.T / 8192)
                again = fine.run(t0, z, t0 + span)[0]
                assert [(a, j) for a, j, _ in again] == [(a, j) for a, j, _ in impacts]
            assert images and min(images) > 0.09, images
            assert all(abs(d[i] - x) > 0.07 for x in images), (omega, d[i], images)  # not an image
            err = abs(d[i] - want) / want
            worst = max(worst, err)
            checked.append((start, omega, d[i], err, min(images)))
            assert err <= 1e-9, (start, omega, d[i], want, images)
    print("rigid distance against the reference (branch from, ω, distance, relative error, nearest image):",
          [(s, f"{w:.7g}", f"{x:.8g}", f"{y:.2g}", f"{z:.3g}") for s, w, x, y, z in checked])
