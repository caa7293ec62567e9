"""Compliant stops (docs/compliant.md) through Python and the command line on a real scene: the
tube in a two-sided compliant support. Each contact phase's release carries its peak force,
duration and impulse; the rigid model beside it has the restitution of Schwager & Pöschel's closed
form for the contact's damping ratio (ζ = c/(2√(k m)), m = 1 at the tube's DOF: M = diag(2, 1)
gives W = (M⁻¹)₁₁ = 1); bad keys are located errors, exit 2."""
import math
import os
import subprocess

import numpy as np

import vibro
from conftest import CLI, SCENES

TUBE = os.path.join(SCENES, "tube_compliant_support.toml")


def test_contact_phases_carry_peak_force_duration_impulse():
    r = vibro.simulate(TUBE, blocks=10, progress=False)
    assert r.summary["status"] == "ok"
    e = r.events
    releases = e[e["kind"] == 4]
    stick = e[e["kind"] == 3]
    assert len(releases) > 100 and len(stick) == len(releases)
    assert set(np.unique(releases["contact"])) == {0, 1}
    # Each phase: a positive peak, a duration near half the contact's period π/√(k/m) (k = 1000,
    # m = 1: 0.0993; the structure and the damping shift it slightly), a positive impulse.
    assert np.all(releases["reaction_max"] > 0)
    assert np.all(np.abs(releases["stick_duration"] / (math.pi / math.sqrt(1000.0)) - 1) < 0.05)
    assert np.all(releases["reaction_integral"] > 0)
    # The phases' energy is the loads' dissipated power.
    assert r.summary["loads"][0]["dissipated_power"] > 0


def test_rigid_beside_restitution_and_distance():
    c = vibro.rigid_beside(TUBE)
    zeta = 2.0 / (2 * math.sqrt(1000.0 * 1.0))
    s = math.sqrt(1 - zeta * zeta)
    e_sp = math.exp(-zeta / s * (math.pi - math.atan2(2 * zeta * s, 1 - 2 * zeta * zeta)))
    for k in c["contacts"]:
        assert math.isclose(k["zeta"], zeta, rel_tol=1e-12)
        assert math.isclose(k["restitution"], e_sp, rel_tol=1e-12)
        assert k["phases"] > 100 and k["peak_force_max"] >= k["peak_force_mean"] > 0
        assert k["compliant"]["dissipated_power"] > 0 and k["rigid"]["dissipated_power"] > 0
    assert 0 < c["distance"]["max"] < 0.2


def test_cli_rigid_beside_and_located_errors(tmp_path):
    out = subprocess.run([CLI, "simulate", TUBE, "--set", "run.periods=40", "--rigid-beside", "--json"],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    import json
    j = json.loads(out.stdout)
    assert "rigid_model" in j and j["rigid_model"]["contacts"][1]["phases"] > 0
    bad = subprocess.run([CLI, "simulate", TUBE, "--set", "contact[0].stiffness=-5"], capture_output=True, text=True)
    assert bad.returncode == 2
    assert "contact[0].stiffness" in bad.stderr and "k > 0" in bad.stderr
    rigid = subprocess.run([CLI, "simulate", os.path.join(SCENES, "tube_loose_support.toml"), "--rigid-beside"],
                           capture_output=True, text=True)
    assert rigid.returncode == 2 and "no compliant stop" in rigid.stderr


def test_check_compares_the_exact_engine_with_cvode():
    # docs/compliant.md "CVODE and vibro check": the closed forms against CVODE's integration of the
    # same law; the Poincaré solver finds the orbit (docs/compliant.md, "Periodic orbits"), its leading
    # multiplier the exact engine's transient decay; the quad engine is refused, located.
    r = vibro.check(vibro.load_scene(TUBE))
    assert r["ok"] and r["orbit_status"] == "converged", [x for x in r["rows"] if not x["ok"]]
    rows = {x["quantity"]: x for x in r["rows"]}
    decay = rows["leading |multiplier| vs transient decay"]
    assert abs(decay["orbit"] / decay["exact"] - 1) < 1e-4
    first = rows["first contact phase peak force"]
    assert first["exact"] > 0 and first["exact"] != first["cvode"]  # two engines, not one run twice
    assert abs(first["cvode"] / first["exact"] - 1) < 1e-8
    assert any(q.startswith("contact phase 2 (contact") for q in rows)
    quad = subprocess.run([CLI, "check", TUBE, "--precision", "quad"], capture_output=True, text=True)
    assert quad.returncode == 2 and quad.stdout == ""
    assert "compliant stop" in quad.stderr and "`vibro check --precision quad` does not handle it yet" in quad.stderr


def test_peak_time_and_penetration_columns(tmp_path):
    # docs/output.md: /events/peak_time and /events/penetration_max, the same in Python's events;
    # a phase's peak lies inside it; at the largest penetration ġ = 0, so the force there is the
    # spring's, k max(−g), at most the peak force; NaN for every other event.
    out = tmp_path / "tube.h5"
    r = vibro.simulate(TUBE, out=str(out), progress=False)
    e = r.events
    rel, stick = e[e["kind"] == 4], e[e["kind"] == 3]
    assert len(rel) > 100 and len(stick) == len(rel)
    assert np.all((stick["t"] <= rel["peak_time"]) & (rel["peak_time"] <= rel["t"]))
    assert np.all(rel["penetration_max"] > 0)
    assert np.all(1000.0 * rel["penetration_max"] <= rel["reaction_max"] * (1 + 1e-12))
    assert np.all(np.isnan(e["peak_time"][e["kind"] != 4])) and np.all(np.isnan(e["penetration_max"][e["kind"] != 4]))
    import h5py
    with h5py.File(out) as f:
        for name in ("peak_time", "penetration_max"):
            np.testing.assert_array_equal(f["events"][name][:], e[name])


def test_check_under_a_sum_of_harmonics(tmp_path):
    # CVODE's contact phase takes every harmonic's forcing term (docs/compliant.md "CVODE"): the
    # exact engine's closed form and CVODE agree on a two-harmonic scene's contact phases.
    scene = tmp_path / "two.toml"
    scene.write_text("[structure]\nmass = [[1.0]]\nstiffness = [[1.0]]\nforcing_dof = 0\ncontact_dof = 0\n"
                     "damping_ratios = [0.05]\n[stop]\nposition = -0.5\nstiffness = 400.0\ndamping = 2.0\n"
                     "[excitation]\namplitude = [1.0, 0.5]\nfrequency = [0.8, 1.6]\n[run]\nperiods = 60\n")
    r = vibro.check(vibro.load_scene(str(scene)))
    assert r["ok"], [x for x in r["rows"] if not x["ok"]]
    rows = {x["quantity"]: x for x in r["rows"]}
    assert abs(rows["contact phase 1 (contact 0) peak force"]["cvode"] /
               rows["contact phase 1 (contact 0) peak force"]["exact"] - 1) < 1e-7


def test_cvode_sections_and_samples_once_each_when_an_exit_follows_a_peak(tmp_path):
    """A dashpot of 1e6 on a spring of 1e-8 (the surfaces campaign's seed 7): each contact phase ends
    4e-6 before the section at t = kT, and CVODE found the phase's peak and then its exit in one step.
    The stretch after the peak was covered to the step's end, past the exit, so every section was
    stored twice (119 for 60 periods). Both engines now store the same 61 sections and samples."""
    scene = tmp_path / "dashpot.toml"
    scene.write_text("""
[structure]
mass = [[1.0]]
stiffness = [[1.0]]
forcing_dof = 0
contact_dof = 0
damping_ratios = [0.0]
[excitation]
amplitude = 0.5
frequency = 0.8
[stop]
position = 0.0
stiffness = 1e-8
damping = 1e6
[initial]
displacement = [0.0]
velocity = [0.0]
[run]
periods = 60
""")
    runs = {}
    for engine in ("exact", "cvode"):
        out = tmp_path / f"{engine}.h5"
        p = subprocess.run([CLI, "simulate", str(scene), "--set", f'run.engine="{engine}"', "--out", str(out)],
                           capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        import h5py
        with h5py.File(out) as f:
            runs[engine] = (f["section/t"][()], f["samples/t"][()])
    for engine, (section, samples) in runs.items():
        assert len(section) == 61 and np.all(np.diff(section) > 0), engine
        assert np.all(np.diff(samples) > 0), engine
    assert np.allclose(runs["cvode"][0], runs["exact"][0], rtol=0, atol=1e-12)
    assert len(runs["cvode"][1]) == len(runs["exact"][1])
