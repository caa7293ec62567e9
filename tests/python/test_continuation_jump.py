"""A continuation never joins two different orbits (docs/orbits.md, "One orbit family per branch"),
on the tube of data/scenes/tube_loose_support.toml, against an independent computation written here.

The defect: continued from its four-impact attractor at omega = 0.4 (`0:impact*2 1:impact*2`), the
branch came down a fold to omega = 0.41289847, where the orbit is strongly unstable (|mu| ~ 1400)
and the corrector gives out; the step over that point converged on the same hyperplane onto the
symmetric two-impact orbit at omega = 0.42964 (153 steps from its predictor) and the branch went on
there, the point labelled "non-smooth". Branch 0 of the tube's diagram (docs/diagram.md) did the
same. Past 0.4129 the four-impact orbit and the two-impact one are different orbits (they meet only
at the grazing of both stops near 0.41277, which the branch had not reached).

The truth, without vibro's code: M q'' + C q' + K q = e_0 f sin(w t), M = diag(2, 1),
K = [[4, -1], [-1, 1]], f = 0.3, C the 2 % modal damping of the mass-normalised modes (docs/model.md
section 7), through the eigen-decomposition of the first-order form plus the closed-form harmonic
particular solution; impacts where q_1 = -0.1 (contact 0, gap speed q_1') or +0.1 (contact 1, gap
speed -q_1'), bracketed on a fine grid and bisected to the last bit, q_1' -> -0.7 q_1'. The period
map from the branch's own section time over one period 2 pi / w.

Checked:
- every point of the branch is a fixed point of that map (relative residual below 1e-9 times the
  largest |multiplier|, the conditioning of an orbit near a grazing) with the four impacts vibro
  lists (phases and speeds within 1e-7): one orbit family, up to its end;
- consecutive points are close: |d omega| < 1e-2 (the old jump was 0.0167), and the whole branch
  keeps the seed's contact sequence;
- the branch ends at the point where the corrector gives out, saying that the corrector converges
  only to another orbit there, and that other orbit (named at its omega) is, by the independent map,
  an orbit with two impacts per period: a different orbit, not the branch's.
- near the lower grazing (0.569366): the branch from omega = 0.52 keeps its four-impact orbit, with
  no `non-smooth` point and no jump, down to its grazing, where it turns back onto the two-impact
  orbit (test_double_grazing.py).
The old build fails all three (points 19 on are two-impact orbits, |d omega| = 0.0167; the branch
from 0.52 goes on along the two-impact orbit past a `non-smooth` point at 0.57040).
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
M = np.diag([2.0, 1.0])
K = np.array([[4.0, -1.0], [-1.0, 1.0]])
F, ZETA, R, GAP = 0.3, 0.02, 0.7, 0.1


def vibro(*args, timeout=600):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=timeout)
    assert p.returncode == 0, p.stderr
    return p


def bisect(g, a, b):
    """The root of g in [a, b] with g(a) > 0 >= g(b): bisection to the last bit."""
    while True:
        m = 0.5 * (a + b)
        if not a < m < b:
            return b
        if g(m) > 0:
            a = m
        else:
            b = m


class Tube:
    """The exact flow of the tube at forcing frequency om, and its period map with impacts."""

    def __init__(self, om):
        self.om = om
        h = np.diag(1 / np.sqrt(np.diag(M)))
        w2, u = np.linalg.eigh(h @ K @ h)
        phi = h @ u
        C = M @ phi @ np.diag(2 * ZETA * np.sqrt(w2)) @ phi.T @ M
        Mi = np.linalg.inv(M)
        A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ K, -Mi @ C]])
        b = np.concatenate([[0.0, 0.0], Mi @ np.array([F, 0.0])])
        self.Q = np.linalg.solve(A @ A + om**2 * np.eye(4), -om * b)  # z_p = P sin(om t) + Q cos(om t)
        self.P = A @ self.Q / om
        self.lam, self.V = np.linalg.eig(A)
        self.Vi = np.linalg.inv(self.V)

    def flow(self, z0, t0, s):
        s = np.atleast_1d(np.asarray(s, dtype=float))
        om, P, Q = self.om, self.P, self.Q
        c = self.Vi @ (z0 - P * np.sin(om * t0) - Q * np.cos(om * t0))
        hom = np.real((self.V[None, :, :] * np.exp(np.outer(s, self.lam))[:, None, :]) @ c)
        return hom + P[None] * np.sin(om * (t0 + s))[:, None] + Q[None] * np.cos(om * (t0 + s))[:, None]

    @staticmethod
    def gaps(z):
        return np.array([z[..., 1] + GAP, GAP - z[..., 1]])

    def period_map(self, z, t0, events=None, n=4000):
        """z at t0 -> z at t0 + T; events: (contact, phase mod 2 pi, speed before) of each impact."""
        T = 2 * np.pi / self.om
        t, end = t0, t0 + T
        z = np.array(z, dtype=float)
        while True:
            s = np.linspace(0, end - t, n + 1)[1:]
            g = self.gaps(self.flow(z, t, s))
            hit = None
            for j in (0, 1):
                k = np.nonzero(g[j] < 0)[0]
                if len(k) and (hit is None or k[0] < hit[1]):
                    hit = (j, k[0])
            # A flight that dips below a stop between two grid points and comes back (a slow impact
            # near a grazing): the grid's minimum of the gap, refined, decides.
            if hit is None:
                for j in (0, 1):
                    k = int(np.argmin(g[j]))
                    if 0 < k < n - 1 and g[j][k] < 1e-4:
                        lo_, hi_ = s[k - 1], s[k + 1]
                        for _ in range(200):
                            m1, m2 = lo_ + (hi_ - lo_) / 3, hi_ - (hi_ - lo_) / 3
                            if self.gaps(self.flow(z, t, [m1])[0])[j] < self.gaps(self.flow(z, t, [m2])[0])[j]:
                                hi_ = m2
                            else:
                                lo_ = m1
                        if self.gaps(self.flow(z, t, [0.5 * (lo_ + hi_)])[0])[j] < 0:
                            hit = (j, None, s[k - 1], 0.5 * (lo_ + hi_))
                            break
            if hit is None:
                return self.flow(z, t, [end - t])[0]
            if hit[1] is not None:
                j, k = hit
                lo, hi = (s[k - 1] if k > 0 else 0.0), s[k]
            else:
                j, _, lo, hi = hit
            u = bisect(lambda x: self.gaps(self.flow(z, t, [x])[0])[j], lo if lo > 0 else 1e-13, hi)
            z = self.flow(z, t, [u])[0].copy()
            t += u
            if events is not None:
                events.append((j, (self.om * t) % (2 * np.pi), z[3] if j == 0 else -z[3]))
            z[3] = -R * z[3]

    def newton(self, z, t0, iterations=8):
        for _ in range(iterations):
            J = np.zeros((4, 4))
            for i in range(4):
                dz = np.zeros(4)
                dz[i] = 1e-7
                J[:, i] = (self.period_map(z + dz, t0) - self.period_map(z - dz, t0)) / 2e-7
            step = np.linalg.solve(J - np.eye(4), self.period_map(z, t0) - z)
            z = z - step
            if np.abs(step).max() < 1e-13:
                break
        return z


@pytest.fixture(scope="module")
def branch(tmp_path_factory):
    out = tmp_path_factory.mktemp("jump") / "branch.h5"
    p = vibro("continue", TUBE, "--set", f"{KEY}=0.4", "--param", KEY, "--to", 1.6, "--out", out, "--json")
    d = json.loads(p.stdout)
    with h5py.File(out, "r") as f:
        g = f["branch"]
        b = {k: g[k][:] for k in ("value", "q", "q_dot", "section_time", "impact_offsets", "impact_phase",
                                  "impact_v_before", "impact_contact", "max_multiplier", "sequence")}
    return d, b


def test_one_family_up_to_the_grazing(branch):
    d, b = branch
    seqs = [s.decode() if isinstance(s, bytes) else s for s in b["sequence"]]
    # The four-impact orbit down to its grazing at 0.41277 (its two slow impacts dying out together,
    # located on the half map: test_double_grazing.py), where the branch turns back onto the
    # two-impact orbit: no jump, no end at 0.41289847 any more.
    k = seqs.index("0:impact 1:impact")
    assert set(seqs[:k]) == {"0:impact*2 1:impact*2"}, set(seqs[:k])
    assert np.abs(np.diff(b["value"][:k + 1])).max() < 1e-2, np.abs(np.diff(b["value"][:k + 1])).max()
    assert "another orbit" not in d["end"], d["end"]
    changes = [x for x in d["bifurcations"] if x.get("sequence_before")]
    g = changes[0]
    assert g["kind"] == "grazing" and abs(g["value"] - 0.41277) < 1e-4, g
    assert (g["sequence_before"], g["sequence_after"], g["through"]) == ("0:impact*2 1:impact*2", "0:impact 1:impact", "back")
    # The independent map: the first point, a few on the way down the unstable side, and the last
    # four at least 1.2e-4 above the grazing (|mu| up to 1.4e3; closer, the slow impacts' dips are
    # below its grid) are its fixed points with vibro's four impacts.
    late = [i for i in range(k) if b["value"][i] - g["value"] > 1.2e-4][-4:]
    for i in sorted({0, k // 3, 2 * k // 3, *late}):
        om, t0 = float(b["value"][i]), float(b["section_time"][i])
        tube = Tube(om)
        z = np.concatenate([b["q"][i], b["q_dot"][i]])
        events = []
        res = np.abs(tube.period_map(z, t0, events) - z).max() / (1 + np.abs(z).max())
        assert res < 1e-9 * max(1.0, b["max_multiplier"][i]), (i, om, res)
        o = b["impact_offsets"][i:i + 2]
        phase, speed, contact = (b["impact_phase"][o[0]:o[1]], b["impact_v_before"][o[0]:o[1]],
                                 b["impact_contact"][o[0]:o[1]])
        assert len(events) == len(phase) == 4, (i, events, phase)
        for j, ph, v in events:
            m = int(np.argmin([abs((p - ph + np.pi) % (2 * np.pi) - np.pi) + 10 * (c != j)
                               for p, c in zip(phase, contact)]))
            assert abs((phase[m] - ph + np.pi) % (2 * np.pi) - np.pi) < 1e-7, (i, j, phase[m], ph)
            assert abs(abs(speed[m]) - abs(v)) < 1e-7 * max(1.0, b["max_multiplier"][i]), (i, j, speed[m], v)


def test_past_the_grazing_the_two_impact_orbit(branch):
    # The orbit the branch turns back onto is, by the independent map, the symmetric two-impact
    # orbit: the attractor from rest at omega = 0.43 (where the old branch jumped to), followed down
    # by Newton in steps of 2.5e-3 (natural parameter), two impacts per period, one on each stop, all
    # the way, has at a two-impact point of the branch (1e-3 past the grazing) vibro's speeds there.
    d, b = branch
    seqs = [s.decode() if isinstance(s, bytes) else s for s in b["sequence"]]
    g = [x for x in d["bifurcations"] if x.get("sequence_before")][0]["value"]
    # 1e-3 past the grazing at least: closer, the flight's closest approach to the stop (1.6e-6 at
    # 1.2e-7) is below what the map's grid resolves.
    k = next(i for i, s in enumerate(seqs) if s == "0:impact 1:impact" and b["value"][i] - g > 1e-3)
    target = float(b["value"][k])
    tube = Tube(0.43)
    z = np.zeros(4)
    for _ in range(200):
        z = tube.period_map(z, 0.0, n=1500)
    for om in np.append(np.arange(0.43, target, -2.5e-3), target):
        tube = Tube(om)
        z = tube.newton(z, 0.0)
        events = []
        assert np.abs(tube.period_map(z, 0.0, events) - z).max() < 1e-11, om
        assert len(events) == 2 and {e[0] for e in events} == {0, 1}, (om, events)
    o = b["impact_offsets"][k:k + 2]
    assert o[1] - o[0] == 2
    mine = sorted(abs(e[2]) for e in events)
    theirs = sorted(abs(v) for v in b["impact_v_before"][o[0]:o[1]])
    assert np.allclose(mine, theirs, rtol=0, atol=1e-7), (mine, theirs)


def test_four_impact_branch_from_0_52_reaches_its_grazing_without_jumping(tmp_path):
    # The same near the lower grazing (omega_g = 0.569366, where the four-impact orbit's two slow
    # impacts die out together): continued from its attractor at omega = 0.52, up round its fold at
    # 0.6179 and back down, the branch keeps the four-impact orbit, with no `non-smooth` point and
    # no jump, down to the grazing, where it turns back onto the two-impact orbit (located on the
    # half map: tests/python/test_double_grazing.py). Before 582649f the step over omega = 0.5704
    # joined the two-impact orbit there (a `non-smooth` point I0I0I1I1 -> I0I1); at 582649f the
    # branch ended at 0.5704 ("another orbit"). Points of the branch before the grazing are fixed
    # points of the independent map with four impacts.
    out = tmp_path / "b.h5"
    p = vibro("continue", TUBE, "--set", f"{KEY}=0.52", "--param", KEY, "--to", 1.6, "--json", "--out", out)
    d = json.loads(p.stdout)
    assert "another orbit" not in d["end"], d["end"]
    assert not [b for b in d["bifurcations"] if b["kind"] == "non-smooth"], d["bifurcations"]
    changes = [b for b in d["bifurcations"] if b.get("sequence_before")]
    assert changes and changes[0]["kind"] == "grazing" and abs(changes[0]["value"] - 0.569366335) < 1e-8, changes
    assert (changes[0]["sequence_before"], changes[0]["sequence_after"]) == ("0:impact*2 1:impact*2", "0:impact 1:impact")
    seqs = [pt["sequence"] for pt in d["points"]]
    k = seqs.index("0:impact 1:impact")
    assert set(seqs[:k]) == {"0:impact*2 1:impact*2"}
    with h5py.File(out, "r") as f:
        g = f["branch"]
        value, q, qd, ts, mm = (g["value"][:], g["q"][:], g["q_dot"][:], g["section_time"][:],
                                g["max_multiplier"][:])
    for i in (k // 2, k - 7):  # k - 7: 1.3e-3 above the grazing (the numpy grid resolves its slow impacts)
        tube = Tube(float(value[i]))
        z = np.concatenate([q[i], qd[i]])
        events = []
        res = np.abs(tube.period_map(z, float(ts[i]), events) - z).max() / (1 + np.abs(z).max())
        assert res < 1e-9 * max(1.0, mm[i]), (value[i], res)
        assert len(events) == 4, (value[i], events)
