"""Every impact and sticking phase names its contact (docs/output.md: `impact_contacts`,
`stick_contacts`; `/attractor` and `/branch/stick_contacts` in HDF5), from the CLI's JSON and from
Python, checked against the closed form of the two-sided 1-DOF oscillator (stops at -1, below, and
+1, above; x'' + x = f sin ωt between impacts), not against vibro's own bookkeeping:

- an impact named on contact c happens at that stop: the free flight that leaves it (x = ±1, the
  restitution law applied with the velocity the summary gives) lands on the stop the next impact
  names, at the next impact's phase;
- a sticking phase named on contact c is held by that stop's reaction: on the stop below,
  R = -1 - f sin ωt >= 0, on the stop above, R = f sin ωt - 1 >= 0, and the release is where R = 0.
"""
import json
import math
import os
import subprocess

import h5py
import numpy as np
import pytest

import vibro
from conftest import CLI, SCENES, cli_json

SCENE = os.path.join(SCENES, "contacts_two_sided_1dof.toml")
POSITION = {0: -1.0, 1: 1.0}   # contact[0] below at -1, contact[1] above at +1
SIGMA = {0: 1.0, 1: -1.0}      # gap = sigma (x - position): open while positive
R = 0.5                        # both stops' restitution
IMPACT = ("--set", "excitation.amplitude=4.0", "--set", "excitation.frequency=2.5")  # impact-periodic


def flight(t0, x0, v0, t, f, w):
    """x(t) of x'' + x = f sin wt from x(t0) = x0, x'(t0) = v0 (closed form, w != 1)."""
    k = f / (1.0 - w * w)
    a = x0 - k * math.sin(w * t0)
    b = v0 - k * w * math.cos(w * t0)
    s = t - t0
    return a * math.cos(s) + b * math.sin(s) + k * math.sin(w * t)


def check_impacts(att, f, w):
    """The impacts of an impact-periodic summary against the closed-form flights between them."""
    phases, gdots, contacts = att["impact_phases"], att["impact_velocities"], att["impact_contacts"]
    assert len(contacts) == len(phases) == len(gdots) > 0
    assert set(contacts) == {0, 1}, contacts  # the symmetric orbit hits both stops
    T = 2 * math.pi / w * att["period"]
    n = len(phases)
    for k in range(n):
        c, c_next = contacts[k], contacts[(k + 1) % n]
        t0 = phases[k] / w
        t1 = phases[(k + 1) % n] / w
        while t1 <= t0:
            t1 += T
        v_before = SIGMA[c] * gdots[k]          # the gap velocity of contact c is sigma_c x'
        assert v_before * SIGMA[c] < 0          # moving into that stop
        v_after = -R * v_before
        x0 = POSITION[c]
        land = flight(t0, x0, v_after, t1, f, w)
        assert land == pytest.approx(POSITION[c_next], abs=1e-7), (k, c, c_next, land)
        # ... and the named stop is the only one touched between: both gaps open inside the flight.
        for s in np.linspace(t0, t1, 200)[1:-1]:
            x = flight(t0, x0, v_after, s, f, w)
            assert -1.0 - 1e-9 <= x <= 1.0 + 1e-9


def check_sticks(phases, contacts, f):
    """Each sticking phase held by its named stop: R >= 0 inside, R = 0 at the release."""
    assert len(contacts) == len(phases) > 0
    for (start, end), c in zip(phases, contacts):
        reaction = (lambda p: -1.0 - f * math.sin(p)) if c == 0 else (lambda p: f * math.sin(p) - 1.0)
        other = (lambda p: f * math.sin(p) - 1.0) if c == 0 else (lambda p: -1.0 - f * math.sin(p))
        inside = np.linspace(start, end, 50)[1:-1]
        assert min(reaction(p) for p in inside) >= -1e-9, (start, end, c)
        assert max(other(p) for p in inside) < 0, (start, end, c)  # the other stop could not hold it
        assert reaction(end) == pytest.approx(0.0, abs=1e-8), (end, c)


def test_impact_contacts_of_simulate_and_orbit():
    run = cli_json("simulate", SCENE, *IMPACT)
    att = run["attractor"]
    assert att["kind"] == "impact-periodic"
    assert att["stick_contacts"] == [] and att["stick_phases"] == []
    check_impacts(att, 4.0, 2.5)
    scene = vibro.load_scene(SCENE, set={"excitation.amplitude": 4.0, "excitation.frequency": 2.5})
    py = vibro.simulate(scene).summary["attractor"]
    assert py["impact_contacts"] == att["impact_contacts"]
    orb = cli_json("orbit", SCENE, *IMPACT, "--kind", "impact")
    check_impacts(dict(orb, period=orb["period"]), 4.0, 2.5)
    assert vibro.orbit(scene, kind="impact")["impact_contacts"] == orb["impact_contacts"]


def test_stick_contacts_of_simulate_orbit_and_hdf5(tmp_path):
    out = tmp_path / "run.h5"
    run = cli_json("simulate", SCENE, "--out", str(out))
    att = run["attractor"]
    assert att["kind"] == "sticking-periodic"
    assert set(att["stick_contacts"]) == {0, 1}  # chattering, then sticking, at both stops
    check_sticks(att["stick_phases"], att["stick_contacts"], 5.0)
    with h5py.File(out, "r") as h:
        assert list(h["attractor"].attrs["stick_contacts"]) == att["stick_contacts"]
    py = vibro.simulate(vibro.load_scene(SCENE)).summary["attractor"]
    assert py["stick_contacts"] == att["stick_contacts"]
    orb = cli_json("orbit", SCENE)
    check_sticks(orb["stick_phases"], orb["stick_contacts"], 5.0)


def test_branch_stick_contacts_in_json_and_hdf5(tmp_path):
    out = tmp_path / "b.h5"
    p = subprocess.run([CLI, "continue", SCENE, "--param", "excitation.amplitude", "--to", "5.3", "--max-points", "6",
                        "--out", str(out), "--json"], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    points = json.loads(p.stdout)["points"]
    assert len(points) >= 3
    with h5py.File(out, "r") as h:
        stored = h["branch/stick_contacts"][:]
        phases = h["branch/stick_phases"][:]
        values = h["branch/value"][:]
        assert stored.dtype.kind == "i" and stored.shape == phases.shape[:2] == (len(points), phases.shape[1])
    for i, pt in enumerate(points):
        n = len(pt["stick_contacts"])
        assert list(stored[i, :n]) == pt["stick_contacts"] and (stored[i, n:] == -1).all()
        assert np.isnan(phases[i, n:]).all()
        check_sticks(phases[i, :n].tolist(), pt["stick_contacts"], values[i])
    branch = vibro.continue_(vibro.load_scene(SCENE), "excitation.amplitude", 5.3, max_points=6)
    assert [q["stick_contacts"] for q in branch["points"]] == [q["stick_contacts"] for q in points]
