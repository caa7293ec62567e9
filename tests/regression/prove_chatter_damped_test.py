#!/usr/bin/env python3
"""`vibro prove` on chattering sticking orbits of damped one-DOF models (docs/prove.md, "One-DOF
sticking orbits with chattering") against a truth computed here at 50 digits: the release from the
closed form sin φ1 = ω1² x0/(T_A f) (R = ω1² x0 − T_A f sin ωt at rest: the damping force vanishes
there), then every flight of ẍ + 2ζω1 ẋ + ω1² x = T_A f sin ωt by mpmath's matrix exponential of the
augmented system (x, ẋ, sin ωt, cos ωt), each landing by a bracketed root, ẋ⁺ = −r ẋ⁻, until the
speed is 1e-24 of the first: the accumulation time is then known to ~1e-24 (the rest of the
sequence lasts about 2v/((1 − r) T_B R)). Nothing here reads vibro's sources.

Every claim must contain the truth: the release phase, each impact's time and speed before, the
accumulation and stick times; the certificate is confirmed by the checker; edits are rejected (the
accumulation moved past the truth, the tail's time bound lowered, the damping ratio moved, the
tail's fall-acceleration inequality dropped).
Usage: prove_chatter_damped_test.py VIBRO CHECKER
"""
import copy
import json
import os
import sys

from mpmath import mp, mpf, matrix, expm, sin, cos, asin, pi, sqrt, findroot

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prove_truth import Harness, inside  # noqa: E402

mp.dps = 50
VIBRO, CHECKER = sys.argv[1:3]
H = Harness(VIBRO, CHECKER, "vibro_prove_chatter_damped_")
expect, prove, check, scene_file = H.expect, H.prove, H.check, H.scene_file

SCENE = """title = "1-DOF preload, damped, chattering"
[structure]
frequencies    = [1.0]
forcing        = [1.0]
contact        = [1.0]
damping_ratios = [{zeta}]
[stop]
position    = 1.0
restitution = {r}
[excitation]
amplitude = {f}
frequency = {w}
[run]
periods = 200
"""


def follow(zeta, r, f, w, x0=mpf(1), w1=mpf(1)):
    zeta, r, f, w = mpf(zeta), mpf(r), mpf(f), mpf(w)
    sigma = zeta * w1
    A = matrix([[0, 1, 0, 0], [-w1 ** 2, -2 * sigma, f, 0], [0, 0, 0, w], [0, 0, -w, 0]])

    def free(t0, x, v, s):
        z = expm(A * s) * matrix([x, v, sin(w * t0), cos(w * t0)])
        return z[0], z[1]
    phi = asin(w1 ** 2 * x0 / f)
    tr = phi / w
    events = []
    # The first flight from rest: scan for the landing (g ~ s³ near the release), then a bracket.
    t, x, v = tr, x0, mpf(0)
    s, ds = mpf("0.05"), mpf("0.05")
    while free(t, x, v, s)[0] - x0 > 0:
        s += ds
    sL = findroot(lambda q: free(t, x, v, q)[0] - x0, (s - ds, s), solver="anderson")
    first = None
    while True:
        xe, ve = free(t, x, v, sL)
        tL = t + sL
        events.append((tL, ve))
        if first is None:
            first = -ve
        vp = -r * ve
        if vp < mpf("1e-24") * first:
            break
        t, x, v = tL, x0, vp
        a = f * sin(w * t) - w1 ** 2 * x0  # the free acceleration on the stop: −T_B R < 0
        est = 2 * vp / (-a)
        sL = findroot(lambda q: free(t, x, v, q)[0] - x0, (est * mpf("0.5"), est * mpf("1.5")), solver="anderson")
    R = w1 ** 2 * x0 - f * sin(w * tL)
    t_inf = tL + 2 * vp / ((1 - r) * R)  # the rest of the sequence, to O(v²) ~ 1e-48
    return tr, phi, events, t_inf


def run(label, zeta, r, f, w):
    scene = scene_file(label.replace(" ", "_") + ".toml", SCENE.format(zeta=zeta, r=r, f=f, w=w))
    out = os.path.join(H.tmp, label.replace(" ", "_") + ".json")
    code, s, err = prove(scene, "--kind", "sticking", out=out)
    expect(code == 0 and s and s["verdict"] == "proven", f"{label}: proven (exit {code}, {s and s['reason'][:160]} {err[:200]})")
    if code != 0:
        return
    tr, phi, events, t_inf = follow(zeta, r, f, w)
    ev = s["events"]
    expect(inside(phi, ev[0]["phase"]), f"{label}: the release phase contains φ1 = {mp.nstr(phi, 20)}")
    impacts = [e for e in ev if e["kind"] == "impact"]
    ok_v = all(inside(vv, e["velocity_before"]) for (_, vv), e in zip(events, impacts))
    expect(len(impacts) <= len(events), f"{label}: {len(impacts)} impacts followed, the truth has {len(events)}")
    # The event times are absolute: the release's own time fixes the shift by whole periods.
    shift = (mpf(ev[0]["time"][0]) - tr) * mpf(w) / (2 * pi)
    k = int(mp.nint(shift))
    T = 2 * pi / mpf(w)
    ok_t = all(inside(tt + k * T, e["time"]) for (tt, _), e in zip(events, impacts))
    expect(ok_t, f"{label}: every impact time contains the truth")
    expect(ok_v, f"{label}: every speed before an impact contains the truth")
    acc = [e for e in ev if e["kind"] == "accumulation"]
    expect(len(acc) == 1 and inside(t_inf + k * T, acc[0]["time"]),
           f"{label}: the accumulation time {acc and acc[0]['time']} contains the truth {mp.nstr(t_inf + k * T, 25)}")
    c, v = check(out)
    expect(c == 0, f"{label}: the certificate is confirmed by the checker ({v})")
    cert = json.load(open(out))
    edits = [
        ("the accumulation moved past the truth", lambda c: [e.__setitem__("time", [e["time"][1] + 1e-12, e["time"][1] + 2e-12])
                                                            for e in c["summary"]["events"] if e["kind"] == "accumulation"]),
        ("the tail's time bound lowered", lambda c: c["tail"].__setitem__("time_bound", c["tail"]["time_bound"] / 2)),
        ("the damping ratio moved by 1e-6", lambda c: c["model"].__setitem__("damping", [mp.nstr(mpf(zeta) + mpf("1e-6"), 15)])),
        ("the damping left out", lambda c: c["model"].pop("damping")),
        ("the fall-acceleration inequality dropped", lambda c: c.__setitem__(
            "inequalities", [q for q in c["inequalities"] if not q["name"].startswith("tail fall acceleration")])),
        ("the tail's reaction lower bound raised", lambda c: c["tail"].__setitem__("reaction_lower", c["tail"]["reaction_upper"])),
    ]
    for name, fn in edits:
        cc = copy.deepcopy(cert)
        fn(cc)
        code, v = H.check_doc(cc)
        expect(code in (1, 2), f"{label}: {name}: rejected (exit {code}, {v and v.get('reason', '')[:100]})")


run("r 0.5 omega 0.8 zeta 0.02", "0.02", "0.5", "1.2", "0.8")
run("Fig 8 with zeta 0.05", "0.05", "0.75", "1.2", "2.8")
H.finish()
