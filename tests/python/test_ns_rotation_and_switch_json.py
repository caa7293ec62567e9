"""Neimark-Sacker points report their rotation number, and `continue --switch --json` says where it
switched (docs/orbits.md), on data/scenes/tube_loose_support.toml.

(a) The four-impact branch through omega = 0.569 (the grazing fold's loop, docs/orbits.md "Near a
    grazing") has a Neimark-Sacker point near 0.5725. By definition its complex pair is e^{+-i theta}:
    the orbit corrected at exactly the reported omega (`--from FILE --point K --to omega_NS`, a point
    held at fixed omega) has that pair on the unit circle (|mu| - 1 < 1e-9) and arg(mu)/2pi equal to
    the reported rotation_number to 1e-9, in JSON and in HDF5 (/bifurcations/rotation_number, NaN
    for the other kinds); the rotation number also lies between the pair's angles at the branch
    points on either side (where |mu| brackets 1).
(b) The pitchfork of the symmetric branch near omega = 0.9554: `--switch --json` holds "switch" with
    the kind, the located value (the stored bifurcation's to 1e-9), the first orbit's omega on the
    side "direction" says, the period and the half taken.
"""
import json
import math
import os
import subprocess

import h5py
import numpy as np
import pytest

CLI = os.environ.get("VIBRO_CLI", "")
HERE = os.path.dirname(os.path.abspath(__file__))
TUBE = os.path.join(HERE, "..", "..", "data", "scenes", "tube_loose_support.toml")
KEY = "excitation.frequency"


def vibro(*args):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr
    return p.stdout


def pair(point):
    mu = [complex(a, b) for a, b in point["floquet_multipliers"]]
    return max((m for m in mu if abs(m.imag) > 1e-9), key=abs)


def test_neimark_sacker_rotation_number(tmp_path):
    out = tmp_path / "four.h5"
    b = json.loads(vibro("continue", TUBE, "--set", f"{KEY}=0.569", "--param", KEY, "--to", 0.65, "--step", 0.002,
                         "--out", out, "--force", "--json"))
    ns = [x for x in b["bifurcations"] if x["kind"] == "neimark-sacker"]
    assert len(ns) == 1
    w, rho = ns[0]["value"], ns[0]["rotation_number"]
    assert abs(w - 0.57245) < 1e-4 and 0 < rho < 0.5
    assert "rotation number" in ns[0]["detail"]
    assert all("rotation_number" not in x for x in b["bifurcations"] if x["kind"] != "neimark-sacker")
    with h5py.File(out) as f:
        kinds = [k.decode() if isinstance(k, bytes) else k for k in f["bifurcations/kind"][:]]
        rot = f["bifurcations/rotation_number"][:]
        value = f["branch/value"][:]
    for k, r in zip(kinds, rot):
        assert (k == "neimark-sacker") == math.isfinite(r)
    assert rot[kinds.index("neimark-sacker")] == rho
    # The pair's angle at the points on either side brackets the rotation number.
    # The NS point is on the way back from the fold at 0.6179 down to the double grazing at 0.569366,
    # where the branch (since the half-map march, docs/orbits.md "A mirror pair") turns back onto the
    # two-impact orbit and goes up to 0.65: the neighbours are taken on the way down only.
    vals = np.array([p["value"] for p in b["points"]])
    turn = int(np.nonzero(np.diff(vals) < 0)[0][0])
    low = turn + int(np.argmin(vals[turn:]))
    ret = list(range(turn, low + 1))
    assert all(b["points"][k]["sequence"] == "0:impact*2 1:impact*2" for k in ret[:-1])
    above = max((k for k in ret if vals[k] > w), key=lambda k: -vals[k])
    below = max((k for k in ret if vals[k] < w), key=lambda k: vals[k])
    mods = [abs(pair(b["points"][k])) for k in (above, below)]
    assert (mods[0] - 1) * (mods[1] - 1) < 0
    angles = sorted(abs(np.angle(pair(b["points"][k]))) / (2 * np.pi) for k in (above, below))
    assert angles[0] < rho < angles[1]
    # At exactly omega_NS the pair is on the unit circle at the reported angle.
    at = json.loads(vibro("continue", TUBE, "--param", KEY, "--from", out, "--point", below, "--to", repr(w),
                          "--json"))
    assert at["end"] == "reached the end value"
    last = at["points"][-1]
    assert last["value"] == w
    mu = pair(last)
    assert abs(abs(mu) - 1) < 1e-9
    assert abs(abs(np.angle(mu)) / (2 * np.pi) - rho) < 1e-9


def test_switch_json_records_the_switch(tmp_path):
    out = tmp_path / "sym.h5"
    b = json.loads(vibro("continue", TUBE, "--param", KEY, "--to", 1.2, "--out", out, "--json"))
    bp = [x for x in b["bifurcations"] if x["kind"] == "branch-point"]
    assert bp and abs(bp[0]["value"] - 0.955443) < 1e-5
    vals = np.array([p["value"] for p in b["points"]])
    k = int(np.argmin(np.abs(vals - bp[0]["value"])))
    s = json.loads(vibro("continue", TUBE, "--param", KEY, "--from", out, "--point", k, "--switch", "--to", 1.0,
                         "--max-points", 20, "--json"))
    sw = s["switch"]
    assert sw["kind"] == "branch-point" and sw["period"] == 1
    assert abs(sw["at"] - bp[0]["value"]) < 1e-9
    assert sw["direction"] in (1, -1)
    assert (sw["start"] - sw["at"]) * sw["direction"] >= 0
    assert 0 < sw["distance"] < 1e-2 and sw["half"]
    assert s["points"][0]["value"] == sw["start"]
    plain = json.loads(vibro("continue", TUBE, "--param", KEY, "--to", 1.0, "--max-points", 3, "--json"))
    assert "switch" not in plain


def test_python_switch_and_rotation_number(tmp_path):
    vibro_py = pytest.importorskip("vibro")
    if not hasattr(vibro_py, "continue_"):
        pytest.skip("the vibro package is not built")
    out = tmp_path / "sym.h5"
    scene = vibro_py.load_scene(TUBE)
    b = vibro_py.continue_(scene, KEY, 1.2, out=str(out))
    bp = [x for x in b["bifurcations"] if x["kind"] == "branch-point"][0]
    vals = np.array([p["value"] for p in b["points"]])
    k = int(np.argmin(np.abs(vals - bp["value"])))
    s = vibro_py.continue_(scene, KEY, 1.0, max_points=10, from_=str(out), point=k, switch=True)
    cli = json.loads(vibro("continue", TUBE, "--param", KEY, "--from", out, "--point", k, "--switch", "--to", 1.0,
                           "--max-points", 10, "--json"))
    assert s["switch"] == cli["switch"]
    assert "switch" not in b
