#!/usr/bin/env python3
"""`vibro prove` on sticking orbits held on sets of contacts (docs/prove.md "Sticking orbits held on
sets of contacts") against a truth computed here at 50 digits in physical coordinates
(held_set_truth.py: the scene's matrices, mpmath's expm of the flows held on each set, findroot on
the multiple-shooting map; nothing of vibro's sources).

Scene A of issue 37 (two masses on preloaded stops, r = 0: each period mass 1 is released, then
mass 0, mass 1 lands and sticks, mass 0 lands beside it and both are held) and the damped 3-DOF chain
whose first two masses are held together while the third moves: every event's kind, contact, phase
and contact velocity, the section (modal enclosures mapped to physical coordinates) and the
multipliers one-to-one contain the truth; the checker confirms; mutations of the certificate are
rejected. Soundness: along scene A's family in the amplitude the landings of the two masses meet at
f* (computed here); 1e-9 on the side where the sequence holds the orbit is proven, 1e-9 past it no
orbit with this sequence is proven. A chattering scene of several contacts is refused with its reason.
Usage: prove_held_set_test.py VIBRO CHECKER SCENES
"""
import copy
import json
import os
import sys

from mpmath import mp, mpf, iv, matrix, eigsy, sqrt, pi, findroot, asin

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prove_truth import Harness, inside  # noqa: E402
from held_set_truth import SetTruth  # noqa: E402

mp.dps = 50
iv.dps = 50
VIBRO, CHECKER, SCENES = sys.argv[1:4]
H = Harness(VIBRO, CHECKER, "vibro_prove_held_set_")
expect, prove, check, scene_file = H.expect, H.prove, H.check, H.scene_file

SCENE_A = """title = "Issue 37, scene A: two masses on preloaded stops, r = 0"
[structure]
mass = [[1.0, 0.0], [0.0, 1.0]]
stiffness = [[2.0, -1.0], [-1.0, 1.0]]
forcing_dof = 1
[[contact]]
dof = 0
side = "below"
position = 0.2
restitution = 0.0
[[contact]]
dof = 1
side = "below"
position = 0.3
restitution = 0.0
[excitation]
amplitude = {f}
frequency = 0.5
[initial]
displacement = [0.2, 0.3]
velocity = [0.0, 0.0]
"""
CHAIN3 = """title = "damped 3-DOF chain, the first two masses on stops, r = 0"
[structure]
mass = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
stiffness = [[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]]
forcing_dof = 1
damping_ratios = [0.05, 0.05, 0.05]
[[contact]]
dof = 0
side = "below"
position = 0.2
restitution = 0.0
[[contact]]
dof = 1
side = "below"
position = 0.3
restitution = 0.0
[excitation]
amplitude = 2.0
frequency = 0.5
[initial]
displacement = [0.2, 0.3, 0.3]
velocity = [0.0, 0.0, 0.0]
"""
M2, K2 = [[1, 0], [0, 1]], [[2, -1], [-1, 1]]
M3, K3 = [[1, 0, 0], [0, 1, 0], [0, 0, 1]], [[2, -1, 0], [-1, 2, -1], [0, -1, 1]]
STOPS = [(0, -1, "below", "0.2"), (1, -1, "below", "0.3")]


def contains_phase(pair, t, w):
    p = (w * t) % (2 * pi)
    return any(inside(p + k * 2 * pi, pair) for k in (-1, 0, 1))


def shapes(Mx, Kx):
    """The mode shapes ψ_k (ascending ω), scaled to a unit component at contact 0 (docs/prove.md):
    the physical state is q = Σ_k ψ_k X_k. 50 digits."""
    N = len(Mx)
    Mh = matrix(N, N)
    for i in range(N):
        Mh[i, i] = 1 / sqrt(mpf(Mx[i][i]))
    lam, Q = eigsy(Mh * matrix(Kx) * Mh)
    order = sorted(range(N), key=lambda k: lam[k])
    Phi = Mh * Q
    out = []
    for k in order:
        s = Phi[0, k]  # contact 0: mass 0 from below
        out.append([Phi[i, k] / s for i in range(N)])
    return out


def segments_of(s):
    """The segments (held set, landing?, contact, sticks) and their start times, from the summary's
    events: a release first, then landings (impact + stick/departure) and releases."""
    ev = s["events"]
    trans = []
    k = 1
    while k < len(ev):
        e = ev[k]
        if e["kind"] == "impact":
            trans.append((True, e["contact"], ev[k + 1]["kind"] == "stick", mpf(e["time"][0])))
            k += 2
        else:
            trans.append((False, e["contact"], False, mpf(e["time"][0])))
            k += 1
    first = ev[0]["contact"]
    trans.append((False, first, False, None))
    seen, held = set(), set()
    for landing, c, _, _ in trans:
        if c not in seen:
            seen.add(c)
            if not landing:
                held.add(c)
    held.discard(first)
    segs, times = [], [mpf(ev[0]["time"][0])]
    for landing, c, sticks, t in trans:
        segs.append((tuple(sorted(held)), landing, c, sticks))
        if t is not None:
            times.append(t)
        if landing and sticks:
            held.add(c)
        if not landing:
            held.discard(c)
    return segs, times


def truth_of(Mx, Kx, zeta, f, s):
    T = SetTruth(Mx, Kx, 1, [(d, p, side, x) for d, p, side, x in STOPS], f, "0.5", zeta=zeta, q=s["period"])
    segs, times = segments_of(s)
    psi = shapes(Mx, Kx)
    X = [mpf(p[0]) for p in s["section"]["X"]]
    V = [mpf(p[0]) for p in s["section"]["V"]]
    N = len(Mx)
    q = [sum(psi[k][i] * X[k] for k in range(N)) for i in range(N)]
    v = [sum(psi[k][i] * V[k] for k in range(N)) for i in range(N)]
    qs, vs = [], []
    for k, seg in enumerate(segs):  # carried from the section by the truth's own flows
        qs.append(q)
        vs.append(v)
        if k + 1 < len(segs):
            _, qe, ve = T.end_value(seg, times[k], q, v, times[k + 1] - times[k])
            q, v = qe, T.jump(seg, ve)
    return T.solve(segs, times, qs, vs), psi


def compare(label, s, T, psi):
    expect(T.residual < mpf("1e-40"), f"{label}: the truth's shooting map vanishes ({mp.nstr(T.residual, 3)})")
    ev = s["events"]
    tev = T.events()
    expect([(e["kind"], e["contact"]) for e in ev] == [(k, c) for k, c, _, _ in tev],
           f"{label}: the sequence {[(k, c) for k, c, _, _ in tev]}")
    for e, (kind, c, t, vm) in zip(ev, tev):
        expect(contains_phase(e["phase"], t, T.w), f"{label}: {kind} of contact {c}: the phase contains the truth "
                                                   f"{mp.nstr((T.w * t) % (2 * pi), 20)}")
        expect(inside(vm, e["velocity_before"]), f"{label}: {kind} of contact {c}: the contact velocity contains "
                                                 f"{mp.nstr(vm, 20)}")
    forces = T.forces_at_starts()
    expect(all(x > 0 for k, fs in enumerate(forces[1:]) for x in fs),
           f"{label}: the truth's held forces are positive at the segments' starts ({[[mp.nstr(x, 6) for x in fs] for fs in forces]})")
    # The section in physical coordinates: q = Σ ψ_k X_k over the claimed modal enclosures.
    t0, q0, v0 = T.starts[0]
    N = len(q0)
    for name, claim, truth in (("q", s["section"]["X"], q0), ("v", s["section"]["V"], v0)):
        for i in range(N):
            box = sum((iv.mpf(psi[k][i]) * iv.mpf([claim[k][0], claim[k][1]]) for k in range(N)), iv.mpf(0))
            expect(box.a <= truth[i] <= box.b, f"{label}: the section's {name}_{i} (physical) contains the truth "
                                                f"{mp.nstr(truth[i], 20)}")
    expect(inside(t0, s["section"]["time"]), f"{label}: the section's time contains {mp.nstr(t0, 20)}")
    mus = T.multipliers()
    claims = [(m["re"], m["im"]) for m in s["multipliers"]]
    left = list(claims)
    for mu in mus:
        hit = next((c for c in left if inside(mp.re(mu), c[0]) and inside(mp.im(mu), c[1])), None)
        expect(hit is not None, f"{label}: a claimed multiplier contains {mp.nstr(mu, 20)}")
        if hit is not None:
            left.remove(hit)
    expect(len(claims) == len(mus), f"{label}: {len(claims)} multipliers claimed, {len(mus)} on the held subspace")
    stable = all(abs(mu) < 1 for mu in mus)
    expect(s["stability"] == ("stable" if stable else "unstable"), f"{label}: stability {s['stability']}")


def mutations(label, path):
    cert = json.load(open(path))
    edits = []

    def add(name, fn):
        edits.append((name, fn))

    def seg(c, k):
        return c["segments"][k]
    add("a multiplier moved past its truth", lambda c: c["summary"]["multipliers"][0].__setitem__(
        "re", [c["summary"]["multipliers"][0]["re"][1] + 1e-12, c["summary"]["multipliers"][0]["re"][1] + 1e-11]))
    add("the release phase moved by its width", lambda c: c["summary"]["events"][0].__setitem__(
        "phase", [2 * c["summary"]["events"][0]["phase"][1] - c["summary"]["events"][0]["phase"][0],
                  3 * c["summary"]["events"][0]["phase"][1] - 2 * c["summary"]["events"][0]["phase"][0]]))
    add("a landing speed moved past", lambda c: c["summary"]["events"][2].__setitem__(
        "velocity_before", [c["summary"]["events"][2]["velocity_before"][1] + 1e-12,
                            c["summary"]["events"][2]["velocity_before"][1] + 1e-11]))
    add("an event's contact swapped", lambda c: c["summary"]["events"][1].__setitem__(
        "contact", 1 - c["summary"]["events"][1]["contact"]))
    add("the sequence edited", lambda c: c["summary"]["sequence"].__setitem__(1, "impact"))
    add("a held force's last piece removed", lambda c: seg(c, 0)["forces"][0]["pieces"].pop())
    add("a gap's end window times 64", lambda c: [g.__setitem__("end_window", g["end_window"] * 64)
                                                  for s_ in c["segments"] for g in s_["gaps"] if g["end_window"] > 0][:1])
    add("a segment's duration moved past", lambda c: seg(c, 1).__setitem__(
        "duration", [seg(c, 1)["duration"][1] + 1e-9, seg(c, 1)["duration"][1] + 2e-9]))
    add("a box component shrunk to its midpoint", lambda c: c["box"].__setitem__(
        1, [c["box"][1][0], c["midpoint"][1] + 1e-300]))
    add("the held set of segment 3 edited", lambda c: seg(c, 3).__setitem__("held", [0]))
    add("a release claimed as a landing", lambda c: [seg(c, 0).__setitem__("end", "landing"),
                                                     seg(c, 0).__setitem__("sticks", True)])
    add("the coupling W_01 moved off its value", lambda c: c["coupling"]["W"][0].__setitem__(1, [1e-3, 2e-3]))
    add("an impulse claim moved", lambda c: [s_["impulses"][0].__setitem__("value", [1.0, 2.0])
                                             for s_ in c["segments"] if s_.get("impulses")][:1])
    add("the restitution of contact 0 set to 0.5", lambda c: c["model"].__setitem__("restitution", "0.5"))
    add("the stability note of the 1-DOF orbit", lambda c: c["summary"].__setitem__(
        "stability_note", "superstable: a one-DOF trajectory that sticks is released from the same state at the "
                          "same phase"))
    add("an unknown key", lambda c: c.__setitem__("tail", {}))
    add("the period doubled", lambda c: [c.__setitem__("period", 2), c["summary"].__setitem__("period", 2)])
    add("the amplitude moved by 1e-9", lambda c: c["model"].__setitem__("amplitude", "2.000000001"))
    rejected = 0
    for name, fn in edits:
        c = copy.deepcopy(cert)
        fn(c)
        code, v = H.check_doc(c)
        expect(code in (1, 2), f"{label}: {name}: rejected (exit {code}, {v and v.get('reason', '')[:110]})")
        rejected += code in (1, 2)
    print(f"{label}: {rejected} of {len(edits)} mutations rejected")


proven = {}  # label: (summary, truth), scene A's reused by the soundness part below
cases = [("scene A", SCENE_A.format(f="2.0"), M2, K2, None, "2.0"),
         ("damped 3-DOF chain", CHAIN3, M3, K3, ["0.05", "0.05", "0.05"], "2.0")]
for label, text, Mx, Kx, zeta, famp in cases:
    name = label.replace(" ", "_")
    scene = scene_file(name + ".toml", text)
    out = os.path.join(H.tmp, name + ".json")
    code, s, err = prove(scene, out=out)
    expect(code == 0 and s and s["verdict"] == "proven" and s["kind"] == "sticking",
           f"{label}: proven (exit {code}, {s and s['reason'][:200]} {err[:200]})")
    if code != 0:
        continue
    print(f"{label}: {s['reason']}")
    if label == "scene A":
        # Closed form: held on both stops, λ_1 = (Kq)_1 − f sin ωt = 0.1 − 2 sin ωt: released at arcsin(0.05).
        expect(s["events"][0]["contact"] == 1 and inside(asin(mpf("0.05")), s["events"][0]["phase"]),
               f"scene A: the release phase of contact 1 contains arcsin(0.05) ({s['events'][0]['phase']})")
    T, psi = truth_of(Mx, Kx, zeta, famp, s)
    proven[label] = (s, T)
    compare(label, s, T, psi)
    c, v = check(out)
    expect(c == 0, f"{label}: the certificate is confirmed by the checker ({v})")
    cert = json.load(open(out))
    expect(cert["coupling"]["source"] == "structure" and cert["coupling"]["W"][0][1] == [0.0, 0.0],
           f"{label}: the contacts' coupling from the mass matrix, W_01 = 0 exactly ({cert['coupling']['W'][0][1]})")
    if label == "damped 3-DOF chain":
        mutations(label, out)

# Soundness: scene A's family in the amplitude. Going down from f = 2, the landing of mass 0 (the
# second, beside mass 1 held) comes closer to mass 1's; at f* they coincide (segment 2 lasts 0).
# The family starts from scene A at f = 2: its proof and its truth above (the same command, the same
# truth, not computed twice).
if "scene A" in proven:
    s, base = proven["scene A"]
    state = {"T": base}

    def family(fv):
        T0 = state["T"]
        T = SetTruth(M2, K2, 1, STOPS, fv, "0.5", q=1)
        T.solve(T0.segs, [x[0] for x in T0.starts], [x[1] for x in T0.starts], [x[2] for x in T0.starts])
        state["T"] = T
        return T

    def held_one(fv):
        T = family(fv)
        return T.starts[3][0] - T.starts[2][0]  # segment 2: mass 1 held, mass 0 flying to its landing
    for fv in ("1.5", "1.0", "0.7", "0.5"):
        family(mpf(fv))
    fstar = findroot(held_one, (mpf("0.5"), mpf("0.45")), solver="secant")
    print("f* =", mp.nstr(fstar, 25))
    expect(mpf("0.3") < fstar < mpf("0.5") and abs(held_one(fstar)) < mpf("1e-30"),
           f"the landings of the two masses meet at f* = {mp.nstr(fstar, 20)}")
    seq = [(e["kind"], e["contact"]) for e in s["events"]]
    for side, df in (("1e-9 above", mpf("1e-9")), ("1e-9 below", mpf("-1e-9"))):
        fv = mp.nstr(fstar + df, 20)
        out = os.path.join(H.tmp, f"a_{side.replace(' ', '_')}.json")
        code, s2, _ = prove(scene_file(f"a_{side.replace(' ', '_')}.toml", SCENE_A.format(f=fv)), out=out)
        same = code == 0 and [(e["kind"], e["contact"]) for e in s2["events"]] == seq
        if df > 0:
            expect(same, f"f = f* + 1e-9 = {fv}: the orbit with this sequence is proven ({s2 and s2['reason'][:200]})")
            if same:
                T2 = family(mpf(fv))
                expect(all(contains_phase(e["phase"], t, T2.w) for e, (_, _, t, _) in zip(s2["events"], T2.events())),
                       f"f* + 1e-9: every phase contains the truth (segment 2 lasts {mp.nstr(T2.starts[3][0] - T2.starts[2][0], 5)})")
        else:
            expect(not same, f"f = f* - 1e-9 = {fv}: no orbit with this sequence is proven "
                             f"({s2 and s2['reason'][:200]}; {s2 and [(e['kind'], e['contact']) for e in s2['events']]})")
        if code == 0:
            c, v = check(out)
            expect(c == 0, f"f* {side}: what is proven is confirmed ({v})")
else:
    expect(False, "scene A at f = 2 is proven")

# The two-sided 1-DOF oscillator with r = 0 at both stops (contacts_two_sided_1dof.toml, x'' + x = 5 sin 0.8t,
# stops at -1 and +1): held below, λ_0 = -1 - 5 sin ωt, released where sin ωt = -0.2 with λ falling
# (phase 2π - arcsin 0.2); held above, λ_1 = 5 sin ωt - 1, released where sin ωt = 0.2 falling (π - arcsin 0.2).
out = os.path.join(H.tmp, "two_sided_r0.json")
code, s, err = prove(os.path.join(SCENES, "contacts_two_sided_1dof.toml"), "--set", "contact[0].restitution=0",
                     "--set", "contact[1].restitution=0", out=out)
expect(code == 0 and s and s["kind"] == "sticking", f"two-sided 1-DOF, r = 0: proven ({s and s['reason'][:160]} {err[:200]})")
if code == 0:
    rel = {e["contact"]: e["phase"] for e in s["events"] if e["kind"] == "release"}
    expect(set(rel) == {0, 1} and inside(2 * pi - asin(mpf("0.2")), rel[0]) and inside(pi - asin(mpf("0.2")), rel[1]),
           f"two-sided 1-DOF, r = 0: the release phases contain 2π - arcsin 0.2 and π - arcsin 0.2 ({rel})")
    c, v = check(out)
    expect(c == 0, f"two-sided 1-DOF, r = 0: the certificate is confirmed ({v})")

# A chattering orbit of several contacts: refused with its precise reason.
code, s, _ = prove(os.path.join(SCENES, "contacts_chain2.toml"))
expect(code == 4 and s and "chattering (an accumulation of impacts) of a model with several contacts" in s["reason"],
       f"contacts_chain2.toml: refused naming the chattering (exit {code}, {s and s['reason'][:200]})")
# Scene A with r = 0.5 at mass 1: impacts that rebound beside a held contact.
text = SCENE_A.format(f="2.0").replace("position = 0.3\nrestitution = 0.0", "position = 0.3\nrestitution = 0.5")
code, s, _ = prove(scene_file("a_r05.toml", text))
expect(code == 4 and s and ("r > 0" in s["reason"] or "chattering" in s["reason"]),
       f"scene A with r = 0.5 at mass 1: refused with its reason (exit {code}, {s and s['reason'][:200]})")
H.finish()
