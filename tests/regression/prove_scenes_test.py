#!/usr/bin/env python3
"""Every shipped scene's orbit is proven or refused with a reason docs/prove.md lists (issue 40).

For each data/scenes/*.toml (contacts_*.toml included), `vibro prove SCENE --out CERT` must end in
one of two ways:
- exit 0, "proven", and the independent checker confirms the certificate;
- exit 4, "not-proven", with a reason that contains one of the refusals listed in docs/prove.md
  ("What is not proven") — each phrase below is looked up in that page, so a refusal the page does
  not list fails the test.
Usage: prove_scenes_test.py VIBRO CHECKER ROOT
"""
import glob
import os
import sys
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prove_truth import Harness  # noqa: E402

VIBRO, CHECKER, ROOT = sys.argv[1:4]
H = Harness(VIBRO, CHECKER, "vibro_prove_scenes_", verbose=True)
TMP, expect = H.tmp, H.expect
# The refusals of docs/prove.md, as the prover words them.
REFUSALS = (
    "sticking orbits with chattering (r > 0) of a model with more than one mode are not proven by this version",
    "sticking orbits with chattering (an accumulation of impacts) of a model with several contacts are not proven by "
    "this version",
    "impacts with r > 0 in a sticking orbit of several contacts are not proven by this version",
    "a sticking orbit held on a contact that never lands is not proven by this version",
    "the Poincaré solver found no orbit to prove",
    "an orbit through a simultaneous impact is not proven",
    "a grazing orbit cannot be proven",
    "impacting orbits with plastic impacts are not proven by this version",
    "orbits under a sum of harmonics are not proven by this version",
)
# Refused before any computation (exit 2): a compliant stop, which the prover does not enclose yet.
COMPLIANT = "this command does not handle it yet (docs/compliant.md)"



def compliant(scene):
    """Whether the scene has a compliant stop: a stiffness on [stop] or on a [[contact]]."""
    with open(scene, "rb") as f:
        t = tomllib.load(f)
    return "stiffness" in t.get("stop", {}) or any("stiffness" in c for c in t.get("contact", []))


doc = open(os.path.join(ROOT, "docs", "prove.md"), encoding="utf-8").read()
for phrase in REFUSALS:
    expect(phrase in doc, f"docs/prove.md lists the refusal '{phrase}'")
expect("this command does not handle it yet" in doc, "docs/prove.md lists the refusal of a compliant stop")

scenes = sorted(glob.glob(os.path.join(ROOT, "data", "scenes", "*.toml")))
expect(len(scenes) >= 15, f"{len(scenes)} shipped scenes")
proven = 0
for scene in scenes:
    name = os.path.basename(scene)
    cert = os.path.join(TMP, name.replace(".toml", ".json"))
    code, s, err = H.prove(scene, "--time-limit", "60", out=cert)
    s = s or {}
    if code == 0:
        ccode, v = H.check(cert)
        expect(s.get("verdict") == "proven" and ccode == 0 and v and v.get("verdict") == "confirmed",
               f"{name}: proven, and the checker confirms ({str(v)[:160]})")
        proven += 1
    elif compliant(scene):
        expect(code == 2 and "a compliant stop" in err and COMPLIANT in err and not os.path.exists(cert),
               f"{name}: a compliant stop, refused before any computation (exit {code}: {err[-200:]})")
    else:
        reason = s.get("reason", "")
        listed = [r for r in REFUSALS if r in reason]
        expect(code == 4 and s.get("verdict") == "not-proven" and listed,
               f"{name}: refused with a listed reason (exit {code}: {reason[:200]} {err[-200:]})")
print(f"{proven} of {len(scenes)} scenes proven, the others refused with a listed reason")
H.finish()
