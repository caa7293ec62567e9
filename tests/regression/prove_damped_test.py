#!/usr/bin/env python3
"""`vibro prove` on damped models (docs/prove.md, docs/model.md §7) against a truth computed here.

The truth is independent of vibro and of the checker (prove_truth.py): for the model the certificate
states (its exact decimals), Newton at 50 digits on the multiple-shooting map of the orbit with the
damped modal flight written there, and the Floquet multipliers by central differences of the
stroboscopic map; the determinant against its closed form Π r² · e^{-qT Σ 2σ_i} (docs/model.md §5.6:
det of an impact's saltation matrix is r², with or without damping).

Every claim of the summary must contain the truth: the impact times and phases, the contact
velocities before the impacts, the section state, the multipliers (one-to-one); the stability
verdict must agree with the moduli. Each certificate is confirmed by the checker, and edits of the
damping (a ratio moved by 1e-6, the damping left out) are rejected. A physical scene's modal data in
the certificate are within 1e-13 of the modal data computed here at 50 digits from M and K.
Usage: prove_damped_test.py VIBRO CHECKER SCENES_DIR TEST_SCENES_DIR
"""
import copy
import json
import os
import sys

from mpmath import mp, mpf, sqrt, matrix, eigsy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prove_truth import Harness, orbit_truth, compare  # noqa: E402

mp.dps = 50
VIBRO, CHECKER, SCENES, TEST_SCENES = sys.argv[1:5]
H = Harness(VIBRO, CHECKER, "vibro_prove_damped_")
TMP = H.tmp
expect, prove, check, scene_file = H.expect, H.prove, H.check, H.scene_file







def damping_edits(label, path):
    cert = json.load(open(path))
    md = cert["model"]
    for name, edit in (("a damping ratio moved by 1e-6",
                        lambda c: c["model"]["damping"].__setitem__(0, mp.nstr(mpf(md["damping"][0]) + mpf("1e-6"), 20))),
                       ("the damping left out", lambda c: c["model"].pop("damping")),
                       ("a damping ratio of 1", lambda c: c["model"]["damping"].__setitem__(0, "1")),
                       ("a multiplier moved past its truth",
                        lambda c: c["summary"]["multipliers"][0].__setitem__(
                            "re", [c["summary"]["multipliers"][0]["re"][1] + 1e-9,
                                   c["summary"]["multipliers"][0]["re"][1] + 2e-9]))):
        c = copy.deepcopy(cert)
        edit(c)
        p = os.path.join(TMP, "edit.json")
        json.dump(c, open(p, "w"))
        code, v = check(p)
        expect(code in (1, 2), f"{label}: {name}: rejected (exit {code}, {v})")


def proven_and_true(label, scene, *args):
    path = os.path.join(TMP, label.replace(" ", "_").replace("=", "") + ".json")
    code, s, err = prove(scene, *args, out=path)
    expect(code == 0 and s and s["verdict"] == "proven",
           f"{label}: proven (exit {code}: {s and s['reason']} {err[-300:]})")
    if code != 0:
        return None, None
    cert = json.load(open(path))
    expect("damping" in cert["model"], f"{label}: the certificate's model states the damping ratios")
    compare(label, s, orbit_truth(cert), expect)
    code, v = check(path)
    expect(code == 0 and v["verdict"] == "confirmed", f"{label}: the checker confirms ({v})")
    damping_edits(label, path)
    return s, cert


# ---- 1 DOF: Fig. 5's impacting orbit with 2 % and 10 % damping --------------------------------------
for zeta in ("0.02", "0.1"):
    scene = scene_file(f"fig05_damped_{zeta}.toml", f"""
title = "Fig. 5 with damping {zeta}"
[structure]
frequencies = [1.0]
forcing = [1.0]
contact = [1.0]
damping_ratios = [{zeta}]
[stop]
position = 1.0
restitution = 0.75
[excitation]
amplitude = 1.1
frequency = 10.0
[run]
periods = 200
""")
    s, cert = proven_and_true(f"1-DOF zeta={zeta}", scene, "--kind", "impact")
    if s:
        expect(s["stability"] in ("stable", "unstable"), f"1-DOF zeta={zeta}: stability decided ({s['stability']})")

# ---- 2 DOF (physical form): the damped chain, three impacts per period -----------------------------
chain = os.path.join(SCENES, "chain2_damped.toml")
s, cert = proven_and_true("2-DOF damped chain f=3", chain, "--kind", "impact", "--set", "excitation.amplitude=3")
if cert:
    # The modal data of M = I, K = [[2, -1], [-1, 1]], contact on DOF 1, force on DOF 0, at 50 digits.
    K = matrix([[2, -1], [-1, 1]])
    lam, vec = eigsy(K)
    order = sorted(range(2), key=lambda i: lam[i])
    md = cert["model"]
    for k, i in enumerate(order):
        psi = [vec[0, i] / vec[1, i], mpf(1)]
        mi = psi[0] ** 2 + psi[1] ** 2
        for key, val in (("frequencies", sqrt(lam[i])), ("forcing", psi[0] / mi), ("contact", 1 / mi)):
            # The scene as written: the model's datum is an enclosure (docs/prove.md), at most 1e-13 wide.
            a, b = (mpf(x) for x in md[key][k][1:-1].split(","))
            expect(a <= val <= b and b - a <= mpf("1e-13") * (1 + abs(val)),
                   f"2-DOF: model.{key}[{k}] = {md[key][k]} encloses the modal datum {mp.nstr(val, 20)}, width <= 1e-13")

# ---- 3 DOF: the damped clearance chain (tests/scenes) -----------------------------------------------
proven_and_true("3-DOF damped clearance", os.path.join(TEST_SCENES, "damped3_clearance.toml"), "--kind", "impact")

# ---- A damped chattering sticking orbit: proven (the tail's bounds with damping), confirmed; against a
# 50-digit follower of its impacts in prove_chatter_damped_test.py ------------------------------------
path = os.path.join(TMP, "fig08_damped.json")
code, s, err = prove(scene_file("fig08_damped.toml", """
title = "Fig. 8 with damping"
[structure]
frequencies = [1.0]
forcing = [1.0]
contact = [1.0]
damping_ratios = [0.02]
[stop]
position = 1.0
restitution = 0.75
[excitation]
amplitude = 1.2
frequency = 1.5
[run]
periods = 200
"""), "--kind", "sticking", out=path)
expect(code == 0 and s and s["sequence"][-2:] == ["accumulation", "stick"],
       f"damped chattering: proven (exit {code}: {s and s['reason']} {err[-200:]})")
if code == 0:
    c, v = check(path)
    expect(c == 0, f"damped chattering: the certificate is confirmed ({v})")

H.finish()
