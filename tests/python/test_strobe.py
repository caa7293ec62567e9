"""The stroboscopic state of a branch point (`strobe`, docs/output.md): every contact's coordinate
at t = initial.time (mod the orbit's period), wherever the section sits (issue: the branch panel's
x_B at the section jumps where the section moves).

Truth, derived here with mpmath (no vibro code): the symmetric two-impact orbit of the two-sided
oscillator x'' + x = a sin(w t), stops at -1 and +1 (restitution r), is the fixed point of the
half map G of test_continuation_precision.py; its flight from the impact on +1 at t1 lasts half a
period and the other half is its mirror image, x(t + T/2) = -x(t), so x at any time is a closed
form. The phase convention against the sweep: `vibro sweep` records x_B at t0 + kT, and on a
stable orbit its last record is the branch's strobe.

ctest runs this file within python.pytest, with VIBRO_CLI set to the built `vibro`.
"""
import csv
import json
import os
import subprocess
import sys

import h5py
import mpmath as mp
import numpy as np
import pytest

from test_continuation_precision import SCENE, flight, symmetric_orbit

CLI = os.environ.get("VIBRO_CLI", "")
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def vibro(*args, code=0):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=900)
    assert p.returncode == code, p.stderr
    return p.stdout


@pytest.fixture(autouse=True)
def _keep_mpmath_precision():
    """mpmath's working precision is global: left as found for the other test files."""
    dps = mp.mp.dps
    yield
    mp.mp.dps = dps


def strobe_truth(a, r, w, t_s):
    """x(t_s) on the symmetric orbit at amplitude a."""
    phi, V = symmetric_orbit(a, r, w)
    t1, half = phi / w, mp.pi / w
    tau = mp.fmod(t_s - t1, 2 * half)
    if tau < 0:
        tau += 2 * half
    if tau < half:
        return flight(1, -r * V, t1, a, w, tau)[0]
    return -flight(1, -r * V, t1, a, w, tau - half)[0]


def test_strobe_is_the_orbit_at_the_start_phase(tmp_path):
    mp.mp.dps = 30
    r, w = mp.mpf("0.7"), mp.mpf("2.2")
    a0 = mp.mpf("3.0")
    phi, V = symmetric_orbit(a0, r, w)
    # The start (and so the strobe's phase): a free state a quarter period after the impact on +1,
    # at a time that is no multiple of the period.
    t0 = phi / w + mp.pi / (2 * w)
    x0, v0 = flight(1, -r * V, phi / w, a0, w, mp.pi / (2 * w))
    path = tmp_path / "two_sided.toml"
    path.write_text(SCENE.format(r=float(r), a=float(a0), w=float(w), t0=float(t0), x0=float(x0), v0=float(v0)))
    out = tmp_path / "b.h5"
    b = json.loads(vibro("continue", path, "--param", "excitation.amplitude", "--transient", 0, "--to", 3.4,
                         "--out", out, "--json"))
    pts = b["points"]
    assert len(pts) > 10
    phases = {round(p["section_phase"], 9) for p in pts}
    for p in pts:
        truth = strobe_truth(mp.mpf(p["value"]), r, w, mp.mpf(float(t0)))
        assert len(p["strobe"]) == 2 and p["strobe"][0] == p["strobe"][1], p  # both contacts on q0
        assert abs(p["strobe"][0] - truth) < 1e-13, (p["value"], p["strobe"], mp.nstr(truth, 17), phases)
    # The same in the branch file, and in the CSV of scripts/branch_to_csv.py, which validate reads.
    with h5py.File(out) as f:
        s = f["branch/strobe"][()]
    assert s.shape == (len(pts), 2)
    assert np.array_equal(s, np.array([p["strobe"] for p in pts]))
    csv_path = tmp_path / "b.csv"
    subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "branch_to_csv.py"), out, csv_path], check=True)
    rows = list(csv.DictReader(open(csv_path)))
    assert [float(x["strobe_0"]) for x in rows] == [p["strobe"][0] for p in pts]
    assert [float(x["strobe_1"]) for x in rows] == [p["strobe"][1] for p in pts]
    v = json.loads(vibro("validate", path, csv_path, "--param", "excitation.amplitude", "--json"))
    assert v["disagreements"] == 0, v


TUBE = """
[structure]
mass = [[2.0, 0.0], [0.0, 1.0]]
stiffness = [[4.0, -1.0], [-1.0, 1.0]]
forcing_dof = 0
damping_ratios = [0.02, 0.02]
[[contact]]
dof = 1
side = "below"
position = -0.1
restitution = 0.7
[[contact]]
dof = 1
side = "above"
position = 0.1
restitution = 0.7
[excitation]
amplitude = 0.3
frequency = {w}
[initial]
displacement = [0.0, 0.0]
velocity = [0.0, 0.0]
"""


def test_strobe_does_not_jump_where_the_section_moves(tmp_path):
    """A tube in a loose support, continued in w from 0.9 to 1.6: the section moves (x_B at it
    jumps), the strobe does not; on the stable orbit at the start it is what a sweep records."""
    path = tmp_path / "tube.toml"
    path.write_text(TUBE.format(w=0.9))
    b = json.loads(vibro("continue", path, "--param", "excitation.frequency", "--to", 1.6, "--json"))
    pts = b["points"]
    value = np.array([p["value"] for p in pts])
    strobe = np.array([p["strobe"] for p in pts])
    x_b = np.array([p["x_B"] for p in pts])
    assert np.all(np.isfinite(strobe)) and strobe.shape == (len(pts), 2)
    assert np.array_equal(strobe[:, 0], strobe[:, 1])  # both contacts constrain q1
    moved = [i for i in range(1, len(pts)) if abs(pts[i]["section_phase"] - pts[i - 1]["section_phase"]) > 1e-3]
    assert moved, "the section never moved: the test shows nothing"
    # Where the section moves x_B at it jumps; the strobe changes no more than its neighbours do.
    slope = np.abs(np.diff(strobe[:, 0])) / np.maximum(np.abs(np.diff(value)), 1e-300)
    typical = np.median(slope)
    for i in moved:
        assert slope[i - 1] < 20 * typical + 1e-9, (i, value[i], slope[i - 1], typical)
    assert max(abs(x_b[i] - x_b[i - 1]) for i in moved) > 0.01  # what the old panel showed
    # The sweep at the start (a stable orbit, reached from rest) records x_B(kT) = the strobe.
    assert pts[0]["stable"]
    s = json.loads(vibro("sweep", path, "--param", "excitation.frequency", "--from", 0.9, "--to", 0.9,
                         "--steps", 1, "--one-way", "--set", "run.periods=400", "--json"))
    last = s["points"][0]["x_B"][-1]
    assert abs(last - strobe[0, 0]) < 1e-7, (last, strobe[0, 0])


def test_plot_and_python_show_the_strobe(tmp_path):
    """`vibro plot`'s branch panel draws /branch/strobe (not x_B at the section), and the Python
    package's continue_ gives it as an array (points, contacts)."""
    path = tmp_path / "tube.toml"
    path.write_text(TUBE.format(w=0.9))
    out = tmp_path / "tube.h5"
    b = json.loads(vibro("continue", path, "--param", "excitation.frequency", "--to", 1.3, "--out", out, "--json"))
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import vibro_plot
    fig, ax = plt.subplots()
    with h5py.File(out) as f:
        vibro_plot.draw_strobe(ax, f)
        strobe = f["branch/strobe"][()]
    drawn = np.concatenate([ln.get_ydata() for ln in ax.get_lines() if len(ln.get_ydata()) > 1 and ln.get_linestyle() in ("-", "--")])
    assert np.isin(strobe[:, 0], drawn).all()
    assert "t_0 + kT" in ax.get_ylabel() and "contacts 0, 1" in ax.get_ylabel(), ax.get_ylabel()
    plt.close(fig)
    # One contact sequence along the whole branch up to 1.3, below the grazing at 1.3646 (0:impact
    # 1:impact, the section moving does not change it): no dotted line and no key saying the
    # sequence changes (issue 37, item 8). Past the grazing the branch goes on with 0:impact*2
    # 1:impact, a true change.
    fig, ax = plt.subplots()
    with h5py.File(out) as f:
        vibro_plot.mark_sequences(fig, ax, f)
        assert len({bytes(s) if not isinstance(s, str) else s for s in f["branch/sequence"][()]}) == 1
    assert not [ln for ln in ax.get_lines() if ln.get_linestyle() == ":" and len(ln.get_xdata()) > 0]
    assert "contact sequence changes" not in ax.get_legend_handles_labels()[1], ax.get_legend_handles_labels()[1]
    plt.close(fig)
    vibro_py = pytest.importorskip("vibro")
    d = vibro_py.continue_(str(path), "excitation.frequency", 1.3)
    assert d["strobe"].shape == (len(b["points"]), 2)
    assert np.array_equal(d["strobe"], np.array([p["strobe"] for p in b["points"]]))
