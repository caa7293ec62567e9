"""`vibro diagram` (docs/diagram.md) against independent truths written here, from the closed-form
free flight of one DOF in mpmath (40 digits) and nothing of vibro:

(a) the symmetric two-sided oscillator x'' + x = a sin(2 t), stops at -1 and +1, r = 0.6, over
    a in [1, 8]: the diagram holds
    - the symmetric period-1 branch: each of its points below the pitchfork is an orbit whose
      state half a period later is minus its state (q -> -q at T/2), to 1e-9, simulated here;
    - the pitchfork where it loses its symmetry, at the a where the half-period map H (impact on +1
      -> impact on -1, mirrored) has the multiplier -1, solved here at 40 digits (3.28605035735799...),
      to 1e-12;
    - both asymmetric branches born there, mirror images of each other: the state of a point of one
      half a period later, mirrored, is a periodic orbit (one period simulated here returns to it,
      1e-9) that is not the point's own orbit, and its impacts are those of the other branch;
    - no branch twice (two stored branches never hold the same orbit at the same a), whatever their
      periods: no branch of period q holds an orbit whose impacts repeat after fewer periods (the
      period-1 orbit continued as a period-3 one), and no orbit, compared over its least period,
      lies on two branches.
(b) the tube scene over omega in [0.4, 1.6], with the default options (a sweep of 30 steps, as
    docs/diagram.md runs it): every attractor of the sweep and of the searches is on a stable
    branch or reported uncovered with a reason; a covered period-1 attractor's section points lie
    on the branch's strobe; only not-periodic attractors are uncovered (grouped into windows, the
    same in the JSON and the HDF5 file): the period-7 and period-9 attractors at 1.04 and 1.56
    too, which the former default cap of 24 branches, spent in the order branches were found, left
    out; the period-1 orbit of the branch covering omega = 0.44, at its point nearest 0.44 and
    continued from there to 0.44 itself (`vibro orbit`), is the one of the exact flow written here at
    the same omega (numpy, closed form between impacts, Newton on the period map), to 1e-9.
(c) bad input: exit 2 with a located message and nothing written; a cap too small: what it left out
    is named (the seeds and switches not followed, the attractors uncovered because of it); the
    defaults of `vibro diagram` (its --help) and of Python's vibro.diagram are the same;
(d) Python: vibro.diagram returns numpy arrays per branch, the pitchfork and its two halves;
(e) Ctrl-C once the progress report shows a stored branch: exit 130, the file says interrupted and keeps them.
"""
import json
import math
import os
import subprocess

import h5py
import mpmath as mp
import numpy as np
import pytest

mp.mp.dps = 40
CLI = os.environ.get("VIBRO_CLI", "")
HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.join(HERE, "..", "..", "data", "scenes")
W, R = mp.mpf(2), mp.mpf("0.6")
T = 2 * mp.pi / W


def vibro(*args, check=True):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=1800)
    if check:
        assert p.returncode == 0, p.stderr
    return p


def flight(a, x0, v0, t0, s):
    """x'' + x = a sin(W t) from (x0, v0) at t0, after time s (closed form)."""
    U = a / (1 - W**2)
    A = x0 - U * mp.sin(W * t0)
    B = v0 - U * W * mp.cos(W * t0)
    return (A * mp.cos(s) + B * mp.sin(s) + U * mp.sin(W * (t0 + s)),
            -A * mp.sin(s) + B * mp.cos(s) + U * W * mp.cos(W * (t0 + s)))


def advance(a, x, v, t, duration):
    """The impact oscillator between the stops at -1 and +1 (restitution R) from (x, v) at t for
    `duration`: impacts found by scanning and bisection of the closed-form flight, at 40 digits."""
    a, x, v, t = mp.mpf(a), mp.mpf(x), mp.mpf(v), mp.mpf(t)
    end = t + duration
    impacts = []
    while True:
        h, s, hit = mp.mpf("2e-3"), mp.mpf(0), None
        while t + s < end:
            s2 = min(s + h, end - t)
            xs = flight(a, x, v, t, s2)[0]
            if abs(xs) > 1:
                hit = (s, s2)
                break
            s = s2
        if hit is None:
            x, v = flight(a, x, v, t, end - t)
            return x, v, impacts
        lo, hi = hit
        side = 1 if flight(a, x, v, t, hi)[0] > 1 else -1
        # Bisection (a root finder may return the start itself after an impact on this stop).
        for _ in range(130):
            mid = (lo + hi) / 2
            if abs(flight(a, x, v, t, mid)[0]) > 1:
                hi = mid
            else:
                lo = mid
        sol = hi
        xs, vs = flight(a, x, v, t, sol)
        t = t + sol
        impacts.append((t, side, vs))
        x, v = mp.mpf(side), -R * vs


# --- (a) the truth: the pitchfork of the symmetric orbit ------------------------------------------


def symmetric_orbit(a):
    """Impact on +1 at tau with arrival speed V, free flight of T/2 to -1 arriving with -V. With
    U = a/(1 - W^2) and theta = W tau: U((1 - r) sin theta + (1 + r) W cos theta) = 1 - r and
    V = 1 - U sin theta + U W cos theta (closed form, W = 2: the flight of T/2 = pi/2 has cos = 0)."""
    U = a / (1 - W**2)
    rho = mp.sqrt((1 - R)**2 + ((1 + R) * W)**2)
    phi = mp.atan2((1 + R) * W, 1 - R)
    base = mp.asin((1 - R) / (U * rho))
    for theta in (base - phi, mp.pi - base - phi):
        V = 1 - U * mp.sin(theta) + U * W * mp.cos(theta)
        tau = theta / W
        if V <= 0:
            continue
        # Admissible: the flight stays strictly between the stops.
        if all(abs(flight(a, 1, -R * V, tau, T / 2 * k / 400)[0]) < 1 for k in range(1, 400)):
            return tau, V
    raise AssertionError("no symmetric orbit")


def half_map(a, tau, V):
    """H: impact on +1 at tau with speed V -> the next impact on -1 at t' with speed V', mirrored
    to an impact on +1 at t' - T/2 with speed V'."""
    guess = tau + T / 2
    t = mp.findroot(lambda u: flight(a, 1, -R * V, tau, u - tau)[0] + 1, guess, tol=mp.mpf(10) ** -35)
    _, v = flight(a, 1, -R * V, tau, t - tau)
    return t - T / 2, -v


def pitchfork():
    """The a where DH has the multiplier -1: det(DH + I) = 0 (DH by central differences)."""
    def g(a):
        tau, V = symmetric_orbit(a)
        e = mp.mpf(10) ** -15
        J = mp.matrix(2, 2)
        for j, (dt, dv) in enumerate(((e, 0), (0, e))):
            p = half_map(a, tau + dt, V + dv)
            m = half_map(a, tau - dt, V - dv)
            J[0, j] = (p[0] - m[0]) / (2 * e)
            J[1, j] = (p[1] - m[1]) / (2 * e)
        return (J[0, 0] + 1) * (J[1, 1] + 1) - J[0, 1] * J[1, 0]
    return mp.findroot(g, mp.mpf("3.286"), tol=mp.mpf(10) ** -30)


@pytest.fixture(scope="module")
def two_sided(tmp_path_factory):
    out = tmp_path_factory.mktemp("diagram") / "two.h5"
    p = vibro("diagram", os.path.join(SCENES, "contacts_two_sided_1dof.toml"), "--set", "contact[0].restitution=0.6",
              "--set", "contact[1].restitution=0.6", "--set", "excitation.frequency=2.0", "--set", "run.periods=200",
              "--param", "excitation.amplitude", "--from", 1, "--to", 8, "--steps", 28, "--json", "--out", out)
    return json.loads(p.stdout), out


def states(h5, name):
    b = h5["diagram/branches"][name]["branch"]
    return b["value"][()], b["section_time"][()], b["q"][()][:, 0], b["q_dot"][()][:, 0]


def test_pitchfork_closed_form():
    a = pitchfork()
    assert abs(a - mp.mpf("3.2860503573579958")) < mp.mpf("1e-12")


def test_symmetric_branch_and_pitchfork(two_sided):
    d, out = two_sided
    truth = float(pitchfork())
    sym = [b for b in d["branches"] if b["origin"] == "seed" and b["period"] == 1 and
           any(x["kind"] == "branch-point" and abs(x["value"] - truth) < 1e-12 for x in b["bifurcations"])]
    assert len(sym) == 1, [(b["index"], b["bifurcations"]) for b in d["branches"]]
    with h5py.File(out, "r") as f:
        value, t0, q, qd = states(f, f"{sym[0]['index']:03d}")
    checked = 0
    below = [i for i, a in enumerate(value) if a < truth - 0.05]
    for i in below[:: max(1, len(below) // 8)]:
        a, t, x, v = value[i], t0[i], q[i], qd[i]
        xh, vh, impacts = advance(a, x, v, t, T / 2)
        assert impacts, "the symmetric orbit hits a stop every half period"
        assert abs(xh + x) < 1e-9 and abs(vh + v) < 1e-9, (a, x, v, xh, vh)
        checked += 1
    assert checked >= 5


def test_asymmetric_branches_are_mirror_images(two_sided):
    d, out = two_sided
    truth = float(pitchfork())
    born = [b for b in d["branches"] if b["origin"] == "branch-point" and abs(b["born_at"] - truth) < 1e-9]
    assert len(born) == 2, [(b["index"], b["origin"], b["born_at"]) for b in d["branches"]]
    with h5py.File(out, "r") as f:
        one, two = (states(f, f"{b['index']:03d}") for b in born)
        imp = {}
        for b in born:
            g = f["diagram/branches"][f"{b['index']:03d}"]["branch"]
            imp[b["index"]] = (g["impact_offsets"][()], g["impact_phase"][()], g["impact_v_before"][()],
                               g["impact_contact"][()])
    checked = periodic = 0
    # Six points spread over the branch, past its birth and before the grazing (past it the branch
    # goes on along the orbit with the new impact: docs/orbits.md, "Through a grazing").
    graze = min([x["value"] for x in born[0]["bifurcations"] if x["kind"] == "grazing"] or [math.inf])
    inner = [i for i, a in enumerate(one[0]) if truth + 0.05 < a < graze][:-2]
    for i in inner[:: max(1, len(inner) // 6)]:
        a, t, x, v = one[0][i], one[1][i], one[2][i], one[3][i]
        # y(t) = -x(t + T/2) solves the equation too (the forcing changes sign in half a period):
        # its state at t0 is minus the point's state half a period later. A periodic orbit, not
        # the point's own.
        xh, vh, _ = advance(a, x, v, t, T / 2)
        xm, vm = -xh, -vh
        xp, vp, impacts = advance(a, xm, vm, t, T)
        assert abs(xp - xm) < 1e-9 and abs(vp - vm) < 1e-9, (a, xm, vm, xp, vp)
        assert abs(xm - x) + abs(vm - v) > 1e-3  # asymmetric: not its own orbit shifted by T/2
        periodic += 1
        # The other branch has these impacts at a: between its two points around a, linearly
        # interpolated (its points are not at the same a: a loose 2e-2, which tells the mirror
        # image, contacts swapped, from the branch itself).
        off, ph, vb, ct = imp[born[1]["index"]]

        def listed(j):
            return sorted((int(c), float(p) % (2 * math.pi), float(s_))
                          for p, s_, c in zip(ph[off[j]:off[j + 1]], vb[off[j]:off[j + 1]], ct[off[j]:off[j + 1]]))
        vals = two[0]
        around = [j for j in range(len(vals) - 1) if min(vals[j], vals[j + 1]) <= a <= max(vals[j], vals[j + 1])]
        if not around:
            continue
        j = around[0]
        lo_, hi_ = listed(j), listed(j + 1)
        if not (len(lo_) == len(hi_) == len(impacts)):  # the other branch's grazing lies between them
            continue
        w = (a - vals[j]) / (vals[j + 1] - vals[j]) if vals[j + 1] != vals[j] else 0.0
        # Ours, from the mirrored orbit simulated here: contact 0 is the stop at -1 (side -1); the
        # gap velocity just before an impact is -|x'|.
        ours = sorted((0 if side == -1 else 1, float(W * tt) % (2 * math.pi), -abs(float(vs)))
                      for tt, side, vs in impacts)
        assert len(ours) == len(lo_) == len(hi_)
        for o, l, h in zip(ours, lo_, hi_):
            assert o[0] == l[0] == h[0], (a, ours, lo_)
            dl = (h[1] - l[1] + math.pi) % (2 * math.pi) - math.pi
            phase = l[1] + w * dl
            speed = l[2] + w * (h[2] - l[2])
            dphi = abs((o[1] - phase + math.pi) % (2 * math.pi) - math.pi)
            assert dphi < 2e-2 and abs(o[2] - speed) < 2e-2 * (1 + abs(speed)), (a, o, phase, speed)
        checked += 1
    assert periodic >= 4 and checked >= 2, (periodic, checked)


def test_no_branch_twice(two_sided):
    d, out = two_sided
    assert d["duplicates"] >= 0
    bs = d["branches"]
    for i in range(len(bs)):
        for j in range(i + 1, len(bs)):
            a, b = bs[i], bs[j]
            if a["period"] != b["period"] or not a["points"] or not b["points"]:
                continue
            # Same orbit at the same a: the same values, sequences and stroboscopic states.
            same = 0
            for p in a["points"]:
                for r in b["points"]:
                    if abs(p["value"] - r["value"]) < 1e-12 and p["sequence"] == r["sequence"] and \
                            abs((p["strobe"][0] or 0) - (r["strobe"][0] or 0)) < 1e-9:
                        same += 1
            assert same < max(3, len(a["points"]) // 2), (i, j, same)


def impacts_of(h5, name):
    """Per point of a stored branch: its impacts over the branch's period as (contact, phase, speed)."""
    b = h5["diagram/branches"][name]["branch"]
    off = b["impact_offsets"][()]
    ph, vb, c = b["impact_phase"][()], b["impact_v_before"][()], b["impact_contact"][()]
    return b["value"][()], [list(zip(c[off[i]:off[i + 1]], ph[off[i]:off[i + 1]], vb[off[i]:off[i + 1]]))
                            for i in range(len(off) - 1)]


def least_period(imp, q, tol=1e-6):
    """The least p dividing q such that shifting time by p periods (phase by 2 pi p, mod 2 pi q)
    maps the impacts onto themselves."""
    span = 2 * math.pi * q
    for p in range(1, q):
        if q % p or len(imp) % (q // p) or not imp:
            continue
        if all(any(c2 == c1 and abs((ph2 - ph1 - 2 * math.pi * p + span / 2) % span - span / 2) < tol and
                   abs(v2 - v1) < tol * (1 + abs(v1)) for c2, ph2, v2 in imp) for c1, ph1, v1 in imp):
            return p
    return q


def reduced(imp, q):
    """The impacts of one least period, as sorted (contact, phase mod 2 pi, speed)."""
    p = least_period(imp, q)
    keep = [(int(c), ph % (2 * math.pi), v) for c, ph, v in imp if ph % (2 * math.pi * q) < 2 * math.pi * p - 1e-9]
    return sorted(keep)


def test_branches_hold_orbits_of_their_least_period(two_sided):
    """A period-1 orbit continued with period 3 is still the period-1 orbit: no stored branch of
    period q holds an orbit whose impacts repeat after fewer periods."""
    d, out = two_sided
    with h5py.File(out, "r") as f:
        for i, b in enumerate(d["branches"]):
            _, imps = impacts_of(f, f"{i:03d}")
            short = [k for k, imp in enumerate(imps) if least_period(imp, b["period"]) < b["period"]]
            assert not short, (i, b["period"], len(short), len(imps))


def test_no_orbit_on_two_branches_of_any_periods(two_sided):
    """Two stored branches, of the same period or not, never hold the same orbit (compared over its
    least period: impact phases mod 2 pi and speeds) at the same a (the other branch's orbit there
    interpolated between its two points around a)."""
    d, out = two_sided
    with h5py.File(out, "r") as f:
        data = [(b["period"],) + impacts_of(f, f"{i:03d}") for i, b in enumerate(d["branches"])]
    for i, (qi, vi, ii) in enumerate(data):
        for j, (qj, vj, ij) in enumerate(data):
            if j == i:
                continue
            same = checked = 0
            for k in range(0, len(vi), max(1, len(vi) // 12)):
                a, mine = vi[k], reduced(ii[k], qi)
                for m in range(len(vj) - 1):
                    lo, hi = sorted((vj[m], vj[m + 1]))
                    if not lo <= a <= hi or hi - lo > 0.2:
                        continue
                    x, y = reduced(ij[m], qj), reduced(ij[m + 1], qj)
                    if len(x) != len(mine) or len(y) != len(mine):
                        continue
                    w = 0.0 if hi == lo else (a - vj[m]) / (vj[m + 1] - vj[m])
                    checked += 1
                    if all(c1 == c2 == c3 and abs(p1 - (p2 + w * (p3 - p2))) < 1e-2 and
                           abs(s1 - (s2 + w * (s3 - s2))) < 1e-2 * (1 + abs(s1))
                           for (c1, p1, s1), (c2, p2, s2), (c3, p3, s3) in zip(mine, x, y)):
                        same += 1
                        break
            assert same < 3, (i, j, same, checked)


def test_ends_are_reported(two_sided):
    d, _ = two_sided
    for b in d["branches"]:
        assert b["end_first"] and b["end_last"]
    # The asymmetric branches meet a grazing: they stop there and say so, or go on through it with
    # the grazing marked with both sequences.
    truth = float(pitchfork())
    born = [b for b in d["branches"] if b["origin"] == "branch-point" and abs(b["born_at"] - truth) < 1e-9]
    assert born and all("grazing" in b["end_last"] or any(
        x["kind"] == "grazing" and x.get("through") and x.get("sequence_after") for x in b["bifurcations"])
        for b in born), [b["end_last"] for b in born]


# --- (b) the tube: coverage ---------------------------------------------------------------------


@pytest.fixture(scope="module")
def tube(tmp_path_factory):
    out = tmp_path_factory.mktemp("tube") / "tube.h5"
    p = vibro("diagram", os.path.join(SCENES, "tube_loose_support.toml"), "--param", "excitation.frequency",
              "--from", 0.4, "--to", 1.6, "--steps", 30, "--json", "--out", out)
    return json.loads(p.stdout), out


def test_tube_coverage(tube):
    d, out = tube
    sweep = d["sweep"]
    entries = [c for c in d["coverage"] if c["source"] != "search"]
    assert len(entries) == len(sweep)
    covered = 0
    for c, s in zip(entries, sweep):
        assert c["value"] == s["value"]
        if c["branch"] is None:
            assert c["reason"], c
            if s["kind"] == "not-periodic":
                assert c["reason"].startswith("not periodic"), c
            continue
        covered += 1
        b = d["branches"][c["branch"]]
        assert b["period"] % (c["period"] or 1) == 0
        assert c["distance"] <= 1e-3
        if c["period"] == 1:
            # The sweep's section points (one value once settled) lie on the branch's strobe,
            # between its two points around the value (linear interpolation).
            v = np.array([p["value"] for p in b["points"]])
            y = np.array([p["strobe"][0] for p in b["points"]], dtype=float)
            ok = False
            for k in range(len(v) - 1):
                lo, hi = sorted((v[k], v[k + 1]))
                if lo - 1e-12 <= s["value"] <= hi + 1e-12 and hi > lo:
                    w = (s["value"] - v[k]) / (v[k + 1] - v[k])
                    yi = y[k] + w * (y[k + 1] - y[k])
                    ok = ok or abs(yi - s["x_B"][-1]) < 2e-2 * (1 + abs(yi))
                elif abs(v[k] - s["value"]) < 1e-12:
                    ok = ok or abs(y[k] - s["x_B"][-1]) < 1e-6
            assert ok, (s["value"], s["x_B"][-1])
    # Outside the chaotic windows (0.96 to 1.52, and 0.48) the sweep's attractors are periodic, and
    # nearly all of them lie on a branch.
    assert covered >= 20, covered


def test_tube_uncovered_only_not_periodic(tube):
    # Every periodic attractor found (period 1 at 0.44, period 7 at 1.04, period 9 at 1.56 down:
    # above --max-period 4, which bounds only the switching) is seeded and lies on a stable branch;
    # what is left uncovered is the not-periodic attractors, grouped into windows. With the default
    # options: the former default cap (24 branches, spent in the order branches were found) ran out
    # before the period-9 seed at 1.56.
    d, _ = tube
    assert not d["cap_reached"] and d["seeds_left_out"] == 0 and d["switches_left_out"] == 0
    unc = [c for c in d["coverage"] if c["branch"] is None]
    assert unc and all(c["kind"] == "not-periodic" and c["period"] is None for c in unc), \
        [(c["value"], c["source"], c["kind"], c["reason"]) for c in unc if c["kind"] != "not-periodic"]
    assert sum(w["count"] for w in d["uncovered_windows"]) == len(unc)
    for w in d["uncovered_windows"]:
        inside = [c for c in unc if c["source"] == w["source"] and min(w["from"], w["to"]) - 1e-12 <= c["value"]
                  <= max(w["from"], w["to"]) + 1e-12]
        assert len(inside) == w["count"], w
    for value, period in ((0.44, 1), (1.04, 7), (1.56, 9)):
        hit = [c for c in d["coverage"] if abs(c["value"] - value) < 1e-9 and c["period"] == period]
        assert hit and all(c["branch"] is not None for c in hit), (value, period, hit)
        assert all(d["branches"][c["branch"]]["period"] == period for c in hit)


def test_tube_period_nine_at_1_56(tube):
    # The period-9 window near omega = 1.56 (the sweep down's attractor there): held by a stable
    # seeded branch of period 9 whose orbit at 1.56 has the attractor's impacts (within the coverage
    # tolerance), and which the HDF5 file stores with the same period and range.
    d, out = tube
    hit = [c for c in d["coverage"] if abs(c["value"] - 1.56) < 1e-9 and c["period"] == 9]
    assert hit, [(c["value"], c["source"], c["period"]) for c in d["coverage"] if abs(c["value"] - 1.56) < 1e-9]
    for c in hit:
        assert c["branch"] is not None and c["distance"] <= 1e-3, c
        b = d["branches"][c["branch"]]
        assert b["period"] == 9 and b["origin"] == "seed"
        v = b["value"] if "value" in b else np.array([p["value"] for p in b["points"]])
        assert min(v) <= 1.56 <= max(v)
        with h5py.File(out, "r") as f:
            g = f["diagram/branches/%03d/branch" % c["branch"]]
            assert g.attrs["period"] == 9
            assert np.array_equal(g["value"][:], np.array([p["value"] for p in b["points"]]))


def test_tube_uncovered_windows_in_hdf5(tube):
    # /diagram/uncovered_windows holds the JSON's uncovered_windows, row by row; vibro.read gives it.
    d, out = tube
    with h5py.File(out, "r") as f:
        w = f["diagram/uncovered_windows"]
        rows = list(zip(w["from"][:], w["to"][:], w["count"][:], w["source"].asstr()[:], w["reason"].asstr()[:]))
        assert f["diagram"].attrs["cap_reached"] == 0
        assert f["diagram"].attrs["seeds_left_out"] == 0 and f["diagram"].attrs["switches_left_out"] == 0
    assert len(rows) == len(d["uncovered_windows"]) > 0
    for (a, b, n, src, why), j in zip(rows, d["uncovered_windows"]):
        assert (a, b, int(n), src, why) == (j["from"], j["to"], j["count"], j["source"], j["reason"])
    vibro_py = pytest.importorskip("vibro")
    g = vibro_py.read(str(out))["diagram"]["uncovered_windows"]
    assert list(g["source"]) == [j["source"] for j in d["uncovered_windows"]]
    assert np.array_equal(g["from"], [j["from"] for j in d["uncovered_windows"]])
    assert np.array_equal(g["count"], [j["count"] for j in d["uncovered_windows"]])


# The tube's period-1 orbit at omega = 0.44, computed here without vibro: the exact flow of
# M q'' + C q' + K q = e_0 f sin(omega t) (C the 2 % modal damping of the mass-normalised modes,
# docs/model.md section 7) through the eigen-decomposition of its first-order form plus the
# closed-form harmonic particular solution; impacts where q_1 = -0.1 (contact 0, gap speed q1') or
# +0.1 (contact 1, gap speed -q1'), located by bracketing on a 2000-step grid and bisection to the last bit,
# q1' -> -0.7 q1'; the stroboscopic map over one period from t = 0, iterated 200 periods from rest
# and solved by Newton (central differences).
TUBE_M = np.diag([2.0, 1.0])
TUBE_K = np.array([[4.0, -1.0], [-1.0, 1.0]])


def root(g, a, b):
    """The root of g in [a, b] (g(a) > 0 > g(b)): bisection to the last bit."""
    ga = g(a)
    assert ga > 0 > g(b)
    while True:
        m = 0.5 * (a + b)
        if not a < m < b:
            return m
        if g(m) > 0:
            a = m
        else:
            b = m


def tube_orbit(om, f=0.3, zeta=0.02, r=0.7, gap=0.1):
    # Mass-normalised modes (K phi = w^2 M phi, phi^T M phi = 1) through the symmetric
    # M^(-1/2) K M^(-1/2), M being diagonal.
    h = np.diag(1 / np.sqrt(np.diag(TUBE_M)))
    w2, u = np.linalg.eigh(h @ TUBE_K @ h)
    phi = h @ u
    C = TUBE_M @ phi @ np.diag(2 * zeta * np.sqrt(w2)) @ phi.T @ TUBE_M
    Mi = np.linalg.inv(TUBE_M)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ TUBE_K, -Mi @ C]])
    b = np.concatenate([[0.0, 0.0], Mi @ np.array([f, 0.0])])
    Q = np.linalg.solve(A @ A + om**2 * np.eye(4), -om * b)  # z_p = P sin(om t) + Q cos(om t)
    P = A @ Q / om
    lam, V = np.linalg.eig(A)
    Vi = np.linalg.inv(V)

    def flow(z0, t0, s):
        s = np.atleast_1d(s)
        c = Vi @ (z0 - P * np.sin(om * t0) - Q * np.cos(om * t0))
        hom = np.real((V[None, :, :] * np.exp(np.outer(s, lam))[:, None, :]) @ c)
        return hom + P[None] * np.sin(om * (t0 + s))[:, None] + Q[None] * np.cos(om * (t0 + s))[:, None]

    def gaps(z):
        return np.array([z[..., 1] + gap, gap - z[..., 1]])

    T = 2 * np.pi / om

    def period_map(z, events=None, n=2000):
        t = 0.0
        while True:
            s = np.linspace(0, T - t, n + 1)[1:]
            g = gaps(flow(z, t, s))
            hit = None
            for j in (0, 1):
                k = np.nonzero(g[j] < 0)[0]
                if len(k) and (hit is None or k[0] < hit[1]):
                    hit = (j, k[0])
            if hit is None:
                return flow(z, t, [T - t])[0]
            j, k = hit
            lo = s[k - 1] if k > 0 else 1e-13
            u = root(lambda x: gaps(flow(z, t, [x])[0])[j], lo, s[k])
            z = flow(z, t, [u])[0].copy()
            t += u
            if events is not None:
                events.append((j, (om * t) % (2 * np.pi), z[3] if j == 0 else -z[3]))
            z[3] = -r * z[3]

    z = np.zeros(4)
    for _ in range(200):
        z = period_map(z)
    for _ in range(6):
        J = np.zeros((4, 4))
        for i in range(4):
            dz = np.zeros(4)
            dz[i] = 1e-7
            J[:, i] = (period_map(z + dz) - period_map(z - dz)) / 2e-7
        z = z - np.linalg.solve(J - np.eye(4), period_map(z) - z)
    events = []
    assert np.abs(period_map(z, events) - z).max() < 1e-13
    return z, events, np.linalg.eigvals(J)


def test_tube_period_one_at_0_44_matches_independent_orbit(tube):
    # The sweep's period-1 attractor at omega = 0.44 (no branch held it before every periodic
    # attractor was seeded: its seed's branch was taken for branch 0's, which reaches 0.43 only) lies
    # on a stable branch. The branch's points are where its continuation stepped (since the half-map
    # march took branch 0 through its double grazing at 0.41277, the covering branch's nearest point
    # is 0.43476, not 0.44), so the test checks vibro's orbit twice against the flow written here:
    # (1) the covering branch's point nearest 0.44, against the independent orbit at that point's own
    #     omega: its stroboscopic state, impacts (phases, speeds) to 1e-9, multipliers to 1e-6;
    # (2) vibro's orbit at exactly omega = 0.44, continued from that point by `vibro orbit
    #     --transient 0` (Newton from the point's state, at the point's forcing phase), against the
    #     independent orbit at 0.44: the same impacts and multipliers, stable, period 1.
    d, out = tube
    om = 0.4 + 0.04  # the sweep's value, as the sweep steps it
    hits = [c for c in d["coverage"] if abs(c["value"] - om) < 1e-12 and c["source"] != "search"]
    assert len(hits) == 2 and all(c["branch"] is not None and c["distance"] <= 1e-3 for c in hits), hits
    k = hits[0]["branch"]
    assert hits[1]["branch"] == k, hits
    with h5py.File(out, "r") as f:
        g = f["diagram/branches/%03d/branch" % k]
        assert g.attrs["period"] == 1
        value = g["value"][:]
        i = int(np.argmin(np.abs(value - om)))
        # Within one step of the sweep's value, on the stable stretch that covers it.
        assert abs(value[i] - om) < 1e-2, value[i]
        assert g["stable"][i]
        strobe = g["strobe"][i]
        o = g["impact_offsets"][i:i + 2]
        phase = g["impact_phase"][o[0]:o[1]]
        speed = g["impact_v_before"][o[0]:o[1]]
        contact = g["impact_contact"][o[0]:o[1]]
        mu = g["multipliers"][i]
        q, q_dot, t0 = g["q"][i], g["q_dot"][i], float(g["section_time"][i])

    def same_orbit(phase, speed, contact, mine, om_, strobe=None):
        z, events, mult = tube_orbit(om_)
        if strobe is not None:
            # strobe: q1 at t = 0 mod T, for both contacts (both on DOF 1)
            assert np.abs(strobe - z[1]).max() < 1e-9, (om_, strobe, z[1])
        assert len(phase) == len(events) == 2, (om_, phase, events)
        for j, ph, v in events:
            (m,) = np.nonzero(contact == j)[0]
            assert abs((phase[m] - ph + np.pi) % (2 * np.pi) - np.pi) < 1e-9, (om_, j, phase[m], ph)
            assert abs(speed[m] - v) < 1e-9, (om_, j, speed[m], v)
        # The multipliers (with the saltation at each impact), against the central-difference
        # Jacobian of the period map here: each of one set next to one of the other.
        assert len(mine) == len(mult)
        for a, b in ((mine, mult), (mult, mine)):
            assert max(np.abs(b - x).min() for x in a) < 1e-6, (om_, mine, mult)

    # (1) the branch's own point
    same_orbit(phase, speed, contact, mu[:, 0] + 1j * mu[:, 1], float(value[i]), strobe)
    # (2) at exactly 0.44, from that point: its state at its section time t0, the forcing phase
    # value[i] * t0 kept (initial.time = value[i] * t0 / 0.44).
    fmt = lambda x: "[%s]" % ", ".join(repr(float(v)) for v in x)  # noqa: E731
    p = vibro("orbit", os.path.join(SCENES, "tube_loose_support.toml"), "--set", "excitation.frequency=%r" % om,
              "--set", "initial.displacement=" + fmt(q), "--set", "initial.velocity=" + fmt(q_dot),
              "--set", "initial.time=%r" % (float(value[i]) * t0 / om), "--transient", 0, "--json")
    r = json.loads(p.stdout)
    assert r["status"] == "converged" and r["period"] == 1 and r["stable"], r["message"]
    assert r["sequence"] == "0:impact 1:impact", r["sequence"]
    # Newton went from the branch's point to the orbit at 0.44: a short way (one step of the branch).
    assert r["distance_from_start"] < 0.1, r["distance_from_start"]
    mine = np.array([complex(re_, im_) for re_, im_ in r["floquet_multipliers"]])
    same_orbit(np.array(r["impact_phases"]), np.array(r["impact_velocities"]), np.array(r["impact_contacts"]),
               mine, om)


# --- (c) bad input --------------------------------------------------------------------------------


def test_bad_input(tmp_path):
    out = tmp_path / "never.h5"
    scene = os.path.join(SCENES, "tube_loose_support.toml")
    for args, where in ((["--param", "excitation.frequency", "--from", 1, "--to", 1], "--from"),
                        (["--param", "excitation.frequency", "--from", -1, "--to", 1], "--from -1"),
                        (["--param", "excitation.nothing", "--from", 0.5, "--to", 1], "excitation.nothing"),
                        (["--param", "excitation.frequency", "--from", 0.5, "--to", 1, "--max-period", 0],
                         "--max-period")):
        p = vibro("diagram", scene, *args, "--out", out, check=False)
        assert p.returncode == 2, (args, p.stderr)
        assert where in p.stderr, (args, p.stderr)
        assert not out.exists()


def test_cap_names_what_it_left_out(tmp_path):
    # A cap of 2 branches on the two-sided oscillator over a in [1, 8]: the first two seeds' own
    # branches are stored (seeds before any switch); every other seed and every switch is named as
    # left out, and each periodic attractor no stored branch holds is uncovered with the cap as
    # the reason.
    out = tmp_path / "cap.h5"
    args = ("diagram", os.path.join(SCENES, "contacts_two_sided_1dof.toml"), "--set", "contact[0].restitution=0.6",
            "--set", "contact[1].restitution=0.6", "--set", "excitation.frequency=2.0", "--set", "run.periods=200",
            "--param", "excitation.amplitude", "--from", 1, "--to", 8, "--steps", 28, "--max-branches", 2)
    p = vibro(*args, "--out", out)
    d = json.loads(vibro(*args, "--json").stdout)
    assert len(d["branches"]) == 2 and all(b["origin"] == "seed" for b in d["branches"])
    assert d["cap_reached"] and d["seeds_left_out"] >= 1 and d["switches_left_out"] >= 1
    notes = d["notes"]
    assert sum("was not continued: --max-branches 2 reached" in n for n in notes) == d["seeds_left_out"], notes
    assert sum("--max-branches 2 reached" in n and ("not switched at" in n or "not stored" in n)
               for n in notes) == d["switches_left_out"], notes
    # The pitchfork of the symmetric branch is among the switches named.
    truth = float(pitchfork())
    assert any("branch-point at excitation.amplitude = %.6f" % truth in n and "not switched at" in n
               for n in notes), notes
    capped = [c for c in d["coverage"] if c["branch"] is None and c["period"] is not None]
    assert capped and any("--max-branches 2 reached" in c["reason"] for c in capped), capped
    for c in capped:
        assert c["reason"].startswith("no stable"), c
    line = [x for x in p.stdout.splitlines() if x.startswith("left out")]
    assert line == ["left out     --max-branches 2 reached: %d seed%s not continued, %d switch%s not followed "
                    "(each named in the notes)" % (d["seeds_left_out"], "" if d["seeds_left_out"] == 1 else "s",
                                                   d["switches_left_out"],
                                                   "" if d["switches_left_out"] == 1 else "es")], p.stdout
    with h5py.File(out, "r") as f:
        a = f["diagram"].attrs
        assert (a["cap_reached"], a["seeds_left_out"], a["switches_left_out"]) == \
            (1, d["seeds_left_out"], d["switches_left_out"])


def test_defaults_are_the_same_for_cli_and_python():
    # `vibro diagram --help` states each default; Python's vibro.diagram has the same ones (both
    # from the library's DiagramDefaults).
    import inspect
    import re
    vibro_py = pytest.importorskip("vibro")
    text = " ".join(vibro("diagram", "--help").stdout.split())
    sig = inspect.signature(vibro_py.diagram).parameters
    options = {"--steps": "steps", "--record": "record", "--searches": "searches", "--grid": "grid",
               "--max-period": "max_period", "--max-branches": "max_branches", "--max-points": "max_points",
               "--coverage-tolerance": "coverage_tolerance", "--threads": "threads"}
    for opt, name in options.items():
        m = re.search(re.escape(opt) + r"\s+\S+\s.*?\(default ([0-9.e+-]+)", text)
        assert m, (opt, text)
        assert float(m.group(1)) == sig[name].default, (opt, m.group(1), sig[name].default)
    # ... which are the library's (vibro::DiagramDefaults, what a C++ DiagramRequest starts with).
    lib = vibro_py._vibro.diagram_defaults()
    assert set(lib) == set(options.values())
    assert all(lib[name] == sig[name].default for name in lib), (lib, sig)
    assert sig["coverage_tolerance"].default == 1e-3 and sig["max_branches"].default == 100


# --- (d) Python: vibro.diagram ---------------------------------------------------------------------


def test_python_diagram():
    vibro_py = pytest.importorskip("vibro")
    scene = vibro_py.load_scene(os.path.join(SCENES, "contacts_two_sided_1dof.toml"),
                                set={"contact[0].restitution": 0.6, "contact[1].restitution": 0.6,
                                     "excitation.frequency": 2.0, "excitation.amplitude": 2.0, "run.periods": 200})
    d = vibro_py.diagram(scene, "excitation.amplitude", 2.0, 4.0, steps=6, searches=0)
    truth = float(pitchfork())
    assert d["branches"]
    for b in d["branches"]:
        n = len(b["points"])
        assert b["value"].shape == (n,) and b["stable"].dtype == bool and b["strobe"].shape[0] == n
    sym = [b for b in d["branches"] if any(x["kind"] == "branch-point" and abs(x["value"] - truth) < 1e-12
                                          for x in b["bifurcations"])]
    assert len(sym) == 1
    born = [b for b in d["branches"] if b["origin"] == "branch-point"]
    assert len(born) == 2
    # Mirror images: at their last points (a = 4, reached by both), the strobe of one is not the other's.
    ends = [b["value"][-1] for b in born]
    assert all(abs(e - 4.0) < 1e-12 for e in ends)
    assert abs(born[0]["strobe"][-1, 0] - born[1]["strobe"][-1, 0]) > 1e-3
    assert d["sweep_value"].shape == d["sweep_x_B"].shape


# --- (e) Ctrl-C: exit 130, the finished branches kept ----------------------------------------------


def test_interrupt_keeps_finished_branches(tmp_path):
    import signal
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    out = tmp_path / "int.h5"
    p = subprocess.Popen([CLI, "diagram", os.path.join(SCENES, "tube_loose_support.toml"), "--param",
                          "excitation.frequency", "--from", "0.4", "--to", "1.6", "--steps", "30", "--out", str(out)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    # The progress report on stderr (rate-limited) says how many branches are stored: interrupt at
    # its first report of at least one.
    import re
    seen = b""
    while not re.search(rb"\(([1-9]\d*) / \d+\)", seen):
        chunk = p.stderr.read1(256)
        if not chunk:
            break
        seen += chunk
    assert re.search(rb"\(([1-9]\d*) / \d+\)", seen), seen[-400:]
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=600)
    assert p.returncode == 130, err
    with h5py.File(out, "r") as f:
        assert f["diagram"].attrs["status"] in (b"interrupted", "interrupted")
        assert f["diagram"].attrs["branches"] >= 1
        assert len(f["diagram/branches"]) == f["diagram"].attrs["branches"]
