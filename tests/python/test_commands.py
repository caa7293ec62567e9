"""vibro.validate, vibro.score and vibro.partition return what `vibro validate|score|partition
--json` prints (one shared implementation in src/frontend/commands.cpp), with numpy tables of the
same rows; bad input raises ValueError naming the keyword argument."""
import os
import subprocess
import sys

import numpy as np
import pytest

import vibro
from conftest import SCENES, cli_json

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
BENCH = os.path.join(ROOT, "data", "benchmarks")
FIG8 = os.path.join(SCENES, "fig08_preload.toml")


def test_score_equals_cli_on_shipped_benchmark():
    scene, events = os.path.join(BENCH, "chatter_1dof.toml"), os.path.join(BENCH, "chatter_1dof.csv")
    got = vibro.score(vibro.load_scene(scene), events)
    table, run = got.pop("table"), got.pop("vibro_run")
    assert got == cli_json("score", scene, events)
    assert run == {"status": "ok", "message": ""}
    assert list(table["kind"]) == [k["kind"] for k in got["kinds"]]
    assert list(table["theirs"]) == [k["theirs"] for k in got["kinds"]]
    assert table["theirs"].dtype == np.int64
    # A tighter window changes the result the same way on both sides.
    got = vibro.score(scene, events, window=0.01, tolerance=1e-9)
    got.pop("table"), got.pop("vibro_run")
    assert got == cli_json("score", scene, events, "--window", "0.01", "--tolerance", "1e-9")


def test_score_bad_window_is_value_error():
    scene, events = os.path.join(BENCH, "chatter_1dof.toml"), os.path.join(BENCH, "chatter_1dof.csv")
    with pytest.raises(ValueError, match=r"window -1: expected a finite positive number"):
        vibro.score(scene, events, window=-1)


def test_validate_equals_cli_on_own_branch(tmp_path):
    """A branch of vibro's own (Fig. 8 at r = 0), exported to CSV, validated from Python and the CLI."""
    scene = vibro.load_scene(FIG8, set={"stop.restitution": 0.0})
    h5 = tmp_path / "b.h5"
    vibro.continue_(scene, "excitation.amplitude", 3.0, max_points=8, out=h5)
    csv = tmp_path / "b.csv"
    subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "branch_to_csv.py"), str(h5), str(csv)],
                   check=True)
    out = tmp_path / "v.h5"
    got = vibro.validate(scene, csv, "excitation.amplitude", out=out)
    table = got.pop("table")
    want = cli_json("validate", FIG8, str(csv), "--set", "stop.restitution=0.0", "--param", "excitation.amplitude")
    assert got == want
    assert want["disagreements"] == 0 and len(want["points"]) > 2
    assert list(table["verdict"]) == ["confirmed"] * len(want["points"])
    assert np.array_equal(table["value"], [p["value"] for p in want["points"]])
    assert list(table["period"]) == [p["period"] for p in want["points"]]
    # The file holds the same verdicts, read back as str.
    v = vibro.read(out)["validation"]
    assert list(v["verdict"]) == list(table["verdict"]) and isinstance(v["verdict"][0], str)


def test_validate_bad_param_is_value_error(tmp_path):
    csv = tmp_path / "x.csv"
    csv.write_text("value,time,displacement_1,velocity_1\n1.5,0,1.1,0\n")
    with pytest.raises(ValueError, match=r"param excitation\.amplitud: not a numeric key"):
        vibro.validate(FIG8, csv, "excitation.amplitud")
    with pytest.raises(ValueError, match=r"tolerance 0: expected a finite positive number"):
        vibro.validate(FIG8, csv, "excitation.amplitude", tolerance=0)


def test_partition_equals_cli(tmp_path):
    scene = vibro.load_scene(FIG8, set={"stop.restitution": 0.0})
    out = tmp_path / "p.h5"
    got = vibro.partition(scene, ("excitation.frequency", "excitation.amplitude"), (2.8, 5), (1.05, 12), [0.5],
                          steps1=1, from2=1.5, out=out)
    crossings, boundaries = got.pop("crossings"), got.pop("boundaries")
    cells, loads = got.pop("cells"), got.pop("loads")
    want = cli_json("partition", FIG8, "--set", "stop.restitution=0.0", "--params",
                    "excitation.frequency,excitation.amplitude", "--range1", "2.8,5", "--steps1", "1",
                    "--range2", "1.05,12", "--from2", "1.5", "--sticking-fraction", "0.5")
    assert got == want
    assert len(crossings) == sum(len(c["crossings"]) for c in want["columns"]) > 0
    assert len(boundaries) == sum(len(c["bifurcations"]) for c in want["columns"])
    assert list(cells["value2"]) == [x["value2"] for c in want["columns"] for x in c["points"]]
    assert list(loads["mean_force"][:, 0]) == [x["loads"][0]["mean_force"] for c in want["columns"] for x in c["points"]]
    p = vibro.read(out)["partition"]
    assert np.array_equal(p["crossing_value2"], crossings["value2"])
    assert list(p["boundary_kind"]) == list(boundaries["kind"])
    assert p.attrs["param1"] == "excitation.frequency"


def test_partition_bad_range_is_value_error():
    with pytest.raises(ValueError, match=r"range1: expected A,B with A < B"):
        vibro.partition(FIG8, ("excitation.frequency", "excitation.amplitude"), (5, 2.8), (1.05, 12), [0.5])
