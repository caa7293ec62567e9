#!/usr/bin/env python3
"""`vibro prove` on models of several contacts (docs/prove.md, docs/contacts.md) against truths computed here.

- The symmetric period-1 orbit of the 1-DOF two-sided clearance, in closed form (docs/contacts.md,
  MODEL (T1)-(T2)): ẍ + x = a sin ωt, stops at ±Δ, restitution r; the arrival speed V solves
  (k1² + k2²)V² − 2Δk1V + Δ² − U² = 0 and the impact phase φ = atan2((Δ − k1V)/U, k2V/U). For
  (a, Δ, r, ω) = (1, 1, 0.8, 2.5) both roots: the stable orbit (complex multipliers of modulus r²) and
  the unstable one (real multipliers, product r⁴). Each is started from the closed form and proven;
  the phases at both stops, the contact of each impact, the velocities and |μ|² lie in the enclosures.
- Past the pitchfork of that orbit (a = 1.5, ω = 1.2): the asymmetric orbit that vibro finds is
  proven, its two impacts have different speeds (disjoint enclosures), and the symmetric orbit of the
  closed form at the same parameters is proven unstable, with a real multiplier above 1.
- A 2-DOF chain with a stop under each mass (2 and 3 impacts per period) and the heat-exchanger tube
  in its two-sided support (damped, physical form): against Newton at 50 digits on the shooting map
  and finite-difference multipliers (prove_truth.py).
Every certificate is re-checked by the checker; edits of the contacts are rejected.
Usage: prove_contacts_test.py VIBRO CHECKER
"""
import copy
import json
import os
import sys

from mpmath import mp, mpf, tan, sqrt, atan2, pi

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prove_truth import Harness, inside, orbit_truth, compare  # noqa: E402

mp.dps = 50
VIBRO, CHECKER = sys.argv[1:3]
H = Harness(VIBRO, CHECKER, "vibro_prove_contacts_")
TMP = H.tmp
expect, prove, check_doc, scene_file = H.expect, H.prove, H.check_doc, H.scene_file







def proven_and_true(label, scene, *args):
    path = os.path.join(TMP, label.replace(" ", "_").replace("=", "") + ".json")
    code, s, err = prove(scene, *args, out=path)
    expect(code == 0 and s and s["verdict"] == "proven", f"{label}: proven (exit {code}: {s and s['reason']} {err[-300:]})")
    if code != 0:
        return None, None
    cert = json.load(open(path))
    compare(label, s, orbit_truth(cert), expect)
    code, v = check_doc(cert)
    expect(code == 0 and v["verdict"] == "confirmed", f"{label}: the checker confirms ({v})")
    return s, cert


def contact_edits(label, cert):
    """The contacts of the certificate edited: each edit is rejected."""
    hits = cert["impact_contacts"]
    other = [1 - h if h in (0, 1) else 0 for h in hits]
    more = cert["model"]["more_contacts"][0]
    edits = [
        ("an event at another contact", lambda c: c["summary"]["events"][0].__setitem__(
            "contact", 1 - c["summary"]["events"][0]["contact"])),
        ("the impacts at the other contacts", lambda c: c.__setitem__("impact_contacts", other)),
        ("impact_contacts left out", lambda c: c.pop("impact_contacts")),
        ("a contact beyond the model's", lambda c: c["impact_contacts"].__setitem__(0, 7)),
        ("contact 1's stop moved by 1e-6", lambda c: c["model"]["more_contacts"][0].__setitem__(
            "stop", mp.nstr(mpf(more["stop"]) + mpf("1e-6"), 20))),
        ("contact 1's restitution moved by 1e-6", lambda c: c["model"]["more_contacts"][0].__setitem__(
            "restitution", mp.nstr(mpf(more["restitution"]) - mpf("1e-6"), 20))),
        ("contact 1 left out", lambda c: c["model"].pop("more_contacts")),
        ("contact 1's shape of the wrong length", lambda c: c["model"]["more_contacts"][0].__setitem__(
            "shape", more["shape"] + ["1"])),
        ("a flight's gaps of another contact", lambda c: c["flights"][0]["gaps"][1].__setitem__("contact", 0)),
        ("a flight without the pieces of contact 1", lambda c: c["flights"][0]["gaps"][1].__setitem__("pieces", [])),
    ]
    for name, edit in edits:
        c = copy.deepcopy(cert)
        edit(c)
        code, v = check_doc(c)
        expect(code in (1, 2), f"{label}: {name}: rejected (exit {code}, {v and v['reason'][:160]})")


def two_sided(a, r, w, delta=1):
    return f"""
title = "1-DOF two-sided clearance"
[structure]
mass = [[1.0]]
stiffness = [[1.0]]
forcing_dof = 0
[[contact]]
dof = 0
side = "below"
position = {-delta}
restitution = {r}
[[contact]]
dof = 0
side = "above"
position = {delta}
restitution = {r}
[excitation]
amplitude = {a}
frequency = {w}
[initial]
displacement = [0.0]
velocity = [0.0]
[run]
periods = 20
"""


def symmetric_orbits(a, r, w, delta=mpf(1)):
    """(T1)-(T2): both roots V > 0 and their impact phases φ at +Δ (ẋ⁻ = V there)."""
    theta = pi / w
    U = a / (1 - w * w)
    k1, k2 = (1 + r) * tan(theta / 2) / 2, (1 - r) / (2 * w)
    A, B, C = k1 * k1 + k2 * k2, -2 * delta * k1, delta * delta - U * U
    out = []
    for sign in (1, -1):
        V = (-B + sign * sqrt(B * B - 4 * A * C)) / (2 * A)
        if V > 0:
            out.append((V, atan2((delta - k1 * V) / U, k2 * V / U) % (2 * pi)))
    return out


def start_args(V, phi, r, w):
    """Start just after the impact at +Δ: x = Δ, ẋ = −rV at t = φ/ω (x slightly below Δ)."""
    return ["--transient", "0", "--set", f"initial.time={mp.nstr(phi / w, 17)}", "--set",
            "initial.displacement=[0.9999999]", "--set", f"initial.velocity=[{mp.nstr(-r * V, 17)}]"]


# ---- The symmetric orbit, both roots: closed form ----------------------------------------------------
a, r, w = mpf(1), mpf("0.8"), mpf("2.5")
scene = scene_file("two_sided.toml", two_sided("1.0", "0.8", "2.5"))
roots = symmetric_orbits(a, r, w)
expect(len(roots) == 2, f"(T2) has two roots V > 0 at (1, 1, 0.8, 2.5): {roots}")
for V, phi in roots:
    label = f"two-sided symmetric V={mp.nstr(V, 6)}"
    s, cert = proven_and_true(label, scene, *start_args(V, phi, r, w))
    if not s:
        continue
    up = [e for e in s["events"] if e["contact"] == 1]
    down = [e for e in s["events"] if e["contact"] == 0]
    expect(len(up) == 1 and len(down) == 1, f"{label}: one impact at each stop ({[e['contact'] for e in s['events']]})")
    if up and down:
        expect(inside(phi, up[0]["phase"]), f"{label}: (T1) phase {mp.nstr(phi, 15)} at +Δ in {up[0]['phase']}")
        expect(inside((phi + pi) % (2 * pi), down[0]["phase"]),
               f"{label}: the phase φ + π at −Δ in {down[0]['phase']}")
        for e in up + down:
            expect(inside(-V, e["velocity_before"]), f"{label}: gap velocity −V = {mp.nstr(-V, 15)} in {e['velocity_before']}")
    mus = s["multipliers"]
    prod_re = [mpf(m_["re"][0]) for m_ in mus]
    if all(m_["im"][0] > 0 or m_["im"][1] < 0 for m_ in mus):  # a complex pair: |μ|² = det = r⁴
        lo = min(mpf(m_["re"][0]) ** 2 + min(mpf(m_["im"][0]) ** 2, mpf(m_["im"][1]) ** 2) for m_ in mus)
        hi = max(max(mpf(m_["re"][0]) ** 2, mpf(m_["re"][1]) ** 2) + max(mpf(m_["im"][0]) ** 2, mpf(m_["im"][1]) ** 2)
                 for m_ in mus)
        expect(lo <= r ** 4 <= hi and s["stability"] == "stable", f"{label}: a complex pair of modulus r² (stable)")
    else:  # real: the product is r⁴
        lo = mpf(mus[0]["re"][0]) * mpf(mus[1]["re"][0])
        hi = mpf(mus[0]["re"][1]) * mpf(mus[1]["re"][1])
        expect(min(lo, hi) <= r ** 4 <= max(lo, hi) and s["stability"] == "unstable" and max(prod_re) > 1,
               f"{label}: real multipliers with product r⁴, one above 1 (unstable)")
    if cert and V == roots[0][0]:
        contact_edits(label, cert)

# ---- Past the pitchfork: the asymmetric orbit, and the symmetric one unstable -------------------------
a, w = mpf("1.5"), mpf("1.2")
scene = scene_file("two_sided_asym.toml", two_sided("1.5", "0.8", "1.2"))
s, cert = proven_and_true("two-sided asymmetric", scene, "--set", "initial.displacement=[0.5]", "--transient", "1000")
if s:
    v0, v1 = (e["velocity_before"] for e in s["events"])
    expect(len(s["events"]) == 2 and (v0[1] < v1[0] or v1[1] < v0[0]),
           f"asymmetric: the two impacts have different speeds ({v0}, {v1})")
    expect(s["stability"] == "stable", f"asymmetric: stable ({s['stability']})")
sym = symmetric_orbits(a, r, w)
expect(len(sym) == 1, f"(T2) at (1.5, 1, 0.8, 1.2): one root V > 0 ({sym})")
if sym:
    V, phi = sym[0]
    s, cert = proven_and_true("two-sided symmetric past the pitchfork", scene, *start_args(V, phi, r, w))
    if s:
        up = [e for e in s["events"] if e["contact"] == 1]
        expect(up and inside(phi, up[0]["phase"]), f"past the pitchfork: (T1) phase {mp.nstr(phi, 15)} in the proven one")
        real_above = [m_ for m_ in s["multipliers"] if m_["im"] == [0.0, 0.0] or
                      (m_["im"][0] <= 0 <= m_["im"][1] and m_["re"][0] > 1)]
        expect(s["stability"] == "unstable" and any(m_["re"][0] > 1 for m_ in real_above),
               f"past the pitchfork: the symmetric orbit is unstable with a real multiplier above 1 ({s['multipliers']})")

# ---- A 2-DOF chain with a stop under each mass ------------------------------------------------------
chain = scene_file("chain2_two_stops.toml", """
title = "2-DOF chain, a stop under each mass"
[structure]
mass = [[1.0, 0.0], [0.0, 1.0]]
stiffness = [[2.0, -1.0], [-1.0, 1.0]]
forcing_dof = 0
[[contact]]
dof = 1
side = "below"
position = -0.6
restitution = 0.5
[[contact]]
dof = 0
side = "below"
position = -0.3
restitution = 0.7
[excitation]
amplitude = 0.8
frequency = 0.8
[initial]
displacement = [0.0, 0.0]
velocity = [0.0, 0.0]
[run]
periods = 20
""")
for amp, impacts in (("0.8", 2), ("2", 3)):
    s, cert = proven_and_true(f"chain2 two stops f={amp}", chain, "--set", f"excitation.amplitude={amp}")
    if s:
        expect(len(s["events"]) == impacts and {e["contact"] for e in s["events"]} == {0, 1},
               f"chain2 two stops f={amp}: {impacts} impacts at both stops ({[e['contact'] for e in s['events']]})")
        if amp == "2":
            contact_edits("chain2 two stops", cert)

# ---- The heat-exchanger tube in its loose support (damped, two-sided, physical form) -----------------
tube = scene_file("tube.toml", """
title = "Heat-exchanger tube in a loose support"
[structure]
mass = [[2.0, 0.0], [0.0, 1.0]]
stiffness = [[4.0, -1.0], [-1.0, 1.0]]
forcing_dof = 0
damping_ratios = [0.02, 0.02]
[[contact]]
dof = 1
side = "below"
position = -0.1
restitution = 0.7
[[contact]]
dof = 1
side = "above"
position = 0.1
restitution = 0.7
[excitation]
amplitude = 0.3
frequency = 0.9
[initial]
displacement = [0.0, 0.0]
velocity = [0.0, 0.0]
[run]
periods = 200
""")
s, cert = proven_and_true("tube", tube)
if s:
    expect(s["stability"] == "stable" and [e["contact"] for e in s["events"]] in ([0, 1], [1, 0]),
           f"tube: stable, one impact at each side ({s['stability']}, {s['events']})")
    contact_edits("tube", cert)

# ---- Refused with the reason of docs/prove.md ---------------------------------------------------------
code, s, err = prove(scene_file("two_sided_chatter.toml", two_sided("5.0", "0.5", "0.8")))
expect(code == 4 and s and "several contacts" in s["reason"],
       f"two-sided chattering (sticking at both stops): not proven, with the reason (exit {code}: {s and s['reason']})")

H.finish()
