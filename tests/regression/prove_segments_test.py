#!/usr/bin/env python3
"""Segments of a branch proven on models of more than one mode (docs/prove.md "Along a branch"):
`vibro prove SCENE --branch FILE.h5` proves, between two neighbouring points, every orbit for every
parameter value of the interval at once (validated continuation). Issue 40.

- The heat-exchanger tube in its two-sided support (damped, two contacts, physical form) and the
  2-DOF chain (one stop, physical form), each over the amplitude: every segment proven, the checker
  confirms every certificate, and at sample parameters of each segment (both ends, 1/3, the middle,
  0.9) the orbit computed here at 50 digits (prove_truth.py: the modal data from the matrices, Newton
  on the multiple-shooting map, the multipliers by central differences of the stroboscopic map;
  nothing read from vibro's sources) lies in the segment certificate's enclosures: every impact's
  time, phase, contact and velocity, the section, and each multiplier.
- Edits of a segment certificate are rejected: the parameter interval made 100 times longer or
  moved by its length, an event time or a multiplier narrowed to the orbit of the middle
  parameter, the box shrunk to the middle orbit's neighbourhood, a Krawczyk component narrowed.
- A segment across a bifurcation (two neighbouring points on either side of the tube's
  symmetry-breaking pitchfork, which the orbit of the middle of the segment crosses): not proven.
- Segments in the forcing frequency (the tube, the 2-DOF chain at f = 5): proven in a tube along the
  family's tangent, confirmed, against the 50-digit truth at five parameters of each piece; edits of
  the tangent (direction, centre, box, left out) and of the interval rejected.
Usage: prove_segments_test.py VIBRO CHECKER
"""
import copy
import json
import os
import subprocess
import sys

from mpmath import mp, mpf, pi

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prove_truth import Harness, inside, orbit_truth  # noqa: E402

mp.dps = 50
VIBRO, CHECKER = sys.argv[1:3]
H = Harness(VIBRO, CHECKER, "vibro_prove_segments_")
TMP = H.tmp
expect, check_doc = H.expect, H.check_doc
SCENES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "data", "scenes")
KEYS = {"excitation.amplitude": "amplitude", "excitation.frequency": "frequency"}


def continued(label, scene, param, to, step, points, *sets):
    path = os.path.join(TMP, label + ".h5")
    p = subprocess.run([VIBRO, "continue", scene, "--kind", "impact", "--param", param, "--to", to, "--step", step,
                        "--max-points", str(points), "--out", path, *sets], capture_output=True, text=True, timeout=600)
    expect(p.returncode == 0, f"{label}: a branch to prove (exit {p.returncode}: {p.stderr[-300:]})")
    return path, p.stdout


def prove_branch(label, scene, h5, *sets):
    out = os.path.join(TMP, label + ".json")
    p = subprocess.run([VIBRO, "prove", scene, "--branch", h5, "--json", "--out", out, *sets],
                       capture_output=True, text=True, timeout=900)
    b = json.loads(p.stdout) if p.stdout.strip() else {}
    doc = json.load(open(out)) if os.path.exists(out) else {"certificates": []}
    return p.returncode, b, doc


def ends(text):
    a, b = (s.strip() for s in text[1:-1].split(","))
    return mpf(a), mpf(b), a, b


def truth_at(cert, key, value):
    """The orbit of the certificate's model with the parameter `key` at the decimal `value`, at 50
    digits, from the certificate's midpoint."""
    c = copy.deepcopy(cert)
    c["model"][key] = value
    return orbit_truth(c)


def contains_truth(label, s, tr, cert=None, value=None):
    """Every claim of the segment's summary contains the orbit `tr` (one parameter of the segment)."""
    m = tr["m"]
    expect(tr["positive"], f"{label}: the 50-digit orbit keeps every gap positive between its impacts")
    det_fd, det_closed = tr["det"]
    expect(abs(det_fd - det_closed) <= mpf("1e-20") * (1 + abs(det_closed)),
           f"{label}: the truth's stroboscopic Jacobian has the closed-form determinant ({mp.nstr(det_fd, 12)})")
    ev = s["events"]
    expect(len(ev) == len(tr["times"]), f"{label}: {len(ev)} events, the truth has {len(tr['times'])} impacts")
    for j, e in enumerate(ev[:len(tr["times"])]):
        t = tr["times"][j]
        expect(e["contact"] == tr["hits"][j], f"{label}: impact {j} at contact {e['contact']} (truth {tr['hits'][j]})")
        expect(inside(t, e["time"]), f"{label}: impact {j} time {mp.nstr(t, 20)} in {e['time']}")
        ph = (m.w * t) % (2 * pi)
        expect(inside(ph, e["phase"]), f"{label}: impact {j} phase {mp.nstr(ph, 20)} in {e['phase']}")
        expect(inside(tr["vbefore"][j], e["velocity_before"]),
               f"{label}: impact {j} velocity before {mp.nstr(tr['vbefore'][j], 20)} in {e['velocity_before']}")
    t0, X0, V0 = tr["section"]
    sec = s["section"]
    expect(inside(t0, sec["time"]) and all(inside(x, p) for x, p in zip(X0, sec["X"])) and
           all(inside(v, p) for v, p in zip(V0, sec["V"])), f"{label}: the section state contains the truth")
    claims, used = s["multipliers"], set()
    if not claims and not (cert and "spectral_bound" in cert):  # not enclosed over the box: no stability claimed
        expect(s["stability"] == "undecided", f"{label}: no multiplier claimed, stability undecided ({s['stability']})")
    if cert and "spectral_bound" in cert:
        # Stability along a frequency segment: the 50-digit multipliers at this parameter below the
        # bound claimed for the sub-piece that holds it, and inside the unit disc.
        expect(s["stability"] == "stable", f"{label}: a spectral bound, stability stable ({s['stability']})")
        where = [p for p in cert["spectral_bound"] if ends(p["interval"])[0] <= mpf(value) <= ends(p["interval"])[1]]
        rho = max(abs(mu) for mu in tr["multipliers"])
        expect(where and all(rho <= p["bound"] < 1 for p in where),
               f"{label}: the spectral radius {mp.nstr(rho, 12)} (50 digits) below the sub-piece's bound "
               f"{[p['bound'] for p in where]}")
    for mu in tr["multipliers"] if claims else []:
        hit = next((k for k, c in enumerate(claims) if k not in used and inside(mp.re(mu), c["re"]) and
                    inside(mp.im(mu), c["im"])), None)
        expect(hit is not None, f"{label}: the multiplier {mp.nstr(mu, 15)} lies in a claimed enclosure")
        if hit is not None:
            used.add(hit)


def segments_proven(label, scene, param, to, step, points, *sets):
    """Every point and segment of the branch proven and confirmed; each segment against the truth at
    sample parameters. Returns the segment certificates with their truths at the middle."""
    key = KEYS[param]
    h5 = continued(label, scene, param, to, step, points, *sets)[0]
    code, b, doc = prove_branch(label, scene, h5, *sets)
    segs = b.get("segments", [])
    expect(code == 0 and b.get("proven") == b.get("total") == points,
           f"{label}: every point proven (exit {code}, {b.get('proven')} of {b.get('total')})")
    expect(len(segs) == points - 1 and b.get("segments_proven") == points - 1,
           f"{label}: the {points - 1} segments proven ({b.get('segments_proven')}: "
           f"{[p['reason'][:200] for s_ in segs for p in s_['pieces'] if p['verdict'] != 'proven']})")
    path = os.path.join(TMP, label + ".json")
    p = subprocess.run([sys.executable, CHECKER, path, "--json"], capture_output=True, text=True, timeout=1800)
    v = json.loads(p.stdout) if p.stdout.strip() else {}
    expect(p.returncode == 0 and v.get("verdict") == "confirmed",
           f"{label}: the checker confirms every point and segment ({v.get('reason', p.stderr[-300:])})")
    pieces = [c for c in doc["certificates"] if c["model"][key].startswith("[")]
    expect(len(pieces) >= points - 1, f"{label}: {len(pieces)} segment certificate(s) written")
    out = []
    for c in pieces:
        a, z, a_text, z_text = ends(c["model"][key])
        expect(c["verdict"] == "proven" and c["reason"].startswith(f"for every {key} in [{a_text}, {z_text}]: exactly one"),
               f"{label}: the theorem names its interval ({c['reason'][:90]})")
        samples = [a_text, mp.nstr(a + (z - a) / 3, 30), mp.nstr((a + z) / 2, 30), mp.nstr(a + (z - a) * 9 / 10, 30),
                   z_text]
        for value in samples:
            expect(a <= mpf(value) <= z, f"{label}: the sample {value} lies in [{a_text}, {z_text}]")
            contains_truth(f"{label} [{a_text}, {z_text}] at {key} = {value}", c["summary"], truth_at(c, key, value),
                           c, value)
        # The middle of the first, the middle and the last stability sub-piece, against the truth too.
        subs = c.get("spectral_bound", [])
        for sub in [subs[0], subs[len(subs) // 2], subs[-1]] if subs else []:
            x0, x1 = ends(sub["interval"])[:2]
            value = mp.nstr((x0 + x1) / 2, 30)
            contains_truth(f"{label} sub-piece {sub['interval']} at {key} = {value}", c["summary"],
                           truth_at(c, key, value), c, value)
        out.append(c)
    return out


def rejected(label, cert, name, edit):
    c = copy.deepcopy(cert)
    edit(c)
    code, v = check_doc(c)
    expect(code in (1, 2), f"{label}: {name}: rejected (exit {code}, {v and v['reason'][:160]})")


def narrow(pair, x, rel=mpf("1e-14")):
    """[x − δ, x + δ] as floats, δ relative to x: a claim that holds the truth at one parameter only."""
    d = rel * (1 + abs(x))
    return [float(x - d), float(x + d)]


# ---- The tube (damped, two contacts, physical form) over the amplitude ------------------------------
tube = os.path.join(SCENES, "tube_loose_support.toml")
tube_segments = segments_proven("tube_amplitude", tube, "excitation.amplitude", "0.31", "0.002", 3)
if tube_segments:
    seg = tube_segments[0]
    a, z, a_text, z_text = ends(seg["model"]["amplitude"])
    mid_text = mp.nstr((a + z) / 2, 30)
    middle = truth_at(seg, "amplitude", mid_text)
    label = "tube segment"
    # The same proof claimed for a longer interval, or for the next one.
    rejected(label, seg, "the interval 100 times longer", lambda c: c["model"].__setitem__(
        "amplitude", f"[{a_text}, {mp.nstr(a + 100 * (z - a), 20)}]"))
    rejected(label, seg, "the interval moved by its length", lambda c: c["model"].__setitem__(
        "amplitude", f"[{z_text}, {mp.nstr(2 * z - a, 20)}]"))
    def reason_interval(c):  # the theorem stated for a longer interval than the model's
        c["reason"] = c["reason"].replace(z_text, mp.nstr(z + (z - a), 20), 1)
        c["summary"]["reason"] = c["reason"]
    rejected(label, seg, "the reason's interval not the model's", reason_interval)

    def narrow_time(c):
        c["summary"]["events"][0]["time"] = narrow(c["summary"]["events"][0]["time"], middle["times"][0])
    rejected(label, seg, "impact 0's time narrowed to the middle orbit's", narrow_time)

    def narrow_velocity(c):
        c["summary"]["events"][1]["velocity_before"] = narrow(None, middle["vbefore"][1])
    rejected(label, seg, "impact 1's velocity narrowed to the middle orbit's", narrow_velocity)

    def multipliers_of_the_middle(c):  # the middle orbit's multipliers claimed for the whole segment
        c["summary"]["multipliers"] = [{"re": narrow(None, mp.re(mu), mpf("1e-12")), "im": narrow(None, mp.im(mu), mpf("1e-12"))}
                                       for mu in middle["multipliers"]]
        c["summary"]["stability"] = "stable"
    rejected(label, seg, "the middle orbit's multipliers claimed for the segment", multipliers_of_the_middle)
    rejected(label, seg, "'stable' claimed without the multipliers", lambda c: c["summary"].__setitem__("stability", "stable"))

    def shrink_box(c):  # a box of relative half-width 1e-12 around the midpoint: too small for the interval
        c["box"] = [[x - 1e-12 * (1 + abs(x)), x + 1e-12 * (1 + abs(x))] for x in c["midpoint"]]
    rejected(label, seg, "the box shrunk to the middle orbit's neighbourhood", shrink_box)

    def narrow_krawczyk(c):
        x = c["midpoint"][0]
        c["krawczyk"][0] = [x - 1e-15, x + 1e-15]
    rejected(label, seg, "a Krawczyk component narrowed to the midpoint", narrow_krawczyk)

    def point_parameter(c):  # the proof claimed at a point past the segment, as far from it as its length
        c["model"]["amplitude"] = mp.nstr(2 * z - a, 20)
        c["reason"] = c["reason"].split(": ", 1)[1]
        c["summary"]["reason"] = c["reason"]
    rejected(label, seg, "the parameter replaced by a point past the segment", point_parameter)

# ---- A segment across the tube's pitchfork (ω = 0.95: a branch point at f ≈ 0.4357670296) ----------
# `vibro continue` from f = 0.435 steps over it: its first two points lie on either side. Where a real
# multiplier is +1 the shooting map's Jacobian is singular, so no box holding that orbit passes
# Krawczyk's test (which proves every Jacobian of the box invertible): the segment must not be proven.
h5, text = continued("tube_pitchfork", tube, "excitation.amplitude", "0.44", "0.002", 4,
                     "--set", "excitation.frequency=0.95", "--set", "excitation.amplitude=0.435")
located = [float(line.split("= ")[1].split()[0]) for line in text.splitlines() if line.startswith("bifurcation  branch-point")]
code, b, doc = prove_branch("tube_pitchfork", tube, h5, "--set", "excitation.frequency=0.95")
segs = b.get("segments", [])
first = segs[0] if segs else {}
expect(located and first and min(first["from"], first["to"]) < located[0] < max(first["from"], first["to"]),
       f"across the pitchfork: the first segment [{first.get('from')}, {first.get('to')}] holds the branch point {located}")
expect(code == 0 and b.get("proven") == b.get("total") == 4 and first and not first["proven"],
       f"across the pitchfork: the points proven, the segment across it not (exit {code}, "
       f"{first and first['pieces'][0]['reason'][:200]})")
expect(first and "Krawczyk" in first["pieces"][0]["reason"], "across the pitchfork: the reason names Krawczyk's test")
expect(not any(c["model"]["amplitude"].startswith("[") and
               mpf(ends(c["model"]["amplitude"])[0]) <= mpf(repr(located[0])) <= mpf(ends(c["model"]["amplitude"])[1])
               for c in doc["certificates"]) if located else False,
       "across the pitchfork: no certificate's interval holds the branch point")

# ---- The 2-DOF chain (one stop, physical form) over the amplitude -----------------------------------
chain = os.path.join(SCENES, "chain2.toml")
segments_proven("chain2_amplitude", chain, "excitation.amplitude", "5.02", "0.005", 3, "--set", "excitation.amplitude=5")

# ---- Segments in the forcing frequency (docs/prove.md "Segments in the frequency") -----------------
# The residual is not affine in ω and the times move with the period: the proof encloses the family
# in a tube along its tangent, ũ + a(ω − ω̃) + W, with a Taylor form in ω (the certificate's
# `tangent`). The tube at ω = 0.9 (steps of 0.002 and 0.001) and the 2-DOF chain's six-impact
# period-2 orbit at f = 5 from ω = 0.8; every orbit at five parameters of each piece (50 digits) in
# the piece's enclosures.
tube_w = segments_proven("tube_frequency", tube, "excitation.frequency", "0.91", "0.002", 3)
segments_proven("chain2_frequency", chain, "excitation.frequency", "0.81", "0.001", 3, "--set", "excitation.amplitude=5")
# Next to the tube's pitchfork (ω* = 0.955442599911…): the largest |μ| reaches 0.995 at 0.955, the
# Krawczyk pieces and the stability sub-pieces are smallest there; every piece proven stable.
near = segments_proven("tube_near_pitchfork", tube, "excitation.frequency", "0.955", "0.001", 2,
                       "--set", "excitation.frequency=0.954")
expect(bool(near) and all(c["summary"]["stability"] == "stable" for c in near),
       "next to the pitchfork: every piece proven stable")
if tube_w:
    seg = tube_w[-1]
    a, z, a_text, z_text = ends(seg["model"]["frequency"])
    middle = truth_at(seg, "frequency", mp.nstr((a + z) / 2, 30))
    label = "tube frequency segment"
    rejected(label, seg, "the interval 100 times longer", lambda c: c["model"].__setitem__(
        "frequency", f"[{a_text}, {mp.nstr(a + 100 * (z - a), 20)}]"))
    rejected(label, seg, "the interval moved by its length", lambda c: c["model"].__setitem__(
        "frequency", f"[{z_text}, {mp.nstr(2 * z - a, 20)}]"))
    rejected(label, seg, "the tangent's direction set to 0 (a tube that does not follow the family)",
             lambda c: c["tangent"].__setitem__("direction", [0.0] * len(c["tangent"]["direction"])))
    rejected(label, seg, "the tangent's direction of the times halved",
             lambda c: c["tangent"]["direction"].__setitem__(0, c["tangent"]["direction"][0] / 2))
    rejected(label, seg, "the tangent's centre outside the interval",
             lambda c: c["tangent"].__setitem__("centre", float(2 * z - a)))
    rejected(label, seg, "the tube's box W shrunk 100 times",
             lambda c: c["tangent"].__setitem__("box", [[x / 100 for x in w] for w in c["tangent"]["box"]]))
    rejected(label, seg, "the tangent left out", lambda c: c.pop("tangent"))

    def unique_in_box(c):  # uniqueness claimed in the whole box: the tangent's proof gives it in the tube only
        head, rest = c["reason"].split(" in the tube along", 1)
        width = rest.split("in its box of width ")[1].split(" ")[0]
        c["reason"] = f"{head} and no other contact in a box of width {width} around the orbit found (Krawczyk)"
        c["summary"]["reason"] = c["reason"]
    rejected(label, seg, "uniqueness in the whole box claimed", unique_in_box)

    def narrow_time(c):
        c["summary"]["events"][0]["time"] = narrow(c["summary"]["events"][0]["time"], middle["times"][0])
    rejected(label, seg, "impact 0's time narrowed to the middle orbit's", narrow_time)
    # Stability along the segment (docs/prove.md "Stability along a segment"): edits of the spectral bound.
    expect(seg["summary"]["stability"] == "stable" and seg.get("spectral_bound"),
           f"{label}: proven stable with a spectral bound ({seg['summary']['stability']})")
    rejected(label, seg, "'stable' claimed with the spectral bound left out", lambda c: c.pop("spectral_bound"))
    sub0 = seg["spectral_bound"][0]
    x0, x1 = ends(sub0["interval"])[:2]
    rho0 = max(abs(mu) for mu in truth_at(seg, "frequency", mp.nstr((x0 + x1) / 2, 30))["multipliers"])

    def bound_below_truth(c):  # a bound below the 50-digit spectral radius in the sub-piece
        c["spectral_bound"][0]["bound"] = float(rho0) - 1e-3
    rejected(label, seg, f"a sub-piece's bound below the true spectral radius {mp.nstr(rho0, 8)}", bound_below_truth)
    if len(seg["spectral_bound"]) > 1:
        rejected(label, seg, "the last sub-piece left out (not covering the interval)",
                 lambda c: c["spectral_bound"].pop())
        rejected(label, seg, "the first sub-piece left out", lambda c: c["spectral_bound"].pop(0))
    rejected(label, seg, "a sub-piece's interval moved past the segment's end", lambda c: c["spectral_bound"][-1].__setitem__(
        "interval", c["spectral_bound"][-1]["interval"].split(",")[0] + f", {mp.nstr(2 * z - a, 20)}]"))

    def singular(c):
        for row in c["spectral_bound"][0]["similarity"]:
            row[0] = 0.0
    rejected(label, seg, "a singular similarity", singular)
    # (Other blocks for the same S give another valid norm: a bound still above it is true, and confirmed.)
    rejected(label, seg, "a sub-piece's bound claimed as 1", lambda c: c["spectral_bound"][0].__setitem__("bound", 1.0))
    rejected(label, seg, "a sub-piece's tube box shrunk 1000 times", lambda c: c["spectral_bound"][0]["tangent"].__setitem__(
        "box", [[x / 1000 for x in w] for w in c["spectral_bound"][0]["tangent"]["box"]]))
    rejected(label, seg, "a sub-piece's tube moved off the segment's (its midpoint's time + 1e-3)",
             lambda c: c["spectral_bound"][0]["midpoint"].__setitem__(0, c["spectral_bound"][0]["midpoint"][0] + 1e-3))
    rejected(label, seg, "the note left out", lambda c: c["summary"].pop("stability_note"))
    if tube_segments:
        rejected("tube amplitude segment", tube_segments[0], "a spectral bound given to a segment in the amplitude",
                 lambda c: (c.__setitem__("spectral_bound", copy.deepcopy(seg["spectral_bound"])),
                            c["summary"].__setitem__("stability", "stable")))
    if tube_segments:
        rejected("tube amplitude segment", tube_segments[0], "a tangent given to a segment in the amplitude",
                 lambda c: c.__setitem__("tangent", copy.deepcopy(seg["tangent"])))

H.finish()
