"""The Python functions return exactly what the command line's --json prints, on every shipped
scene (short runs): the same library calls and the same JSON writer behind both."""
import os
import subprocess

import h5py
import pytest

import vibro
import tomllib

from conftest import CLI, SCENES, cli_json, shipped_scenes



def compliant(path):
    """A compliant stop: a stiffness on [stop] or a [[contact]] (docs/compliant.md)."""
    with open(path, "rb") as f:
        t = tomllib.load(f)
    return "stiffness" in t.get("stop", {}) or any("stiffness" in c for c in t.get("contact", []))


SHORT = {"run.periods": 12, "run.samples_per_period": 0}
SHORT_ARGS = ["--set", "run.periods=12", "--set", "run.samples_per_period=0"]


@pytest.mark.parametrize("name", shipped_scenes())
def test_model_and_simulate_equal_cli(name):
    path = os.path.join(SCENES, name)
    scene = vibro.load_scene(path, set=SHORT)
    assert vibro.model(scene) == cli_json("model", path, *SHORT_ARGS)
    for engine in ("exact", "cvode"):  # several contacts and compliant stops too (docs/contacts.md, compliant.md)
        s = vibro.load_scene(path, set={**SHORT, "run.engine": engine})
        got = vibro.simulate(s).summary
        want = cli_json("simulate", path, *SHORT_ARGS, "--set", f'run.engine="{engine}"')
        assert got == want, (engine, got, want)


@pytest.mark.parametrize("name", shipped_scenes())
def test_check_equals_cli(name):
    path = os.path.join(SCENES, name)
    args = ["--set", "run.periods=10"]
    if compliant(path):  # the exact engine against CVODE (docs/compliant.md); the orbit by both alike,
        # with its contact phases and the rigid model's orbit beside it (docs/compliant.md, "Periodic orbits")
        got = vibro.orbit(vibro.load_scene(path, set={"run.periods": 10}))
        assert got == cli_json("orbit", path, *args)
        assert got["status"] == "converged" and got["contact_phases"] and got["rigid_model"]["status"] == "converged"
        with pytest.raises(ValueError, match="compliant stop.*does not handle it yet"):
            vibro.prove(vibro.load_scene(path, set={"run.periods": 10}))
    assert vibro.check(vibro.load_scene(path, set={"run.periods": 10})) == cli_json("check", path, *args)


def test_orbit_with_several_contacts_equals_cli():
    # docs/contacts.md "Periodic orbits": the dict has the contact sequence, as the CLI's JSON.
    path = os.path.join(SCENES, "contacts_chain2.toml")
    got = vibro.orbit(vibro.load_scene(path))
    assert got == cli_json("orbit", path)
    assert got["status"] == "converged"
    assert got["sequence"] == "0:impact*13 0:accumulation 0:stick 1:impact*2 0:release"


def test_orbit_continue_sweep_equal_cli():
    path = os.path.join(SCENES, "fig08_preload.toml")
    scene = vibro.load_scene(path)
    assert vibro.orbit(scene) == cli_json("orbit", path)
    assert vibro.orbit(scene, kind="sticking", period=1, guess=(0.9,)) == \
        cli_json("orbit", path, "--kind", "sticking", "--period", "1", "--guess", "0.9")
    branch = vibro.continue_(scene, "excitation.amplitude", 2.0, max_points=40)
    want = cli_json("continue", path, "--param", "excitation.amplitude", "--to", "2.0", "--max-points", "40")
    table = branch.pop("table")
    loads = branch.pop("loads")
    strobe = branch.pop("strobe")
    assert branch == want
    # The strobe array is the points' stroboscopic states, per contact.
    assert [p["strobe"] for p in want["points"]] == [list(row) for row in strobe]
    # The loads arrays are the points' loads, per contact.
    assert [p["loads"][0]["work_rate"] for p in want["points"]] == list(loads["work_rate"][:, 0])
    # The table is the points' columns.
    assert [p["value"] for p in want["points"]] == list(table["value"])
    assert [p["stable"] for p in want["points"]] == list(table["stable"])
    got = vibro.sweep(vibro.load_scene(path, set={"run.periods": 20}), "excitation.amplitude", 1.2, 1.6, steps=4)
    assert got == cli_json("sweep", path, "--set", "run.periods=20", "--param", "excitation.amplitude",
                           "--from", "1.2", "--to", "1.6", "--steps", "4")


def test_overrides_by_dict_equal_cli_set():
    """set={...} with Python values is --set KEY=VALUE with TOML values."""
    path = os.path.join(SCENES, "chain2.toml")
    py = vibro.load_scene(path, set={"excitation.amplitude": 2.5, "run.engine": "exact", "run.periods": 8,
                                      "structure.damping_ratios": [0.01, 0.02]})
    cli = cli_json("simulate", path, "--set", "excitation.amplitude=2.5", "--set", 'run.engine="exact"',
                   "--set", "run.periods=8", "--set", "structure.damping_ratios=[0.01, 0.02]")
    assert vibro.simulate(py).summary == cli


def test_studies_equal_cli():
    path = os.path.join(SCENES, "fig05_coexistence.toml")
    scene = vibro.load_scene(path, set={"run.periods": 60})
    args = ["--set", "run.periods=60"]
    b = vibro.basin(scene, grid=(6, 5), threads=2)
    want = cli_json("basin", path, *args, "--grid", "6,5", "--threads", "1")
    labels, x, y, extent = b.pop("labels"), b.pop("x"), b.pop("y"), b.pop("extent")
    assert b == want
    assert labels.shape == (5, 6) and str(labels.dtype) == "int32"
    assert set(labels.ravel()) <= set(range(-3, len(want["attractors"])))
    # Cell centres over the default ranges (x_B from the stop over two stop distances).
    assert extent[0] < x[0] < x[-1] < extent[1] and extent[2] < y[0] < y[-1] < extent[3]
    assert vibro.attractors(scene, samples=12, seed=3) == \
        cli_json("attractors", path, *args, "--samples", "12", "--seed", "3")


def test_failed_orbit_file_ends_as_the_cli_file(tmp_path):
    """A Newton solve that does not converge still ends the --out file (status numerical-failure
    with the reason), as the command line does; it used to stay at status "running"."""
    path = os.path.join(SCENES, "chain10_stiff.toml")
    out = tmp_path / "py.h5"
    got = vibro.orbit(vibro.load_scene(path), kind="impact", period=3, transient=0, out=str(out))
    assert got["status"] == "not-converged"
    cli_out = tmp_path / "cli.h5"
    from conftest import CLI
    p = subprocess.run([CLI, "orbit", path, "--kind", "impact", "--period", "3", "--transient", "0",
                        "--out", str(cli_out)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 3, p.stderr
    with h5py.File(out, "r") as a, h5py.File(cli_out, "r") as b:
        assert a.attrs["status"] == b.attrs["status"] == "numerical-failure"
        assert a.attrs["message"] == b.attrs["message"]
