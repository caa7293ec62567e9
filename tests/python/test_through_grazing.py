"""Continuation through a grazing (docs/orbits.md, "Through a grazing"), on the tube scene of
data/scenes/tube_loose_support.toml, against an independent 30-digit computation.

The truth, written here without vibro's code: the tube is M q'' + C q' + K q = e_0 f sin(wt),
M = diag(2, 1), K = [[4, -1], [-1, 1]], f = 0.3, modal damping 0.02 in both modes (mass-normalised
modes: x_k'' + 2 z W_k x_k' + W_k^2 x_k = phi_k[0] f sin wt, solved in closed form), contacts on DOF 1
at q_1 = -0.1 (below, gap q_1 + 0.1) and q_1 = +0.1 (above, gap 0.1 - q_1), Newton's law with r = 0.7.
M is diagonal and the contacts act on DOF 1 alone, so an impact maps q_1' -> -r q_1' and leaves q_0'.

The four-impact orbit is symmetric (q(t + T/2) = -q(t)): from the state just before its fast impact
on the lower stop at t_a (q_0, q_0', q_1 = -0.1, q_1' = -v_a), the flow (impact, flight, the slow
impact on the same stop, flight) reaches the upper stop at t_c; the orbit is the root of
t_c - t_a - T/2 = 0, q(t_c) = -q(t_a), q'(t_c) = -q'(t_a) (mpmath findroot, 30 digits), events by
a dense float scan of the closed-form gap and a 30-digit bracketed root.

Checked:
- `vibro continue` from omega = 0.9 down meets the grazing near 0.569366 and TURNS BACK onto the
  four-impact orbit (a grazing fold), marked with both contact sequences in JSON and HDF5, with no
  hand-picked start, and goes on to the fold at 0.6179 and down the stable four-impact branch;
- every point of that branch within 2e-3 of the grazing has the independent orbit's four impacts
  (phases and speeds) within 1e-9;
- the new impact speed v of the independent orbits at distances 1e-4 .. 1.6e-3 from the grazing:
  the grazing value fitted from v (a cubic in omega) agrees with vibro's location within 1e-9, and
  the exponent of v ~ c d^p fitted over those distances is 1 (|p - 1| < 0.01), not 1/2.
"""
import json
import os
import subprocess

import h5py
import mpmath as mp
import numpy as np
import pytest

CLI = os.environ.get("VIBRO_CLI", "")
HERE = os.path.dirname(os.path.abspath(__file__))
TUBE = os.path.join(HERE, "..", "..", "data", "scenes", "tube_loose_support.toml")
KEY = "excitation.frequency"


@pytest.fixture(autouse=True, scope="module")
def _thirty_digits():
    """30 digits for this module's tests only (set at import, it would hold for every module
    collected with it: test_branch_switch's truths need their 40)."""
    dps = mp.mp.dps
    mp.mp.dps = 30
    yield
    mp.mp.dps = dps


with mp.workdps(30):  # the constants at 30 digits, whatever precision the import runs at
    R = mp.mpf("0.7")
    F = mp.mpf("0.3")
    ZETA = mp.mpf("0.02")
    GAP = mp.mpf("0.1")


def vibro(*args):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr
    return p.stdout


class Tube:
    """The closed-form flow of the damped tube at forcing frequency w (30 digits)."""

    def __init__(self, w):
        self.w = mp.mpf(w)
        M = mp.matrix([[2, 0], [0, 1]])
        K = mp.matrix([[4, -1], [-1, 1]])
        # M^{-1/2} K M^{-1/2} is symmetric: its eigenvectors give the mass-normalised modes.
        Mh = mp.matrix([[1 / mp.sqrt(2), 0], [0, 1]])
        E, Q = mp.eigsy(Mh * K * Mh)
        self.W = [mp.sqrt(E[k]) for k in range(2)]
        self.Phi = Mh * Q  # q = Phi x, Phi^T M Phi = I
        self.PhiT_M = self.Phi.T * M
        self.T = 2 * mp.pi / self.w
        self.modes = []
        for k in range(2):
            Wk, fk = self.W[k], self.Phi[0, k] * F
            a, b = Wk**2 - self.w**2, 2 * ZETA * Wk * self.w
            A = fk * a / (a * a + b * b)  # particular x_p = A sin wt + B cos wt
            B = -fk * b / (a * a + b * b)
            self.modes.append((Wk, Wk * mp.sqrt(1 - ZETA**2), A, B))

    def flow(self, t0, q, qd, t, floats=False):
        """q, q' at time t (scalar, or a numpy array with floats=True) from q, q' at t0 (free flight)."""
        x = self.PhiT_M * mp.matrix(q)
        xd = self.PhiT_M * mp.matrix(qd)
        out_q, out_qd = [], []
        for k, (Wk, Wd, A, B) in enumerate(self.modes):
            w = self.w
            C = x[k] - (A * mp.sin(w * t0) + B * mp.cos(w * t0))
            D = (xd[k] - (A * w * mp.cos(w * t0) - B * w * mp.sin(w * t0)) + ZETA * Wk * C) / Wd
            if floats:
                s = np.asarray(t, float) - float(t0)
                tt = np.asarray(t, float)
                e = np.exp(-float(ZETA * Wk) * s)
                c, sn = np.cos(float(Wd) * s), np.sin(float(Wd) * s)
                xk = e * (float(C) * c + float(D) * sn) + float(A) * np.sin(float(w) * tt) + float(B) * np.cos(float(w) * tt)
                out_q.append(xk)
                continue
            s = t - t0
            e = mp.exp(-ZETA * Wk * s)
            c, sn = mp.cos(Wd * s), mp.sin(Wd * s)
            xk = e * (C * c + D * sn) + A * mp.sin(w * t) + B * mp.cos(w * t)
            xdk = (e * (-ZETA * Wk * (C * c + D * sn) + Wd * (-C * sn + D * c)) + A * w * mp.cos(w * t)
                   - B * w * mp.sin(w * t))
            out_q.append(xk)
            out_qd.append(xdk)
        if floats:
            return [sum(float(self.Phi[i, k]) * out_q[k] for k in range(2)) for i in range(2)]
        qq = self.Phi * mp.matrix(out_q)
        qqd = self.Phi * mp.matrix(out_qd)
        return [qq[0], qq[1]], [qqd[0], qqd[1]]

    def next_impact(self, t0, q, qd):
        """The first time after t0 where q_1 reaches -0.1 or +0.1, and which (0 below, 1 above)."""
        h = float(self.T) / 20000
        t_grid = float(t0) + h * np.arange(1, 20001)
        q1 = self.flow(t0, q, qd, t_grid, floats=True)[1]
        below = np.nonzero(q1 + 0.1 < 0)[0]
        above = np.nonzero(0.1 - q1 < 0)[0]
        firsts = [(below[0], 0) if below.size else None, (above[0], 1) if above.size else None]
        i, c = min(x for x in firsts if x is not None)
        sign = 1 if c == 0 else -1
        gap = lambda t: sign * self.flow(t0, q, qd, t)[0][1] + GAP
        lo = mp.mpf(t_grid[i - 1]) if i > 0 else t0 + mp.mpf(h) / 1000
        hi = mp.mpf(t_grid[i])
        t = mp.findroot(gap, (lo, hi), solver="anderson")
        return t, c

    def half_period(self, u):
        """The residual of the symmetric four-impact orbit, and its impacts (time, contact, gap velocity before)."""
        t_a, q0, q0d, v_a = u
        q, qd = [q0, -GAP], [q0d, -v_a]
        impacts = [(t_a, 0, -v_a)]
        t = t_a
        qd = [qd[0], -R * qd[1]]
        for _ in range(2):
            t_n, c = self.next_impact(t, q, qd)
            q, qd = self.flow(t, q, qd, t_n)
            g_dot = qd[1] if c == 0 else -qd[1]
            impacts.append((t_n, c, g_dot))
            t = t_n
            qd = [qd[0], -R * qd[1]]
        t_c, c, _ = impacts[-1]
        qd_before = [qd[0], -qd[1] / R]
        res = [t_c - t_a - self.T / 2, q[0] + q0, qd_before[0] + q0d, qd_before[1] - v_a]
        return res, impacts, c

    def orbit(self, guess):
        u = mp.findroot(lambda *u: self.half_period(u)[0], [mp.mpf(g) for g in guess], tol=mp.mpf(10) ** -26)
        res, impacts, c = self.half_period(u)
        assert c == 1 and max(abs(r) for r in res) < mp.mpf(10) ** -20, (c, res)
        # The other half period is the mirror: the same speeds on the other stop, T/2 later.
        both = impacts[:2] + [(t + self.T / 2, 1 - c_, g) for (t, c_, g) in impacts[:2]]
        return u, both

    def phase(self, t):
        return mp.fmod(self.w * t, 2 * mp.pi)


def vibro_impacts(f, k):
    b = f["branch"]
    off = b["impact_offsets"][:]
    sl = slice(off[k], off[k + 1])
    return list(zip(b["impact_phase"][sl], b["impact_contact"][sl], b["impact_v_before"][sl]))


def guess_from_section(tube, t_s, q, qd):
    """A start for findroot: vibro's section state (a free state of its orbit) flowed by THIS
    module's closed form and impact law to the next fast impact on the lower stop. The root is the
    independent computation's own (its residual is checked at 1e-20)."""
    t, q, qd = mp.mpf(t_s), [mp.mpf(x) for x in q], [mp.mpf(x) for x in qd]
    for _ in range(8):
        t_n, c = tube.next_impact(t, q, qd)
        q, qd = tube.flow(t, q, qd, t_n)
        t = t_n
        if c == 0 and abs(qd[1]) > 0.05:
            return t, q[0], qd[0], -qd[1]
        qd = [qd[0], -R * qd[1]]
    raise AssertionError("no fast impact on the lower stop")


@pytest.fixture(scope="module")
def down(tmp_path_factory):
    out = tmp_path_factory.mktemp("grazing") / "down.h5"
    j = json.loads(vibro("continue", TUBE, "--param", KEY, "--to", 0.4, "--out", out, "--json", "--force"))
    return j, out


@pytest.fixture(scope="module")
def near_grazing(down):
    """vibro's four-impact points within 2e-3 of the grazing, each with the independent orbit there."""
    j, out = down
    w_g = [b for b in j["bifurcations"] if b["kind"] == "grazing"][0]["value"]
    rows = []
    with h5py.File(out) as f:
        b = f["branch"]
        value = b["value"][:]
        seqs = [s.decode() if isinstance(s, bytes) else s for s in b["sequence"][:]]
        for k in range(len(value)):
            if seqs[k] != "0:impact*2 1:impact*2" or not 0 < value[k] - w_g < 2e-3:
                continue
            tube = Tube(value[k])
            u, truth = tube.orbit(guess_from_section(tube, b["section_time"][k], b["q"][k], b["q_dot"][k]))
            rows.append((value[k], vibro_impacts(f, k), tube, truth))
    return w_g, rows


def test_the_branch_turns_back_at_the_grazing_onto_the_four_impact_orbit(down):
    j, out = down
    g = [b for b in j["bifurcations"] if b["kind"] == "grazing"][0]
    assert abs(g["value"] - 0.569366) < 1e-5
    assert g["through"] == "back"
    assert g["sequence_before"] == "0:impact 1:impact"
    assert g["sequence_after"] == "0:impact*2 1:impact*2"
    assert g["events_before"] == "I0I1" and g["events_after"] == "I0I0I1I1"
    assert 0.9 < g["new_impact_speed"] / g["new_impact_distance"] < 1.2  # linear: v/d = 1.065
    assert any(abs(b["value"] - 0.61791) < 1e-4 for b in j["bifurcations"] if b["kind"] == "fold")
    # On down the stable four-impact branch below the grazing (its attractor at 0.55, docs/orbits.md).
    after = [p for p in j["points"] if p["sequence"] == "0:impact*2 1:impact*2"]
    assert any(p["stable"] and p["value"] < 0.56 for p in after)
    with h5py.File(out) as f:
        bif = f["bifurcations"]
        k = [x.decode() if isinstance(x, bytes) else x for x in bif["through"][:]].index("back")
        seq = bif["sequence_after"][k]
        assert (seq.decode() if isinstance(seq, bytes) else seq) == "0:impact*2 1:impact*2"
        assert bif["value"][k] == g["value"]
        assert bif["new_impact_speed"][k] == g["new_impact_speed"]


def test_the_orbits_past_the_grazing_match_an_independent_computation(near_grazing):
    w_g, rows = near_grazing
    assert len(rows) >= 4, len(rows)
    worst = 0.0
    for value, imp, tube, truth in rows:
        assert len(imp) == 4
        for (t, c, gdot) in truth:
            ph = float(tube.phase(t))
            dist = lambda i: abs(np.remainder(i[0] - ph + np.pi, 2 * np.pi) - np.pi)
            match = min((i for i in imp if i[1] == c), key=dist)
            worst = max(worst, dist(match), abs(match[2] - float(gdot)))
    assert worst < 1e-9, worst


def test_the_new_impact_speed_is_linear_in_the_distance(near_grazing):
    w_g, rows = near_grazing
    lam = np.array([float(r[0]) for r in rows])
    v = np.array([float(min(abs(g) for (_, _, g) in r[3])) for r in rows])
    # The independent speeds vanish where a cubic through them vanishes: vibro's grazing.
    c = np.polynomial.polynomial.polyfit(lam - w_g, v, 3)
    roots = [x.real for x in np.polynomial.polynomial.polyroots(c) if abs(x.imag) < 1e-12 and abs(x.real) < 1e-4]
    assert roots and min(abs(x) for x in roots) < 1e-9, roots
    # v ~ k d^p over the distances: p = 1 (a square-root law would give 1/2).
    p = np.polyfit(np.log(lam - w_g), np.log(v), 1)[0]
    assert abs(p - 1) < 0.01, p


def period_map(tube, t_s, q, qd):
    """The 30-digit flow of one forcing period from the free state (q, q') at t_s, with the impacts."""
    t, q, qd = mp.mpf(t_s), [mp.mpf(x) for x in q], [mp.mpf(x) for x in qd]
    end = t + tube.T
    while True:
        t_n, c = tube.next_impact(t, q, qd)
        if t_n >= end:
            return tube.flow(t, q, qd, end)
        q, qd = tube.flow(t, q, qd, t_n)
        t = t_n
        qd = [qd[0], -R * qd[1]]


def test_a_closed_loop_stops_where_it_returns_to_its_first_point(down, tmp_path):
    """The asymmetric four-impact branch switched at the branch point near omega = 0.577019 goes
    round a closed loop (before: three times round, until --max-points). It now stops where it
    comes back: its last orbit is its first (a periodic orbit of the independent flow, 1e-9)."""
    j, out = down
    bp = [b["value"] for b in j["bifurcations"] if b["kind"] == "branch-point" and abs(b["value"] - 0.577019) < 1e-5]
    assert bp
    vals = [p["value"] for p in j["points"]]
    k = next(i for i in range(len(vals) - 1)
             if min(vals[i], vals[i + 1]) < bp[0] < max(vals[i], vals[i + 1])
             and j["points"][i]["sequence"] == "0:impact*2 1:impact*2")
    loop = tmp_path / "loop.h5"
    res = json.loads(vibro("continue", TUBE, "--param", KEY, "--to", 0.62, "--from", out, "--point", k, "--switch",
                           "--out", loop, "--json", "--force"))
    assert res["closed_loop"] is True and res["end"].startswith("closed loop"), res["end"]
    n = len(res["points"])
    assert 10 < n < 200, n  # once round
    with h5py.File(loop) as f:
        assert f["branch"].attrs["closed_loop"] == 1
        b = f["branch"]
        first, last = vibro_impacts(f, 0), vibro_impacts(f, n - 1)
        assert abs(b["value"][0] - b["value"][n - 1]) < 1e-9
        key = lambda i: (i[0] % (2 * np.pi))
        for x, y in zip(sorted(first, key=key), sorted(last, key=key)):
            assert x[1] == y[1]
            assert abs(np.remainder(x[0] - y[0] + np.pi, 2 * np.pi) - np.pi) < 1e-9
            assert abs(x[2] - y[2]) < 1e-9
        # Its orbits are asymmetric (the symmetric one it was born from is another branch), and its
        # first and last orbits are a periodic orbit of the independent flow.
        def asymmetry(i):
            imp = vibro_impacts(f, i)
            s0 = sorted(abs(x[2]) for x in imp if x[1] == 0)
            s1 = sorted(abs(x[2]) for x in imp if x[1] == 1)
            return max(abs(a - c) for a, c in zip(s0, s1)) if len(s0) == len(s1) else 1.0
        assert max(asymmetry(i) for i in range(n)) > 1e-3
        for i in (0, n - 1):
            tube = Tube(b["value"][i])
            q, qd = period_map(tube, b["section_time"][i], b["q"][i], b["q_dot"][i])
            err = max(abs(float(q[m]) - b["q"][i][m]) for m in range(2))
            err = max(err, max(abs(float(qd[m]) - b["q_dot"][i][m]) for m in range(2)))
            assert err < 1e-9, (i, err)


def flow_with_impacts(tube, t_s, q, qd, duration):
    """The 30-digit flow from the free state (q, q') at t_s over `duration`, with the impacts."""
    t, q, qd = mp.mpf(t_s), [mp.mpf(x) for x in q], [mp.mpf(x) for x in qd]
    end = t + duration
    while True:
        t_n, c = tube.next_impact(t, q, qd)
        if t_n >= end:
            return tube.flow(t, q, qd, end)
        q, qd = tube.flow(t, q, qd, t_n)
        t = t_n
        qd = [qd[0], -R * qd[1]]


def cyclic_words_equal(a, b):
    """Two contact sequences ("0:impact*2 1:impact") as cyclic words: one a rotation of the other."""
    def expand(text):
        out = []
        for e in text.split():
            name, _, n = e.partition("*")
            out += [name] * int(n or 1)
        return out
    x, y = expand(a), expand(b)
    return len(x) == len(y) and any(x == y[k:] + y[:k] for k in range(max(len(y), 1)))


def swapped(text):
    """The sequence with contacts 0 and 1 swapped: the tube's mirror image (q -> -q, t -> t + T/2)."""
    return " ".join(("1" if e[0] == "0" else "0") + e[1:] for e in text.split())


def grazing_quantity(detail):
    """The grazing quantity a grazing's detail states at its located point: the N-side's "test
    quantity", or the slow impact's speed over its contact's largest where it died out."""
    import re
    m = re.search(r"falls to [0-9.e+-]+ \(([0-9.e+-]+) of the contact's largest speed", detail)
    if m:
        return float(m.group(1))
    m = re.search(r"test quantity ([0-9.e+-]+)\)", detail)
    return float(m.group(1)) if m else None


def test_a_branch_stops_where_it_meets_the_mirror_image_of_a_transition(tmp_path):
    """From omega = 0.9 up, the symmetric orbit passes its pitchfork at 0.9554, goes through its
    grazing at 1.3646 onto a three-impact orbit (turning back) and down to where that orbit's slow
    impact dies out near 0.95588: located there from the slow impact's side (its speed followed to
    below 1e-5 of its scale), it goes on past it along the asymmetric two-impact orbit, round the
    pitchfork (a fold of the asymmetric branch) onto the mirror asymmetric orbit and up to its
    grazing near 0.95588: the mirror image (contacts swapped) of the transition it went through,
    crossed the other way. It stops there, a closed loop, after about a hundred points (before:
    creeping near 1.36463 with |mu| up to 2.5e5, 714 points, or --max-points).
    Independent: the orbits next to both transitions are periodic orbits of the 30-digit flow
    (1e-9) and asymmetric (q(t + T/2) != -q(t)); the two are mirror images of each other's
    sequences as cyclic words; no transition is called a grazing whose grazing quantity is above
    the tolerance 1e-5."""
    out = tmp_path / "up.h5"
    j = json.loads(vibro("continue", TUBE, "--param", KEY, "--to", 1.5, "--out", out, "--json", "--force"))
    assert j["closed_loop"] is True and j["end"].startswith("closed loop: through the mirror image"), j["end"]
    assert len(j["points"]) < 300, len(j["points"])
    for b in j["bifurcations"]:
        if b["kind"] == "grazing":
            q = grazing_quantity(b["detail"])
            assert q is not None and q < 1e-5, b["detail"]
    assert not [b for b in j["bifurcations"] if b["kind"] == "non-smooth"]
    kinds = [(b["kind"], round(b["value"], 6)) for b in j["bifurcations"]]
    assert ("grazing", 1.364647) in kinds, kinds
    last = j["bifurcations"][-1]
    assert last["kind"] == "grazing" and last["through"] in ("past", "back")
    # The earlier transition it mirrors: the same kind at the same omega (within their brackets).
    earlier = [b for b in j["bifurcations"][:-1]
               if b["kind"] == last["kind"] and b.get("through")
               and abs(b["value"] - last["value"]) < 1e-9 + b["bracket"] + last["bracket"]]
    assert earlier, [(b["kind"], b["value"]) for b in j["bifurcations"]]
    e = earlier[0]
    assert abs(e["value"] - 0.955877) < 1e-6 and abs(e["value"] - last["value"]) < 2e-9
    assert "dies out" in e["detail"] and e["through"] == "past"  # located from the slow impact's side
    fwd = cyclic_words_equal(swapped(e["sequence_before"]), last["sequence_before"]) and \
        cyclic_words_equal(swapped(e["sequence_after"]), last["sequence_after"])
    rev = cyclic_words_equal(swapped(e["sequence_before"]), last["sequence_after"]) and \
        cyclic_words_equal(swapped(e["sequence_after"]), last["sequence_before"])
    assert fwd or rev, (e, last)
    assert not cyclic_words_equal(e["sequence_after"], last["sequence_after"])  # a mirror image, not the same
    with h5py.File(out) as f:
        b = f["branch"]
        # The two-impact orbits next to the transitions: after e (the branch went on past it), and
        # before last (from where it would have crossed it).
        # At least 1e-6 from the grazing (where the flight clears the stop plainly): walk away.
        for k, step in ((e["point"] + 1, 1), (last["point"], -1)):
            while abs(b["value"][k] - last["value"]) < 1e-6:
                k += step
            assert abs(b["value"][k] - last["value"]) < 1e-4
            tube = Tube(b["value"][k])
            q0, qd0 = b["q"][k], b["q_dot"][k]
            q, qd = flow_with_impacts(tube, b["section_time"][k], q0, qd0, tube.T)
            err = max(max(abs(float(q[m]) - q0[m]), abs(float(qd[m]) - qd0[m])) for m in range(2))
            assert err < 1e-9, ("periodic", k, err)
            q, qd = flow_with_impacts(tube, b["section_time"][k], q0, qd0, tube.T / 2)
            err = max(max(abs(float(q[m]) + q0[m]), abs(float(qd[m]) + qd0[m])) for m in range(2))
            assert err > 1e-3, ("asymmetric", k, err)
