"""numpy in: vibro.score and vibro.validate take their tables as arrays (a structured array, a dict of
1-D arrays, a 2-D array with columns=[...]) as well as CSV files, with the same result as the file
of the same rows; a wrong argument says what type was expected. They used to take the array's
text as a file name ("[(0. , 3, 0.) …]: cannot open the events file")."""
import csv
import os
import subprocess
import sys

import numpy as np
import pytest

import vibro
from conftest import SCENES

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
BENCH = os.path.join(ROOT, "data", "benchmarks")
CHATTER = os.path.join(BENCH, "chatter_1dof.toml")
EVENTS = os.path.join(BENCH, "chatter_1dof.csv")
FIG8 = os.path.join(SCENES, "fig08_preload.toml")


def _without_arrays(d):
    return {k: v for k, v in d.items() if k != "table"}


def _events_rows():
    with open(EVENTS) as f:
        return [r for r in csv.DictReader(f)]


@pytest.fixture(scope="module")
def from_file():
    return vibro.score(CHATTER, EVENTS)


def test_score_structured_array_equals_file(from_file):
    rows = _events_rows()
    a = np.array([(float(r["t"]), r["kind"], float(r["velocity"])) for r in rows],
                 dtype=[("t", "f8"), ("kind", "U12"), ("velocity", "f8")])
    got = vibro.score(CHATTER, a)
    assert _without_arrays(got) == _without_arrays(from_file)
    assert np.array_equal(got["table"], from_file["table"])
    assert got["kinds"][0]["theirs"] > 0


def test_score_dict_and_2d_array_equal_file(from_file):
    rows = _events_rows()
    t = np.array([float(r["t"]) for r in rows])
    kind = np.array([vibro.EVENT_KINDS[r["kind"]] for r in rows], dtype=np.int8)  # as numbers 1..5
    v = np.array([float(r["velocity"]) for r in rows])
    assert _without_arrays(vibro.score(CHATTER, {"t": t, "kind": kind, "velocity": v})) == _without_arrays(from_file)
    m = np.column_stack([t, kind, v])
    assert _without_arrays(vibro.score(CHATTER, m, columns=["t", "kind", "velocity"])) == _without_arrays(from_file)


def test_score_own_events_match_exactly():
    """vibro's own events (simulate(...).events) are a table score takes as it is."""
    scene = vibro.load_scene(CHATTER, set={"run.periods": 4})
    events = vibro.simulate(scene).events
    r = vibro.score(scene, events)
    assert r["first_divergence"] is None
    for k in r["kinds"]:
        assert k["matched"] == k["theirs"], k
        assert k["max_time_error"] == 0


@pytest.mark.parametrize("events, columns, message", [
    (42, None, "events: expected a file name (str or os.PathLike), a numpy structured array, a dict of 1-D arrays, "
               "a 2-D array with columns=[...], or a pandas DataFrame; got int"),
    (np.zeros((3, 2)), None, "events: a 2-D array of 2 columns needs their names: columns=[...]"),
    (np.zeros(3), None, "events: expected a file name"),
    ({"t": [0.0, 1.0], "kind": [1, 1], "x": [0, 0]}, None, "events: unknown column 'x'"),
    ({"t": [0.0, 1.0]}, None, "events: missing column 'kind'"),
    ({"t": [0.0, np.nan], "kind": [1, 1]}, None, "events row 1 (t): nan is not a finite number"),
    ({"t": [0.0, 1.0], "kind": [1, 9]}, None, "events row 1 (kind): '9' is not impact"),
    ({"t": [0.0, 1.0], "kind": ["impact", "bounce"]}, None, "events row 1 (kind): 'bounce' is not impact"),
    ({"t": [0.0, 1.0], "kind": [1, 1], "velocity": [0, np.inf]}, None, "events row 1 (velocity): inf is not"),
    ({"t": ["a", "b"], "kind": [1, 1]}, None, "events column 't': expected numbers, got an array of dtype <U1"),
    ({"t": [], "kind": []}, None, "events: no rows"),
    ({"t": [0.0], "kind": [1]}, ["t", "kind"], "columns: only for a 2-D array events"),
])
def test_score_bad_table_is_value_error(events, columns, message):
    with pytest.raises(ValueError) as e:
        vibro.score(CHATTER, events, columns=columns)
    assert str(e.value).startswith(message), str(e.value)


@pytest.fixture(scope="module")
def branch_csv(tmp_path_factory):
    """A branch of vibro's own (Fig. 8 at r = 0) exported to CSV (scripts/branch_to_csv.py)."""
    d = tmp_path_factory.mktemp("branch")
    scene = vibro.load_scene(FIG8, set={"stop.restitution": 0.0})
    vibro.continue_(scene, "excitation.amplitude", 3.0, max_points=6, out=d / "b.h5")
    subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "branch_to_csv.py"), str(d / "b.h5"),
                    str(d / "b.csv")], check=True)
    return scene, d / "b.csv"


def test_validate_arrays_equal_file(branch_csv):
    scene, path = branch_csv
    want = vibro.validate(scene, path, "excitation.amplitude")
    assert len(want["points"]) > 2 and want["disagreements"] == 0
    a = np.genfromtxt(path, delimiter=",", names=True, comments="#")
    got = vibro.validate(scene, a, "excitation.amplitude")
    assert _without_arrays(got) == _without_arrays(want)
    # A dict whose states are (N, n) arrays, as structured fields of shape (n,) are.
    s = np.empty(len(a), dtype=[("value", "f8"), ("time", "f8"), ("displacement", "f8", (1,)), ("velocity", "f8", (1,))])
    s["value"], s["time"] = a["value"], a["time"]
    s["displacement"][:, 0], s["velocity"][:, 0] = a["displacement_1"], a["velocity_1"]
    got = vibro.validate(scene, s, "excitation.amplitude")
    assert [p["verdict"] for p in got["points"]] == [p["verdict"] for p in want["points"]]
    # A refuted claim is refuted from arrays too.
    wrong = {name: a[name].copy() for name in a.dtype.names}
    wrong["displacement_1"][1] += 0.1
    got = vibro.validate(scene, wrong, "excitation.amplitude")
    assert got["points"][1]["verdict"] != "confirmed" and got["disagreements"] == 1


@pytest.mark.parametrize("change, message", [
    (lambda d: d.pop("time"), "branch: missing column 'time'"),
    (lambda d: d.update(speed=d["value"]), "branch: unknown column 'speed'"),
    (lambda d: d["value"].__setitem__(1, np.nan), "branch row 1 (value): nan is not a finite number"),
    (lambda d: d.update(stable=np.full(len(d["value"]), 2.0)), "branch row 0 (stable): 2 is not 0 or 1"),
    (lambda d: d.update(period=np.full(len(d["value"]), 1.5)), "branch row 0 (period): 1.5 is not a whole number"),
    (lambda d: d["time"].__setitem__(2, np.inf), "branch row 2 (time): inf is not a finite number"),
    (lambda d: d.update(time=d["time"][:-1]), "branch: column 'time' has "),
])
def test_validate_bad_table_is_value_error(branch_csv, change, message):
    scene, path = branch_csv
    a = np.genfromtxt(path, delimiter=",", names=True, comments="#")
    d = {name: a[name].copy() for name in a.dtype.names}
    change(d)
    with pytest.raises(ValueError) as e:
        vibro.validate(scene, d, "excitation.amplitude")
    assert str(e.value).startswith(message), str(e.value)


def test_states_as_arrays():
    """States given as numpy arrays: the initial state of a scene and the guess of an orbit."""
    scene = vibro.load_scene(FIG8, set={"initial.displacement": np.array([1.3]), "initial.velocity": np.array([0.0]),
                                        "run.periods": 5})
    assert "displacement = [ 1.3 ]" in scene.text
    by_array = vibro.orbit(FIG8, guess=np.array([0.5, 0.1]))
    assert by_array == vibro.orbit(FIG8, guess=(0.5, 0.1))
    with pytest.raises(ValueError, match=r"guess .*: expected PHASE or \(PHASE, VELOCITY\)"):
        vibro.orbit(FIG8, guess=np.zeros(3))


def test_event_kinds_both_ways():
    assert vibro.EVENT_KINDS[4] == "release" and vibro.EVENT_KINDS["release"] == 4
    assert all(vibro.EVENT_KINDS[vibro.EVENT_KINDS[k]] == k for k in range(1, 6))
    assert list(vibro.EVENT_KINDS) == [1, 2, 3, 4, 5] and "stick" in vibro.EVENT_KINDS
    assert vibro.EVENT_KINDS.get("grazing") == 5 and vibro.EVENT_KINDS.get("bounce") is None
    with pytest.raises(KeyError):
        vibro.EVENT_KINDS["bounce"]
