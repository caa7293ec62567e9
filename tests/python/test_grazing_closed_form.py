"""A grazing met from the side of its slow impact is located where that impact's speed vanishes
(docs/orbits.md, "Through a grazing"), against a closed form, on a 1-DOF damped linear oscillator
with one rigid stop written here:

    x'' + 2 zeta x' + x = f sin(w t),  x <= d  (a stop above at d = 1, restitution 0.8).

The truth: its non-impacting periodic orbit is x = A sin(w t - phi) with
A = f / sqrt((1 - w^2)^2 + (2 zeta w)^2), and it grazes the stop exactly when A = d:
f_g = d sqrt((1 - w^2)^2 + (2 zeta w)^2).

`vibro continue` starts on the one-impact orbit at f = 1.02 f_g (the transient's attractor, no
hand-picked state) and goes down in f:
- w = 0.5: the branch turns at a fold just below f_g and comes back up towards f_g as the impact
  slows; it reaches f_g and turns back along the free orbit (a grazing fold);
- w = 0.8: the branch passes a flip, then its impact slows to f_g and the branch goes on past it
  along the free orbit.
Checked in both: one grazing, within 1e-10 of f_g and within its own bracket; the slow impact's
speed at the located point below the stated tolerance (1e-5 of the contact's largest speed); the
orbits past it have no impact and are the closed-form orbit (amplitude A(f) within 1e-9) on the
side of f_g where A < d. Before this (main at 178b13f) both branches ended with a "grazing" where
the impact still had 3.7e-5 and 3.9e-4 of its scale, 3.9e-5 and 4.8e-6 away from f_g.
"""
import json
import math
import os
import re
import subprocess

import h5py
import numpy as np
import pytest

CLI = os.environ.get("VIBRO_CLI", "")
ZETA, D, R = 0.05, 1.0, 0.8
TOLERANCE = 1e-5  # kGrazingTolerance (src/analysis/continuation.cpp, docs/orbits.md)

SCENE = """title = "1-DOF damped linear oscillator, one stop at d = 1 above (grazing closed form)"
[structure]
mass           = [[1.0]]
stiffness      = [[1.0]]
forcing_dof    = 0
damping_ratios = [{zeta}]
[[contact]]
dof         = 0
side        = "above"
position    = {d}
restitution = {r}
[excitation]
amplitude = 0.5
frequency = 0.5
[initial]
displacement = [0.0]
velocity     = [0.0]
[run]
periods = 200
"""


def denominator(w):
    return math.sqrt((1 - w * w) ** 2 + (2 * ZETA * w) ** 2)


def f_grazing(w):
    return D * denominator(w)


def vibro(*args):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr
    return p.stdout


@pytest.fixture(scope="module", params=[(0.5, "back"), (0.8, "past")], ids=["w0.5-fold", "w0.8-past"])
def branch(request, tmp_path_factory):
    w, through = request.param
    d = tmp_path_factory.mktemp(f"graze{w}")
    scene = d / "osc.toml"
    scene.write_text(SCENE.format(zeta=ZETA, d=D, r=R))
    fg = f_grazing(w)
    out = d / "branch.h5"
    j = json.loads(vibro("continue", scene, "--set", f"excitation.frequency={w}", "--set",
                         f"excitation.amplitude={1.02 * fg!r}", "--param", "excitation.amplitude",
                         "--to", repr(0.9 * fg), "--json", "--out", out, "--force"))
    return w, through, fg, j, out


def test_the_grazing_is_located_at_the_closed_form(branch):
    w, through, fg, j, _ = branch
    g = [b for b in j["bifurcations"] if b["kind"] == "grazing"]
    assert len(g) == 1, [(b["kind"], b["value"]) for b in j["bifurcations"]]
    g = g[0]
    assert abs(g["value"] - fg) < 1e-10, (g["value"], fg)
    assert abs(g["value"] - fg) <= g["bracket"], (g["value"] - fg, g["bracket"])
    assert g["through"] == through
    assert g["events_before"] == "I" and not g["events_after"]


def test_the_slow_impact_is_below_the_tolerance_where_it_is_located(branch):
    _, _, fg, j, _ = branch
    g = [b for b in j["bifurcations"] if b["kind"] == "grazing"][0]
    m = re.search(r"falls to ([0-9.e+-]+) \(([0-9.e+-]+) of the contact's largest speed; grazing tolerance ([0-9.e+-]+)\)",
                  g["detail"])
    assert m, g["detail"]
    speed, relative, tolerance = (float(x) for x in m.groups())
    assert tolerance == TOLERANCE
    assert 0 < relative < TOLERANCE
    assert speed == pytest.approx(g["new_impact_speed"], rel=1e-2)
    # The speed is linear in the distance to the grazing (docs/orbits.md, "Near a grazing"), and
    # that orbit lies at new_impact_distance from the closed-form grazing.
    assert g["new_impact_distance"] < 1e-6


def test_the_orbits_past_it_are_the_free_closed_form_orbit(branch):
    w, _, fg, j, out = branch
    with h5py.File(out) as f:
        b = f["branch"]
        value, q, qd = b["value"][:], b["q"][:, 0], b["q_dot"][:, 0]
        off = b["impact_offsets"][:]
    k = [b for b in j["bifurcations"] if b["kind"] == "grazing"][0]["point"]
    free = [i for i in range(k + 1, len(value)) if off[i + 1] == off[i]]
    assert len(free) >= 3 and free[0] == k + 1, (k, len(value))
    assert value[-1] == pytest.approx(0.9 * fg, rel=1e-12)  # on to the end value
    for i in free:
        assert value[i] <= fg + 1e-12  # the side where A < d
        amplitude = math.hypot(q[i], qd[i] / w)
        assert abs(amplitude - value[i] / denominator(w)) < 1e-9, (value[i], amplitude)
    # Every point before it is an impacting orbit.
    assert all(off[i + 1] > off[i] for i in range(k + 1))


def test_python_locates_it_too(tmp_path):
    vibro_py = pytest.importorskip("vibro")
    scene_file = tmp_path / "osc.toml"
    scene_file.write_text(SCENE.format(zeta=ZETA, d=D, r=R))
    w = 0.5
    fg = f_grazing(w)
    scene = vibro_py.load_scene(str(scene_file), set={"excitation.frequency": w, "excitation.amplitude": 1.02 * fg})
    b = vibro_py.continue_(scene, "excitation.amplitude", 0.9 * fg)
    g = [x for x in b["bifurcations"] if x["kind"] == "grazing"]
    assert len(g) == 1
    assert abs(g[0]["value"] - fg) < 1e-10 and abs(g[0]["value"] - fg) <= g[0]["bracket"]
    assert g[0]["through"] == "back" and 0 < g[0]["new_impact_speed"] < 1e-5
