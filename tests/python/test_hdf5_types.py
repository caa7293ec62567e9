"""What h5py returns from vibro's files, dataset by dataset: strings are variable-length UTF-8
(attributes read as str, datasets as str through .asstr()), integers are integers, tables are
one dataset per column, /orbit holds typed scalars, /model the mode shapes; provenance on every
file; --out never replaces a vibro file of another scene or command without --force."""
import json
import os
import subprocess

import h5py
import numpy as np
import pytest

import vibro
from conftest import CLI, SCENES

FIG05 = os.path.join(SCENES, "fig05_coexistence.toml")
FIG08 = os.path.join(SCENES, "fig08_preload.toml")
CHAIN2 = os.path.join(SCENES, "chain2.toml")


def run(*args):
    return subprocess.run([CLI, *args], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("files")
    out = {k: str(d / f"{k}.h5") for k in ("simulate", "orbit", "impact", "continue", "basin", "sweep")}
    cmds = {
        "simulate": ["simulate", CHAIN2, "--set", "run.periods=20"],
        "orbit": ["orbit", FIG08],
        "impact": ["orbit", FIG05, "--kind", "impact", "--period", "1"],
        "continue": ["continue", FIG08, "--param", "excitation.amplitude", "--to", "1.25"],
        "basin": ["basin", FIG05, "--grid", "6,6", "--set", "run.periods=60"],
        "sweep": ["sweep", FIG08, "--param", "excitation.amplitude", "--from", "1.2", "--to", "1.3",
                  "--steps", "2", "--set", "run.periods=20"],
    }
    for k, c in cmds.items():
        p = run(*c, "--out", out[k])
        assert p.returncode == 0, (k, p.stderr)
    return out, cmds


def string_dataset(ds):
    info = h5py.check_string_dtype(ds.dtype)
    return info is not None and info.encoding == "utf-8" and info.length is None


def test_provenance_on_every_file(files):
    out, cmds = files
    for k, path in out.items():
        with h5py.File(path, "r") as f:
            a = f.attrs
            for name in ("vibro_version", "git_commit", "command", "command_line", "options", "scene",
                         "scene_resolved", "status", "created"):
                assert isinstance(a[name], str), (k, name, type(a[name]))
            assert a["command"] == cmds[k][0]
            assert a["command_line"].split()[1:] == cmds[k] + ["--out", path]
            assert a["git_commit"] and a["vibro_version"] == vibro.__version__
            # The options with their values, defaults included (e.g. --json=false).
            assert "json=false" in a["options"] and "force=false" in a["options"]
            assert isinstance(a["periods"], np.integer) and isinstance(a["rtol"], np.floating)


def test_resolved_scene_is_shortest_and_reruns_the_same(files):
    out, _ = files
    with h5py.File(out["simulate"], "r") as f:
        text = f.attrs["scene_resolved"]
    # Every key resolved, numbers in shortest round-trip form.
    for key in ("restitution", "rtol", "atol", "chatter_switch", "samples_per_period", "max_period",
                "period_tolerance", "engine", "method"):
        assert f"\n{key} = " in text, key
    assert "periods = 20\n" in text and "9999999" not in text and "0000001" not in text
    again = vibro.Scene.from_toml(text, source="scene_resolved")
    original = vibro.load_scene(CHAIN2, set={"run.periods": 20})
    assert vibro.simulate(again).summary == vibro.simulate(original).summary


def test_string_and_integer_datasets(files):
    out, _ = files
    with h5py.File(out["simulate"], "r") as f:
        assert h5py.check_enum_dtype(f["events/kind"].dtype) is not None and f["events/kind"].dtype == np.int8
        assert f["samples/mode"].dtype == np.int8 and f["events/period"].dtype == np.int64
        for g in ("events", "samples", "section"):
            for k, ds in f[g].items():
                assert ds.dtype.kind in "fi", (g, k, ds.dtype)
    with h5py.File(out["continue"], "r") as f:
        assert string_dataset(f["branch/events"]) and string_dataset(f["bifurcations/kind"])
        events = f["branch/events"].asstr()[()]
        assert all(isinstance(e, str) for e in events) and len(events) == f["branch/value"].shape[0]
        assert f["branch/stable"].dtype == np.uint8
        assert isinstance(f["branch"].attrs["param"], str)


def test_attractors_table(files):
    out, _ = files
    j = json.loads(run("basin", FIG05, "--grid", "6,6", "--set", "run.periods=60", "--json").stdout)
    with h5py.File(out["basin"], "r") as f:
        t = f["attractors"]
        assert isinstance(t, h5py.Group) and all(isinstance(t[k], h5py.Dataset) for k in t)
        n = len(j["attractors"])
        types = {"period": np.int32, "impacts_per_period": np.int64, "stable": np.int8,
                 "merged_classes": np.int32, "multiplier_count": np.int32, "multiplier_offset": np.int32,
                 "sticking_fraction": np.float64, "basin_fraction": np.float64,
                 "basin_fraction_error": np.float64, "orbit_residual": np.float64,
                 "leading_multiplier": np.float64}
        for k, dt in types.items():
            assert t[k].dtype == dt and t[k].shape == (n,), (k, t[k].dtype, t[k].shape)
        assert string_dataset(t["kind"]) and string_dataset(t["orbit_status"])
        # The table's rows are the JSON's attractors.
        for i, a in enumerate(j["attractors"]):
            assert t["kind"].asstr()[i] == a["kind"] and t["period"][i] == a["period"]
            assert t["impacts_per_period"][i] == (a["impacts_per_period"] if a["impacts_per_period"] is not None else -1)
            sp = a["sticking_fraction"] if a["kind"] == "sticking-periodic" else None
            if sp is not None:
                assert t["sticking_fraction"][i] == sp
            assert t["basin_fraction"][i] == a["basin_fraction"]
            assert t["stable"][i] == (-1 if a["stable"] is None else int(a["stable"]))
            o, c = t["multiplier_offset"][i], t["multiplier_count"][i]
            assert t["floquet_multipliers"][o:o + c].tolist() == a["floquet_multipliers"]
        assert f["basin/labels"].dtype == np.int32


def test_orbit_scalars(files):
    out, _ = files
    j = json.loads(run("orbit", FIG08, "--json").stdout)
    with h5py.File(out["orbit"], "r") as f:
        o = f["orbit"].attrs
        assert isinstance(o["period"], np.int64) and o["period"] == j["period"]
        assert isinstance(o["newton_iterations"], np.int64) and o["newton_iterations"] == j["newton_iterations"]
        assert isinstance(o["stable"], np.bool_) and bool(o["stable"]) == j["stable"]
        assert isinstance(o["residual"], np.float64) and isinstance(o["section_time"], np.float64)
        assert o["multipliers"].shape == (len(j["floquet_multipliers"]), 2)


def test_no_stray_attractor_and_info_lists_groups(files):
    out, _ = files
    for k in ("basin", "continue"):
        with h5py.File(out[k], "r") as f:
            assert "attractor" not in f, k
    for k, group in (("basin", "basin"), ("continue", "branch"), ("orbit", "orbit"), ("sweep", "sweep")):
        info = vibro.info(out[k])
        assert group in info["groups"], (k, info["groups"])
        text = run("info", out[k]).stdout
        assert group in text.split("groups", 1)[1].splitlines()[0], text
    # What the result groups hold, one line each.
    text = run("info", out["basin"]).stdout
    assert "/basin         6 × 6 cells, x = x_B, y = v_B" in text and "attractor    none" in text, text
    assert vibro.info(out["basin"])["attractor"] is None
    assert "param = excitation.amplitude" in run("info", out["continue"]).stdout
        # An impact orbit's phases: in the file, in info --json and in the text.
    j = json.loads(run("orbit", FIG05, "--kind", "impact", "--period", "1", "--json").stdout)
    info = vibro.info(out["impact"])
    assert info["attractor"]["impact_phases"] == pytest.approx(j["impact_phases"], abs=1e-9)
    assert "impacts      phase " in run("info", out["impact"]).stdout  # the impact phases, with ẋ_B


def test_model_mode_shapes_rebuild_physical_displacements(files):
    """Independent truth: the contact DOF's physical displacement Σ ψ_Bi X_i is the stored x_B
    (mode shapes have a unit component at B), and M-orthogonality is not needed for that."""
    out, _ = files
    with h5py.File(out["simulate"], "r") as f:
        m = f["model"].attrs
        assert m["form"] == "physical"
        shapes, labels = m["mode_shapes"], list(m["dof_labels"])
        assert shapes.ndim == 2 and len(labels) == shapes.shape[0] and all(isinstance(s, str) for s in labels)
        b = [i for i, s in enumerate(labels) if "B" in s]
        assert len(b) == 1
        x = f["samples/X"][()] @ shapes.T  # physical displacements (M, N)
        np.testing.assert_allclose(x[:, b[0]], f["samples/x_B"][()], atol=1e-12)
    with h5py.File(out["orbit"], "r") as f:
        assert f["model"].attrs["form"] == "modal" and "mode_shapes" not in f["model"].attrs


def test_out_refuses_another_scene_or_command(tmp_path):
    path = tmp_path / "run.h5"
    assert run("simulate", FIG08, "--set", "run.periods=5", "--out", str(path)).returncode == 0
    before = path.read_bytes()
    for args in (["simulate", FIG08, "--set", "run.periods=6"],      # another scene
                 ["orbit", FIG08, "--set", "run.periods=5"]):         # another command
        p = run(*args, "--out", str(path))
        assert p.returncode == 2 and "--force" in p.stderr, p.stderr
        assert path.read_bytes() == before
    # The same command and scene again replaces it; --force replaces anything vibro wrote.
    assert run("simulate", FIG08, "--set", "run.periods=5", "--out", str(path)).returncode == 0
    assert run("orbit", FIG08, "--set", "run.periods=5", "--out", str(path), "--force").returncode == 0
    with h5py.File(path, "r") as f:
        assert f.attrs["command"] == "orbit"
    # From Python: ValueError, then force=True.
    with pytest.raises(ValueError, match="--force"):
        vibro.simulate(vibro.load_scene(FIG08, set={"run.periods": 7}), out=path)
    vibro.simulate(vibro.load_scene(FIG08, set={"run.periods": 7}), out=path, force=True)
    with h5py.File(path, "r") as f:
        assert f.attrs["command"] == "simulate" and f.attrs["command_line"].startswith("vibro.simulate(")
