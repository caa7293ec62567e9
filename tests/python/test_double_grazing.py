"""The tube's four-impact branch reaches the grazing of both stops at once and goes on along the
two-impact orbit (docs/orbits.md, "Through a grazing"), on data/scenes/tube_loose_support.toml,
against the independent numpy flow of tests/python/test_continuation_jump.py (exact linear flow,
impacts bisected to the last bit).

The orbit: the symmetric four-impact orbit `0:impact*2 1:impact*2` continued from its attractor at
omega = 0.52 up round its fold at 0.6179 comes back towards omega_g = 0.569366, unstable, with two
slow impacts (one per stop, mirror images half a period apart, equal speeds). Before, the march that
follows a slow impact to its grazing held one of the two speeds, the other's square-root term made
Newton stall near 1e-4 of the contact's speed, and the branch ended at omega = 0.5704 ("the
corrector converges only to another orbit"). It now marches on the half map z -> -Phi_{T/2}(z),
which holds one slow impact per half period.

The truth, without vibro's code: the grazing omega_g is where the symmetric two-impact orbit (Newton
on the numpy period map) has the closest approach of q_1 to -0.1 inside its flight after the impact
on that stop equal to zero (by the symmetry, +0.1 too); that approach is smooth and linear in
omega - omega_g, so omega_g is the root of its quadratic through three orbits 1e-4..3e-4 above,
refined by the line through two orbits 1e-6 and 2e-6 above that root.

Checked:
- the branch from 0.52 is marked `grazing` at omega_g within 1e-9 of the numpy root (measured 1.2e-10), with both
  sequences (0:impact*2 1:impact*2 -> 0:impact 1:impact), both contacts named, and goes on (a
  grazing fold: the branch turns back) along two-impact orbits, fixed points of the numpy map with
  two impacts; no `another orbit` end at 0.5704;
- the four-impact orbits within 2e-3 of omega_g are fixed points of the numpy map with
  four impacts, whose two slow impacts (one per stop) have equal speeds; the speed v against
  d = omega - omega_g over 3-4 of them (5e-5 < d < 2e-3, where the numpy map resolves the
  slow impacts) fits v ~ d^p with p = 1 within 0.05: the new impact speed
  grows linearly with the parameter distance (the square root is of the depth, v = sqrt(2 a x),
  x ~ d^2: docs/orbits.md, "Near a grazing"), not like sqrt(d).
The build before fails the first (the branch ends at 0.5704 naming the two-impact orbit).
"""
import importlib.util
import json
import os

import h5py
import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
TUBE = os.path.join(HERE, "..", "..", "data", "scenes", "tube_loose_support.toml")
KEY = "excitation.frequency"

_spec = importlib.util.spec_from_file_location("continuation_jump_truth", os.path.join(HERE, "test_continuation_jump.py"))
_truth = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_truth)
Tube, R, bisect = _truth.Tube, _truth.R, _truth.bisect


def vibro(*args):
    return _truth.vibro(*args, timeout=900)


def impacts(tube, z, t0):
    """(contact, time, state just after) of each impact of one period from z at t0, in order."""
    events = []
    tube.period_map(z, t0, events)
    t, z = t0, np.array(z, float)
    out = []
    for j, ph, _ in events:
        tk = t + ((ph - tube.om * t) % (2 * np.pi)) / tube.om
        zk = tube.flow(z, t, [tk - t])[0].copy()
        zk[3] = -R * zk[3]
        out.append((j, tk, zk))
        t, z = tk, zk
    return events, out


def closest_approach(tube, z, t0):
    """The closest approach of q_1 to the stop at -0.1 inside the flight after the impact on it: the
    interior minimum of q_1 (q_1' from - to +, bisected), plus 0.1."""
    _, imp = impacts(tube, z, t0)
    for k, (j, tk, zk) in enumerate(imp):
        if j != 0:
            continue
        tn = imp[(k + 1) % len(imp)][1]
        if tn <= tk:
            tn += 2 * np.pi / tube.om
        s = np.linspace(0, tn - tk, 20001)[1:-1]
        qd = tube.flow(zk, tk, s)[:, 3]
        i = np.nonzero((qd[:-1] < 0) & (qd[1:] >= 0))[0]
        assert len(i), "no interior minimum"
        u = bisect(lambda x: -tube.flow(zk, tk, [x])[0][3], s[i[0]], s[i[0] + 1])
        return tube.flow(zk, tk, [u])[0][1] + 0.1
    raise AssertionError("no impact on contact 0")


@pytest.fixture(scope="module")
def branch(tmp_path_factory):
    out = tmp_path_factory.mktemp("double") / "b.h5"
    p = vibro("continue", TUBE, "--set", f"{KEY}=0.52", "--param", KEY, "--to", 1.6, "--json", "--out", out)
    d = json.loads(p.stdout)
    with h5py.File(out, "r") as f:
        g = f["branch"]
        b = {k: g[k][:] for k in ("value", "q", "q_dot", "section_time", "sequence", "max_multiplier")}
    b["sequence"] = [s.decode() if isinstance(s, bytes) else s for s in b["sequence"]]
    return d, b


@pytest.fixture(scope="module")
def omega_g(branch):
    """The grazing by the numpy map, from the branch's first two-impact orbit past it as a seed."""
    d, b = branch
    k = next((i for i, s in enumerate(b["sequence"]) if s == "0:impact 1:impact"), None)
    assert k is not None, ("the branch never reaches the two-impact orbit", d["end"])
    z = np.concatenate([b["q"][k], b["q_dot"][k]])
    phase = b["value"][k] * b["section_time"][k]

    def approach(om, z):
        tube = Tube(om)
        t0 = phase / om
        z = tube.newton(z, t0)
        events = []
        assert np.abs(tube.period_map(z, t0, events) - z).max() < 1e-12, om
        assert len(events) == 2, (om, events)
        return closest_approach(tube, z, t0), z

    # Down from the seed to 3e-4 above the grazing in small steps (Newton follows the orbit).
    guess = 0.569366
    for om in np.arange(b["value"][k], guess + 3e-4, -2e-4):
        _, z = approach(om, z)
    pts = []
    for d in (3e-4, 2e-4, 1e-4):
        m, z = approach(guess + d, z)
        pts.append((guess + d, m))
    c = np.polyfit([p[0] - guess for p in pts], [p[1] for p in pts], 2)
    root = guess + min((r.real for r in np.roots(c) if abs(r.imag) < 1e-14), key=abs)
    w1, m1 = root + 2e-6, approach(root + 2e-6, z)[0]
    w2, m2 = root + 1e-6, approach(root + 1e-6, z)[0]
    assert m1 > 0 and m2 > 0, (m1, m2)
    return w2 - m2 * (w1 - w2) / (m1 - m2)


def test_the_branch_goes_through_the_double_grazing(branch, omega_g):
    d, b = branch
    assert abs(omega_g - 0.569366334827) < 1e-9, omega_g  # prove.md's proven interval, as a sanity check
    assert "another orbit" not in d["end"], d["end"]
    graz = [x for x in d["bifurcations"] if x["kind"] == "grazing" and abs(x["value"] - 0.5694) < 1e-3]
    assert len(graz) == 1, d["bifurcations"]
    g = graz[0]
    assert abs(g["value"] - omega_g) < 1e-9, (g["value"], omega_g)
    assert g["sequence_before"] == "0:impact*2 1:impact*2" and g["sequence_after"] == "0:impact 1:impact", g
    assert g["through"] == "back", g  # the two-impact orbit is on the same side: a grazing fold
    assert "contacts 0 and 1" in g["detail"], g["detail"]
    # Past it: two-impact orbits of the numpy map, the first few and one farther on.
    k = next(i for i, s in enumerate(b["sequence"]) if s == "0:impact 1:impact")
    assert b["value"][k] > omega_g
    for i in (k, k + 1, k + 5):
        om, t0 = float(b["value"][i]), float(b["section_time"][i])
        tube = Tube(om)
        z = np.concatenate([b["q"][i], b["q_dot"][i]])
        events = []
        res = np.abs(tube.period_map(z, t0, events) - z).max() / (1 + np.abs(z).max())
        assert res < 1e-9 * max(1.0, b["max_multiplier"][i]), (om, res)
        assert len(events) == 2 and {e[0] for e in events} == {0, 1}, (om, events)


def test_the_new_impacts_grow_linearly_with_the_distance(branch, omega_g):
    _, b = branch
    k = next(i for i, s in enumerate(b["sequence"]) if s == "0:impact 1:impact")
    dist, speed = [], []
    for i in range(k - 1, 0, -1):
        if b["sequence"][i] != "0:impact*2 1:impact*2":
            break
        om, t0 = float(b["value"][i]), float(b["section_time"][i])
        d = om - omega_g
        if not 5e-5 < d < 2e-3:
            continue
        tube = Tube(om)
        z = np.concatenate([b["q"][i], b["q_dot"][i]])
        events = []
        # A grid fine enough to see the slow impacts' dips below the stops.
        res = np.abs(tube.period_map(z, t0, events, n=40000) - z).max() / (1 + np.abs(z).max())
        assert res < 1e-9 * max(1.0, b["max_multiplier"][i]), (om, res)
        assert len(events) == 4, (om, events)
        slow = sorted(events, key=lambda e: abs(e[2]))[:2]
        assert {e[0] for e in slow} == {0, 1}, slow  # one per stop
        assert abs(abs(slow[0][2]) - abs(slow[1][2])) < 1e-6 * abs(slow[0][2]) + 1e-12, slow  # mirror images
        dist.append(d)
        speed.append(abs(slow[0][2]))
        if len(dist) == 4:
            break
    assert len(dist) >= 3, (dist, speed)
    p = np.polyfit(np.log(dist), np.log(speed), 1)[0]
    assert abs(p - 1.0) < 0.05, (p, dist, speed)
