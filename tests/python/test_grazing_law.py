"""The tube's lower grazing is a grazing fold, and the new impact speed grows LINEARLY with the
distance to it (docs/orbits.md, "Near a grazing"), on data/scenes/tube_loose_support.toml:

- the symmetric two-impact orbit, continued down from omega = 0.9, meets a grazing omega_g
  (both stops touched tangentially) with no orbit past it (the branch turns back there onto the
  four-impact orbit: test_through_grazing.py);
- the stable four-impact orbit found by a transient at omega = 0.569 < omega_g, continued upwards,
  turns at a fold near 0.618 and comes back towards omega_g as an unstable branch whose two new
  impacts (one per stop, the slowest two of the period) slow down as omega falls.

The truth is the fixed point of the square-root normal form, x = mu - c sqrt(x) (x the depth the
orbit without the new impact would reach, v ~ sqrt(x) the new impact's speed, mu the distance to
the grazing): sqrt(x) = mu/c + O(mu^2), so v = c1 (omega - omega_g) + O((omega - omega_g)^2), and
the speed vanishes exactly at the grazing of the OTHER branch. Checked: a quadratic fit of v against
omega - omega_g on the returning branch's last points has an intercept below 2e-6 (while a
square-root law v = k sqrt(omega - omega_g) would leave v/sqrt(distance) varying by >10 % over the
same points), and v/(omega - omega_g) is constant to 2 % there (1.058 to 1.070, down to 1.9e-5 from
the grazing, which the branch now reaches: test_double_grazing.py).
"""
import json
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


def test_new_impact_speed_is_linear_in_the_distance_to_the_grazing(tmp_path):
    down = json.loads(vibro("continue", TUBE, "--param", KEY, "--to", 0.4, "--json"))
    grazings = [b for b in down["bifurcations"] if b["kind"] == "grazing"]
    assert grazings, down["end"]
    w_g = grazings[0]["value"]  # the branch turns back there (tests/python/test_through_grazing.py)
    assert abs(w_g - 0.569366) < 1e-5

    out = tmp_path / "four.h5"
    vibro("continue", TUBE, "--set", f"{KEY}=0.569", "--param", KEY, "--to", 0.65, "--step", 0.002,
          "--out", out)
    with h5py.File(out) as f:
        b = f["branch"]
        value = b["value"][:]
        off = b["impact_offsets"][:]
        speeds = np.abs(b["impact_v_before"][:])
        contact = b["impact_contact"][:]
        kinds = [k.decode() if isinstance(k, bytes) else k for k in f["bifurcations"]["kind"][:]]
        bif = f["bifurcations"]["value"][:]
    assert "fold" in kinds and abs(bif[kinds.index("fold")] - 0.6179) < 1e-3
    assert value[0] < w_g  # the stable orbit lives below the grazing
    # The four-impact part, up to the grazing (where the branch now turns back onto the two-impact
    # orbit: tests/python/test_double_grazing.py); the returning branch from its fold, omega falling
    # towards omega_g.
    counts = off[1:] - off[:-1]
    stop = next((i for i, c in enumerate(counts) if c != 4), len(value))
    turn = int(np.argmax(value[:stop]))
    ret = np.arange(turn, stop)
    assert value[stop - 1] - w_g < 2e-3, "the returning branch does not come near the grazing"
    v = np.array([np.sort(speeds[off[k]:off[k + 1]])[:2] for k in ret])
    n_imp = np.array([off[k + 1] - off[k] for k in ret])
    near = (value[ret] - w_g < 0.01) & (n_imp == 4)
    assert near.sum() >= 8
    d = value[ret][near] - w_g
    vs = v[near]
    # Two new impacts, one per stop, of the same speed (the orbit stays symmetric).
    np.testing.assert_allclose(vs[:, 0], vs[:, 1], rtol=1e-6, atol=1e-9)  # atol: the march's slowest (v ~ 1e-5, DF ~ 1/v)
    c = [np.unique(contact[off[k]:off[k + 1]][np.argsort(speeds[off[k]:off[k + 1]])[:2]]).size for k in ret[near]]
    assert all(x == 2 for x in c)
    s = vs[:, 0]
    a0, a1, a2 = np.polynomial.polynomial.polyfit(d, s, 2)
    assert abs(a0) < 2e-6, (a0, a1, a2)  # v -> 0 at the grazing of the other branch
    close = d < 3e-3
    ratio = s[close] / d[close]
    # linear (up to the O(d) term: 1.058 at 3e-3 to 1.070 at 1.9e-5 with the march's orbits), not square root
    assert ratio.max() / ratio.min() - 1 < 2e-2, ratio
    sqrt_ratio = s / np.sqrt(d)
    assert sqrt_ratio.max() / sqrt_ratio.min() - 1 > 0.1
    assert 0.9 < ratio.mean() < 1.2  # measured 1.065
