"""Continuation with several contacts against independent truths (docs/contacts.md, "Branches").

The truths are the closed forms of tests/reference/contacts/closed_forms.py (mpmath, 50 digits,
no vibro code):

(a) the symmetric two-sided 1-DOF oscillator: every point of a branch in the forcing amplitude is
    the closed-form symmetric orbit (T2) (impact speeds, the product of the multipliers r^4), and
    the branch point where the orbit loses its symmetry (a pitchfork: tr DG = -(1 + r^2), (T5)) is
    located to 1e-10 in the amplitude; the stable asymmetric orbits past it are seen by `orbit`;
(b) the fold of the symmetric family in the forcing frequency (the discriminant of (T2)), to 1e-10;
(c) the grazing of the lower stop by an orbit that hits only the upper one (T6), located by
    continuation in the amplitude, against the closed-form orbit's lowest point and against a
    bisection on simulations in quad precision, each to 1e-10, on contact 0;
(d) the same from Python (vibro.continue_), with the contact sequence of every point and the
    contact of every bifurcation.

ctest runs this file as python.contacts_continue with VIBRO_CLI set to the built `vibro`.
"""
import json
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tests", "reference", "contacts"))

import mpmath as mp  # noqa: E402

import closed_forms as cf  # noqa: E402

CLI = os.environ.get("VIBRO_CLI", "")

SCENE = """
title = "Two-sided 1-DOF"
[structure]
mass = [[1.0]]
stiffness = [[1.0]]
forcing_dof = 0
[[contact]]
dof = 0
side = "below"
position = {lo!r}
restitution = {r!r}
[[contact]]
dof = 0
side = "above"
position = 1.0
restitution = {r!r}
[excitation]
amplitude = {a!r}
frequency = {w!r}
[initial]
time = {t0!r}
displacement = [{x0!r}]
velocity = [{v0!r}]
[run]
periods = {periods}
"""


def scene_file(tmp_path, name, lo=-1.0, r=0.8, a=4.0, w=2.5, t0=0.0, x0=0.0, v0=0.0, periods=200, precision=None):
    text = SCENE.format(lo=lo, r=r, a=a, w=w, t0=t0, x0=x0, v0=v0, periods=periods)
    if precision:
        text += f'precision = "{precision}"\n'
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return str(path)


def vibro(*args, check=True):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=600)
    if check:
        assert p.returncode == 0, p.stderr
    return p


def continue_json(*args):
    return json.loads(vibro("continue", *args, "--json").stdout)


def mid_flight_state(orb):
    """A free state of the symmetric orbit: a quarter period after the impact on +D."""
    t = orb.phi / orb.w + mp.pi / (2 * orb.w)
    x, v = cf.flight(orb.D, -orb.r * orb.V, orb.phi / orb.w, orb.w1, orb.a, orb.w, mp.pi / (2 * orb.w))
    return float(t), float(x), float(v)


R = mp.mpf("0.8")


# (a) ------------------------------------------------------------------------------------------


def test_pitchfork_of_the_symmetric_orbit_at_the_closed_form(tmp_path):
    a_star = cf.pitchfork_amplitude(1, 1, R, "2.5", 4, 5)
    path = scene_file(tmp_path, "two_sided", a=4.0)
    out = tmp_path / "branch.h5"
    b = continue_json(path, "--param", "excitation.amplitude", "--to", 5.0, "--out", out)
    assert b["end"] == "reached the end value"
    bps = [x for x in b["bifurcations"] if x["kind"] == "branch-point"]
    assert len(bps) == 1, b["bifurcations"]
    assert abs(bps[0]["value"] - float(a_star)) < 1e-10, (bps[0]["value"], a_star)
    assert not [x for x in b["bifurcations"] if x["kind"] != "branch-point"], b["bifurcations"]
    # Every point is the closed-form symmetric orbit, stable below the pitchfork only.
    with h5py.File(out, "r") as f:
        g = f["branch"]
        value, offsets = g["value"][()], g["impact_offsets"][()]
        v_before, contact = g["impact_v_before"][()], g["impact_contact"][()]
        seq = [s.decode() if isinstance(s, bytes) else s for s in g["sequence"][()]]
        mu = g["multipliers"][()]
    assert len(value) >= 10
    for i, a in enumerate(value):
        orb = cf.symmetric_orbits(1, mp.mpf(float(a)), 1, R, "2.5")[0]
        speeds = v_before[offsets[i]:offsets[i + 1]]
        assert sorted(contact[offsets[i]:offsets[i + 1]]) == [0, 1]
        assert np.allclose(np.abs(speeds), float(orb.V), rtol=0, atol=1e-10), (a, speeds, orb.V)
        assert seq[i] == "0:impact 1:impact"
        m = mu[i, :, 0] + 1j * mu[i, :, 1]
        assert abs(np.prod(m) - float(R) ** 4) < 1e-10
        # The multipliers are the squares of DG's eigenvalues (T5).
        expected = [complex(z) for z in cf.floquet_multipliers(orb)]
        assert all(min(abs(m - z)) < 1e-9 for z in expected), (a, m, expected)
        assert (b["points"][i]["stable"]) == (a < float(a_star)), (a, b["points"][i])
    # Past the pitchfork the attractor is an asymmetric orbit: two impact speeds that differ.
    o = json.loads(vibro("orbit", path, "--set", "excitation.amplitude=4.7", "--json").stdout)
    assert o["stable"] and o["sequence"] == "0:impact 1:impact"
    speeds = np.abs(np.array(o["impact_velocities"]))
    assert abs(speeds[0] - speeds[1]) > 1e-3, speeds


# (b) ------------------------------------------------------------------------------------------


def test_fold_of_the_symmetric_family_at_the_closed_form(tmp_path):
    w_fold = cf.fold_frequency(1, "0.5", 1, R, "2.5", "3.0")
    orb = cf.symmetric_orbits(1, "0.5", 1, R, "2.5")[0]
    assert cf.admissible(orb)
    t0, x0, v0 = mid_flight_state(orb)
    path = scene_file(tmp_path, "fold", a=0.5, w=2.5, t0=t0, x0=x0, v0=v0)
    b = continue_json(path, "--param", "excitation.frequency", "--to", 3.2, "--transient", 0, "--max-points", 60)
    folds = [x for x in b["bifurcations"] if x["kind"] == "fold"]
    assert folds, b["bifurcations"]
    assert abs(folds[0]["value"] - float(w_fold)) < 1e-10, (folds[0]["value"], w_fold)


# (c) ------------------------------------------------------------------------------------------

LOWER = -1.7  # the lower stop; the one-sided period-2 orbit grazes it between a = 1.0 and 1.2


def one_sided(a):
    return cf.one_sided_orbit(1, a, 1, R, "2.5", 2, "8.056521", "0.957892")


def grazing_amplitude_closed_form():
    return mp.findroot(lambda a: cf.flight_minimum(*one_sided(a), samples=400)[0] - LOWER,
                       (mp.mpf("1.0"), mp.mpf("1.2")), solver="anderson")


def hits_lower_stop_in_quad(tmp_path, a):
    """One orbit period (2 T) of the closed-form one-sided orbit at amplitude a, simulated in quad
    with the lower stop at LOWER: does it reach contact 0?"""
    orb, span = one_sided(a)
    t0 = orb.phi / orb.w + span / 20  # a free state shortly after the impact on +D
    x, v = cf.flight(orb.D, -orb.r * orb.V, orb.phi / orb.w, orb.w1, orb.a, orb.w, span / 20)
    path = scene_file(tmp_path, "quad", lo=LOWER, a=float(a), t0=float(t0), x0=float(x), v0=float(v), periods=3,
                      precision="quad")
    out = tmp_path / "quad.h5"
    vibro("simulate", path, "--out", out, "--force")
    with h5py.File(out, "r") as f:
        return bool(np.any(f["events"]["contact"][()] == 0))


def test_grazing_of_the_second_stop_located_by_continuation(tmp_path):
    a_graze = grazing_amplitude_closed_form()
    # Bisection on quad simulations (the closed-form state at each amplitude).
    lo, hi = mp.mpf("1.0"), mp.mpf("1.2")
    assert not hits_lower_stop_in_quad(tmp_path, lo) and hits_lower_stop_in_quad(tmp_path, hi)
    while hi - lo > 2e-12:
        mid = (lo + hi) / 2
        if hits_lower_stop_in_quad(tmp_path, mid):
            hi = mid
        else:
            lo = mid
    assert abs((lo + hi) / 2 - a_graze) < 1e-10, (lo, hi, a_graze)
    # Continuation from the closed-form orbit at a = 1.0.
    orb, span = one_sided(mp.mpf("1.0"))
    t0 = orb.phi / orb.w + span / 20  # a free state shortly after the impact on +D
    x, v = cf.flight(orb.D, -orb.r * orb.V, orb.phi / orb.w, orb.w1, orb.a, orb.w, span / 20)
    path = scene_file(tmp_path, "graze", lo=LOWER, a=1.0, t0=float(t0), x0=float(x), v0=float(v))
    b = continue_json(path, "--param", "excitation.amplitude", "--to", 1.2, "--transient", 0, "--period", 2)
    g = [x for x in b["bifurcations"] if x["kind"] == "grazing"]
    assert g, b["bifurcations"]
    assert g[0]["contact"] == 0, g[0]
    assert abs(g[0]["value"] - float(a_graze)) < 1e-10, (g[0]["value"], a_graze)
    before = [p["sequence"] for p in b["points"] if p["value"] < g[0]["value"]]
    after = [p["sequence"] for p in b["points"] if p["value"] > g[0]["value"]]
    assert before and set(before) == {"1:impact"}, before
    # Past the grazing no period-2 orbit with a low-velocity impact on contact 0 joins this one
    # (Newton from the one-sided orbit fails there, and a transient goes to an orbit 0.4 away):
    # the branch ends, saying why; where one does join, its points carry the new impact.
    assert all("0:impact" in s for s in after), (after, b["end"])
    assert after or b["end"] == "grazing (the orbit does not go on)", b["end"]


# (d) ------------------------------------------------------------------------------------------


def test_python_continue_gives_the_sequences_and_the_branch_point(tmp_path):
    vibro_py = pytest.importorskip("vibro")
    a_star = cf.pitchfork_amplitude(1, 1, R, "2.5", 4, 5)
    path = scene_file(tmp_path, "py", a=4.0)
    b = vibro_py.continue_(path, "excitation.amplitude", 5.0)
    assert [x["kind"] for x in b["bifurcations"]] == ["branch-point"]
    assert abs(b["bifurcations"][0]["value"] - float(a_star)) < 1e-10
    assert all(p["sequence"] == "0:impact 1:impact" for p in b["points"])
    assert len(b["table"]) == len(b["points"])


def test_orbit_from_a_state_just_after_an_impact_with_a_transient(tmp_path):
    # Started right after an impact on the orbit, every period boundary of the transient is an
    # impact to rounding: the section state must still be taken on the orbit (it used to be
    # restarted from the state just before that impact, and Newton went to the no-contact orbit).
    orb = cf.symmetric_orbits(1, 1, 1, R, "2.5")[0]
    path = scene_file(tmp_path, "after_impact", a=1.0, t0=float(orb.phi / orb.w), x0=1.0,
                      v0=float(-orb.r * orb.V))
    for transient in (1, 50, 200):
        o = json.loads(vibro("orbit", path, "--transient", transient, "--json").stdout)
        assert o["status"] == "converged", (transient, o["message"])
        assert o["sequence"] == "0:impact 1:impact"
        assert np.allclose(np.abs(o["impact_velocities"]), float(orb.V), rtol=0, atol=1e-10)


SHIPPED = sorted(n for n in os.listdir(os.path.join(ROOT, "data", "scenes")) if n.startswith("contacts_"))


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_contact_scene_continues_from_python(name):
    # Every shipped scene with several contacts: its orbit is continued a few points down in the
    # frequency from Python, each point with its contact sequence, the same as the CLI's.
    vibro_py = pytest.importorskip("vibro")
    path = os.path.join(ROOT, "data", "scenes", name)
    import tomllib
    with open(path, "rb") as f:
        w = tomllib.load(f)["excitation"]["frequency"]
    b = vibro_py.continue_(path, "excitation.frequency", 0.98 * w, max_points=3)
    assert len(b["points"]) >= 2, b["end"]
    assert all(p["sequence"] for p in b["points"]), b["points"]
    cli = continue_json(path, "--param", "excitation.frequency", "--to", 0.98 * w, "--max-points", 3)
    assert [p["sequence"] for p in cli["points"]] == [p["sequence"] for p in b["points"]]
    assert [p["value"] for p in cli["points"]] == [p["value"] for p in b["points"]]
