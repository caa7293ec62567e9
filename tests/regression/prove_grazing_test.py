#!/usr/bin/env python3
"""`vibro prove --bifurcation` of grazings (docs/prove.md "Bifurcation points") against truths
computed here.

Scenes: the tube of docs/prove.md (data/scenes/tube_loose_support.toml: physical form, damped,
two contacts on DOF 1 at ±0.1), whose symmetric orbit grazes near ω = 1.3646 and 0.5694, and a
damped one-DOF oscillator with one stop (two impacts per period), which grazes near ω = 0.5355.
`vibro continue` locates each grazing and stores its branch; `prove --bifurcation BRANCH.h5`
proves it.

The truth is independent of vibro and of the checker: the modal data of the tube from its mass and
stiffness matrices at 50 digits (prove_truth.scene_model), the whole period-1 orbit (both impacts,
no symmetry assumed) written with prove_truth.Truth's flight and impact law, and mpmath's findroot
at 50 digits on the orbit together with the tangency (the gap velocity and the gap zero at a time
of the grazing flight), the forcing frequency an unknown. Its ω, its grazing time, the gap's second
derivative there and dm/dω (the minimum gap's derivative, by central differences of the minimum
found at 50 digits at ω ± 1e-20) must lie in the certificate's claims; the interval must be at most
1e-10 wide; the checker confirms. Soundness: given 1e-9 above or below the grazing (`grazing:KEY=V
--from BRANCH.h5`), nothing is proven (exit 4); mutated certificates are rejected (the interval
moved, the slope claim moved or of the wrong sign, the curvature and time claims moved, the box
shrunk, the window cut, another contact or flight, the symmetry flag flipped, the model edited).
Python's vibro.prove_bifurcation(..., branch=...) gives the command's answer.

The tube's symmetry-breaking pitchfork near ω = 0.9554 (`prove --bifurcation BRANCH.h5 --point K`
of its "branch-point"): the truth is the ω where the whole orbit's multiple-shooting Jacobian
(central differences, h = 1e-20, at 50 digits, the symmetric orbit by findroot; no block split) is
singular, and dμ/dω from that Jacobian's antisymmetric block bordered by the certificate's ℓ and k.
Usage: prove_grazing_test.py VIBRO CHECKER SCENES_DIR
"""
import copy
import json
import os
import subprocess
import sys

from mpmath import mp, mpf, pi, findroot

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prove_truth import Harness, Truth, bifurcation_reading_mutations, scene_model  # noqa: E402

mp.dps = 50
VIBRO, CHECKER, SCENES = sys.argv[1:4]
H = Harness(VIBRO, CHECKER, "vibro_prove_grazing_", verbose=os.environ.get("VERBOSE") == "1")
expect, prove, check_doc, scene_file = H.expect, H.prove, H.check_doc, H.scene_file

ONE_DOF = """title = "1-DOF, one stop, damped"
[structure]
frequencies    = [1.0]
forcing        = [1.0]
contact        = [1.0]
damping_ratios = [0.05]
[stop]
position    = -1.0
restitution = 0.8
[excitation]
amplitude = 2.0
frequency = 0.8
[initial]
displacement = [0.0]
velocity     = [0.0]
[run]
periods = 200
"""


def run(*args):
    p = subprocess.run([VIBRO, *args], capture_output=True, text=True, timeout=600)
    return p.returncode, p.stdout, p.stderr


def full_orbit(cert):
    """The whole orbit's unknowns (t_j, X_j, V_j per impact) and the impacts' contacts, from the
    certificate's midpoint (a symmetric orbit's half completed by its mirror image)."""
    b = cert["bifurcation"]
    md = dict(scene_model(cert))
    md[b["parameter"]] = mp.nstr(sum(mpf(x) for x in b["interval"]) / 2, 20)  # the unknown's start
    n = len(md["frequencies"])
    u = [mpf(x) for x in b["midpoint"][:-1]]
    hits = b["impact_contacts"]
    if b["symmetric"]:
        w = sum(mpf(x) for x in b["interval"]) / 2
        t, X, V = u[0], u[1:1 + n], u[1 + n:]
        u = u + [t + pi / w] + [-x for x in X] + [-v for v in V]
    return md, n, u, hits, mpf(b["midpoint"][-1])


def whole_orbit(m, n, hits, u):
    """The whole period-1 orbit's equations (per impact: on its contact; the flight to the next
    impact; the impact law there), with prove_truth.Truth's flight."""
    count, per, out = len(hits), 2 * n + 1, []
    for j in range(count):
        k = (j + 1) % count
        t, X, V = u[j * per], u[j * per + 1:j * per + 1 + n], u[j * per + 1 + n:(j + 1) * per]
        tn, Xn, Vn = u[k * per], u[k * per + 1:k * per + 1 + n], u[k * per + 1 + n:(k + 1) * per]
        tn = tn + (m.T if j == count - 1 else 0)
        Xe, Ve = m.state(t, X, V, tn)
        Vp = m.impact(Ve, hits[k])
        out.append(m.gap(X, hits[j]))
        out += [Xe[i] - Xn[i] for i in range(n)] + [Vp[i] - Vn[i] for i in range(n)]
    return out


def pitchfork_truth(cert):
    """The tube's pitchfork at 50 digits: the ω where the whole orbit's multiple-shooting Jacobian
    (central differences, h = 1e-20) is singular along the symmetric orbit (its half by findroot at
    50 digits for each ω, mirrored; then the secant method on the determinant); and dμ/dω, μ the bordering of the
    antisymmetric block A − Bσ' (A, B: the first flight's rows of that Jacobian in the first and the
    second impact's unknowns) with the certificate's ℓ and row k, by central differences."""
    b = cert["bifurcation"]
    md = dict(scene_model(cert))
    md[b["parameter"]] = mp.nstr(sum(mpf(x) for x in b["interval"]) / 2, 20)
    n = len(md["frequencies"])
    m = Truth(md)
    hits = b["impact_contacts"]
    per = 2 * n + 1
    a = [mpf(x) for x in b["midpoint"][:per]]
    w0 = sum(mpf(x) for x in b["interval"]) / 2
    state = {"a": a}

    def half(z):  # the symmetric orbit: on contact a, half a period later on b in −(X_0, V_0)
        t, X, V = z[0], z[1:1 + n], z[1 + n:]
        Xe, Ve = m.state(t, X, V, t + m.T / 2)
        Vp = m.impact(Ve, hits[1])
        return [m.gap(X, hits[0])] + [Xe[i] + X[i] for i in range(n)] + [Vp[i] + V[i] for i in range(n)]

    def orbit(w):  # the whole orbit, its second impact the first mirrored (its Jacobian is singular here)
        m.w, m.T = w, 2 * pi / w
        z = findroot(lambda *y: half(list(y)), state["a"], tol=mpf(10) ** -45)
        z = [z[i] for i in range(len(z))]
        state["a"] = z
        return z + [z[0] + m.T / 2] + [-x for x in z[1:]]

    def jacobian(w):
        u = orbit(w)
        h = mpf("1e-20")
        J = mp.matrix(2 * per, 2 * per)
        for c in range(2 * per):
            up, um = list(u), list(u)
            up[c] += h
            um[c] -= h
            fp, fm = whole_orbit(m, n, hits, up), whole_orbit(m, n, hits, um)
            for r in range(2 * per):
                J[r, c] = (fp[r] - fm[r]) / (2 * h)
        return J

    w = findroot(lambda w_: mp.det(jacobian(w_)), w0, tol=mpf(10) ** -40)
    ell, k = [mpf(x) for x in b["normal"]], b["row"]

    def mu(w_):
        J = jacobian(w_)
        M = mp.matrix(per + 1, per + 1)
        for r in range(per):
            for c in range(per):
                sig = 1 if c == 0 else -1
                M[r, c] = J[r, c] - J[r, per + c] * sig
        M[k, per] = 1
        for c in range(per):
            M[per, c] = ell[c]
        rhs = mp.matrix([0] * per + [1])
        return mp.lu_solve(M, rhs)[per]

    hh = mpf("1e-15")
    slope = (mu(w + hh) - mu(w - hh)) / (2 * hh)
    return w, slope


def truth_of(cert):
    """(ω*, t_grazing, γ̈ there, dm/dω) at 50 digits, from findroot on the whole orbit with its
    tangency (ω an unknown)."""
    md, n, u0, hits, s0 = full_orbit(cert)
    b = cert["bifurcation"]
    J, l = b["flight"], b["contact"]
    m = Truth(md)
    count, per = len(hits), 2 * n + 1

    def set_w(w):
        m.w, m.T = w, 2 * pi / w

    def orbit_eqs(u):
        return whole_orbit(m, n, hits, u)

    def at(u, s):
        t, X, V = u[J * per], u[J * per + 1:J * per + 1 + n], u[J * per + 1 + n:(J + 1) * per]
        return m.state(t, X, V, t + s)

    def extended(*z):
        z = list(z)
        set_w(z[-1])
        u, s = z[:-2], z[-2]
        Xs, Vs = at(u, s)
        return orbit_eqs(u) + [m.rate(Vs, l), m.gap(Xs, l)]

    w0 = sum(mpf(x) for x in b["interval"]) / 2
    z = findroot(extended, u0 + [s0, w0], tol=mpf(10) ** -45)
    z = [z[i] for i in range(len(z))]
    w, s, u = z[-1], z[-2], z[:-2]
    set_w(w)
    Xs, Vs = at(u, s)
    t, X, V = u[J * per], u[J * per + 1:J * per + 1 + n], u[J * per + 1 + n:(J + 1) * per]
    # γ̈ = c_l·Ẍ with Ẍ_i = T_A,i f sin ωt − ω_i² X_i − 2ζ_iω_i Ẋ_i.
    acc = [m.TA[i] * m.f * mp.sin(w * (t + s)) - m.wi[i] ** 2 * Xs[i] - 2 * m.zeta[i] * m.wi[i] * Vs[i]
           for i in range(n)]
    curvature = sum(c * a for c, a in zip(m.contacts[l][0], acc))

    def minimum(wv):  # the orbit at ω = wv and its gap's minimum on flight J
        def eqs(*y):
            y = list(y)
            set_w(wv)
            Xs_, Vs_ = at(y[:-1], y[-1])
            return orbit_eqs(y[:-1]) + [m.rate(Vs_, l)]
        y = findroot(eqs, u + [s], tol=mpf(10) ** -45)
        y = [y[i] for i in range(len(y))]
        set_w(wv)
        return m.gap(at(y[:-1], y[-1])[0], l)

    h = mpf("1e-20")
    slope = (minimum(w + h) - minimum(w - h)) / (2 * h)
    set_w(w)
    return w, t + s, curvature, slope


def inside(x, pair):
    return mpf(pair[0]) <= x <= mpf(pair[1])


def moved_interval(c, d):
    a, z = (mp.nstr(mpf(x) + d, 17) for x in c["bifurcation"]["interval"])
    for node in (c["bifurcation"], c["summary"]):
        node["interval"] = [a, z]
    c["model"][c["bifurcation"]["parameter"]] = f"[{a}, {z}]"


def mutants(label, cert):
    """Edits of a confirmed certificate, each of which the checker must reject."""
    b = cert["bifurcation"]
    lo, hi = (mpf(x) for x in b["interval"])
    out = []

    def edit(what, f):
        c = copy.deepcopy(cert)
        f(c)
        out.append((what, c))

    def moved(c, d):
        a, z = (mp.nstr(mpf(x) + d, 17) for x in c["bifurcation"]["interval"])
        for node in (c["bifurcation"], c["summary"]):
            node["interval"] = [a, z]
        c["model"][c["bifurcation"]["parameter"]] = f"[{a}, {z}]"

    edit("the interval moved by 1e-9", lambda c: moved(c, mpf("1e-9")))
    edit("the interval moved by -3e-10", lambda c: moved(c, mpf("-3e-10")))
    sl = b["slope"]
    edit("the slope claim moved past itself", lambda c: [c[k].__setitem__("slope", [sl[1] + abs(sl[1]), sl[1] + 2 * abs(sl[1])])
                                                         for k in ("bifurcation", "summary")])
    edit("the slope of the wrong sign", lambda c: [c[k].__setitem__("slope", [-sl[1], -sl[0]])
                                                   for k in ("bifurcation", "summary")])
    cv = b["curvature"]
    edit("the curvature claim narrowed off the truth", lambda c: [c[k].__setitem__("curvature", [cv[0], cv[0] + 1e-12 * abs(cv[0])])
                                                                  for k in ("bifurcation", "summary")])
    tg = b["grazing_time"]
    edit("the grazing time moved by 1e-6", lambda c: [c[k].__setitem__("grazing_time", [tg[0] + 1e-6, tg[1] + 1e-6])
                                                       for k in ("bifurcation", "summary")])

    def shrink(c):
        bx = c["bifurcation"]["box"][0]
        w = bx[1] - bx[0]
        bx[0] += 0.45 * w
        bx[1] -= 0.45 * w
    edit("the box shrunk", shrink)

    def cut(c):
        S = c["bifurcation"]["box"][-1]
        c["bifurcation"]["window"] = [c["bifurcation"]["window"][0], (S[0] + S[1]) / 2]
    edit("the window cut inside the tangency's time box", cut)
    other = 1 - b["contact"] if len(cert["model"].get("more_contacts", [])) else None
    if other is not None:
        edit("another contact", lambda c: [c["bifurcation"].__setitem__("contact", other),
                                           c["summary"].__setitem__("grazing_contact", other)])
    if len(b["impact_contacts"]) > 1 and not b["symmetric"]:
        edit("another flight", lambda c: [c["bifurcation"].__setitem__("flight", 1 - b["flight"]),
                                          c["summary"].__setitem__("grazing_flight", 1 - b["flight"])])
    if b["symmetric"]:
        edit("the symmetry flag flipped", lambda c: [c["bifurcation"].__setitem__("symmetric", False),
                                                     c["summary"].__setitem__("symmetric", False)])
    edit("the amplitude edited", lambda c: c["model"].__setitem__("amplitude", "0.3000001" if c["model"]["amplitude"] == "0.3"
                                                                 else "2.000001"))
    # The checker reads the whole certificate (issue 38).
    out += bifurcation_reading_mutations(cert)
    for what, c in out:
        code, v = check_doc(c)
        expect(code in (1, 2) and v and "the checker failed" not in v["reason"],
               f"{label}: {what}: rejected ({v and v['reason'][:160]})")


TRUTH = {}


def grazing(label, scene, branch, point, key="excitation.frequency"):
    out = os.path.join(H.tmp, f"{label}.json")
    code, s, err = prove(scene, "--bifurcation", branch, "--point", str(point), out=out)
    expect(code == 0 and s and s["verdict"] == "proven", f"{label}: proven (exit {code}: {s and s['reason'][:300]} {err[-300:]})")
    if code != 0:
        return
    lo, hi = (mpf(x) for x in s["interval"])
    expect(0 < hi - lo <= mpf("1e-10"), f"{label}: the interval is {mp.nstr(hi - lo, 3)} wide (≤ 1e-10)")
    code, v = H.check(out)
    expect(code == 0, f"{label}: the checker confirms ({v})")
    cert = json.load(open(out))
    w, t, curv, slope = truth_of(cert)
    TRUTH[label] = w
    print(f"{label}: ω* = {mp.nstr(w, 30)}, dm/dω = {mp.nstr(slope, 12)}, γ̈ = {mp.nstr(curv, 12)}")
    expect(lo <= w <= hi, f"{label}: the interval [{s['interval'][0]}, {s['interval'][1]}] contains the 50-digit "
                          f"grazing ω* = {mp.nstr(w, 25)}")
    expect(inside(slope, s["slope"]), f"{label}: the slope claim {s['slope']} contains dm/dω = {mp.nstr(slope, 20)}")
    expect(inside(curv, s["curvature"]), f"{label}: the curvature claim {s['curvature']} contains γ̈ = {mp.nstr(curv, 20)}")
    expect(inside(t, s["grazing_time"]), f"{label}: the time claim {s['grazing_time']} contains t = {mp.nstr(t, 20)}")
    mutants(label, cert)
    # Soundness: 1e-9 above and below the grazing, nothing is proven (the orbit from the branch).
    for d in (mpf("1e-9"), mpf("-1e-9")):
        past = os.path.join(H.tmp, f"{label}-past.json")
        code, s2, err = prove(scene, "--bifurcation", f"grazing:{key}={mp.nstr(w + d, 17)}", "--from", branch, out=past)
        expect(code == 4 and s2 and s2["verdict"] == "not-proven",
               f"{label}: {mp.nstr(d, 2)} from the grazing: nothing proven (exit {code}: {s2 and s2['reason'][:200]})")
    return s


tube = os.path.join(SCENES, "tube_loose_support.toml")
up = os.path.join(H.tmp, "tube_up.h5")
down = os.path.join(H.tmp, "tube_down.h5")
one = scene_file("one_dof.toml", ONE_DOF)
one_down = os.path.join(H.tmp, "one_down.h5")
for scene, to, out in ((tube, "1.5", up), (tube, "0.5", down), (one, "0.3", one_down)):
    code, o, err = run("continue", scene, "--param", "excitation.frequency", "--to", to, "--out", out)
    expect(code == 0 and "bifurcation  grazing" in o, f"continue {os.path.basename(scene)} to {to}: a grazing located "
                                                       f"(exit {code})")


def grazing_index(branch):
    import h5py
    with h5py.File(branch, "r") as f:
        kinds = [k.decode() if isinstance(k, bytes) else k for k in f["/bifurcations/kind"][:]]
    return kinds.index("grazing")


s_up = grazing("tube ω ≈ 1.3646", tube, up, grazing_index(up))
grazing("tube ω ≈ 0.5694", tube, down, grazing_index(down))
s_one = grazing("1-DOF ω ≈ 0.5355", one, one_down, grazing_index(one_down))
if s_up:
    expect(s_up["symmetric"] is True and "symmetric" in s_up["reason"], "tube: the symmetric orbit proven as its half")
if s_one:
    expect(s_one["symmetric"] is False and len(s_one["impact_contacts"]) == 2, "1-DOF: the whole orbit (two impacts)")

# The tube's pitchfork near ω = 0.9554 (its symmetric orbit, damped, two modes).
pf = os.path.join(H.tmp, "pitchfork.json")
kinds = []
import h5py  # noqa: E402
with h5py.File(up, "r") as fh:
    kinds = [k.decode() if isinstance(k, bytes) else k for k in fh["/bifurcations/kind"][:]]
code, s_pf, err = prove(tube, "--bifurcation", up, "--point", str(kinds.index("branch-point")), out=pf)
expect(code == 0 and s_pf and s_pf["verdict"] == "proven", f"tube pitchfork: proven (exit {code}: "
                                                             f"{s_pf and s_pf['reason'][:300]} {err[-300:]})")
if code == 0:
    code, v = H.check(pf)
    expect(code == 0, f"tube pitchfork: the checker confirms ({v})")
    cert = json.load(open(pf))
    w, slope = pitchfork_truth(cert)
    lo, hi = (mpf(x) for x in s_pf["interval"])
    print(f"tube pitchfork: ω* = {mp.nstr(w, 30)}, dμ/dω = {mp.nstr(slope, 12)}")
    expect(lo <= w <= hi and hi - lo <= mpf("1e-10"), f"tube pitchfork: [{s_pf['interval'][0]}, {s_pf['interval'][1]}] "
                                                      f"contains the 50-digit ω* = {mp.nstr(w, 25)}")
    expect(inside(slope, s_pf["slope"]), f"tube pitchfork: the slope claim {s_pf['slope']} contains dμ/dω = "
                                         f"{mp.nstr(slope, 20)}")
    for what, edit in (("the interval moved by 1e-9", lambda c: moved_interval(c, mpf("1e-9"))),
                       ("the slope of the wrong sign", lambda c: [c[k_].__setitem__("slope", [-c[k_]["slope"][1], -c[k_]["slope"][0]])
                                                                  for k_ in ("bifurcation", "summary")]),
                       ("the normal's first entry halved", lambda c: c["bifurcation"]["normal"].__setitem__(0, c["bifurcation"]["normal"][0] / 2)),
                       ("the amplitude edited", lambda c: c["model"].__setitem__("amplitude", "0.3000001"))):
        c = copy.deepcopy(cert)
        edit(c)
        code, v = check_doc(c)
        expect(code in (1, 2), f"tube pitchfork: {what}: rejected ({v and v['reason'][:160]})")
    for what, c in bifurcation_reading_mutations(cert):  # the checker reads the whole certificate (issue 38)
        code, v = check_doc(c)
        expect(code in (1, 2) and v and "the checker failed" not in v["reason"],
               f"tube pitchfork: {what}: rejected ({v and v['reason'][:160]})")
    for d in (mpf("1e-9"), mpf("-1e-9")):
        code, s2, err = prove(tube, "--bifurcation", f"branch-point:excitation.frequency={mp.nstr(w + d, 17)}", "--from", up)
        expect(code == 4 and s2 and s2["verdict"] == "not-proven",
               f"tube pitchfork: {mp.nstr(d, 2)} from it: nothing proven (exit {code}: {s2 and s2['reason'][:200]})")

# Python gives the command's answer.
if s_up:
    code = ("import vibro, json; print(json.dumps(vibro.prove_bifurcation(%r, 'grazing', 'excitation.frequency', %r, "
            "branch=%r)))" % (tube, float(s_up["located"]), up))
    env = dict(os.environ)
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, env=env)
    if p.returncode == 0:
        r = json.loads(p.stdout)
        lo, hi = (mpf(x) for x in r.get("interval", ["1", "0"]))
        expect(r["verdict"] == "proven" and lo <= TRUTH["tube ω ≈ 1.3646"] <= hi and hi - lo <= mpf("1e-10"),
               f"python: vibro.prove_bifurcation(..., branch=) proves an interval ≤ 1e-10 holding ω* "
               f"({r.get('interval')})")
    else:
        expect("No module named" in p.stderr, f"python: vibro importable or absent ({p.stderr[-300:]})")

H.finish()
