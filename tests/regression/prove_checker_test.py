#!/usr/bin/python3
"""The proof checker cannot be fooled (docs/prove.md, "What the checker checks").

Certificates of `vibro prove` for Fig. 5's two impact orbits, Fig. 4, Fig. 8 (chattering), Fig. 10
(two flights), Fig. 11 (clearance), the 2-DOF chain and a branch segment, and a certificate made
here by hand from a closed form (without vibro), are each edited systematically, and the checker
must answer every edit as its truth demands:

- an edit that makes a claim false (a bound moved past the truth, by one unit in the last place or
  by the claimed width; a period, sequence, kind, verdict, contact, stability or reason changed; a
  list emptied or extended) is rejected: exit 1 "not confirmed" or exit 2 "not a certificate";
- an edit that makes the file malformed (nan, inf, bounds swapped, a number where a list belongs,
  a list of the wrong length, deep nesting, not JSON at all) is rejected with exit 2;
- an edit that keeps every claim true (a claimed interval widened) is confirmed, exit 0;
- an edit of the proof's own data (the box, the preconditioner, a window, a piece) is rejected or
  confirmed, and never anything else: the claims it leaves were checked true independently.

The truths are independent of vibro and of the checker: the closed form of Fig. 5's period-1 orbits
and of its multipliers, and for the 1-DOF sticking orbits a follower written here (the free flight
ẍ = −x + f sin ωt in closed form, each landing bracketed and bisected at 60 digits, the plastic or
restitution law, the release where f sin ωt = x0), and for the 2-DOF chain Newton on its own
multiple-shooting map at 50 digits.

The checker runs in this process (its check_document) for speed; a sample runs through the command,
whose output must be one line, with the exit code, and never a traceback.
Usage: prove_checker_test.py VIBRO CHECKER SCENES_DIR
"""
import copy
import importlib.util
import json
import math
import os
import subprocess
import sys
import tempfile
import time

from mpmath import mp, mpf, asin, sin, cos, sqrt, atan2, pi, hypot, fmod

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prove_truth import scene_model  # noqa: E402

mp.dps = 60
VIBRO, CHECKER, SCENES = sys.argv[1], sys.argv[2], sys.argv[3]
TMP = tempfile.mkdtemp(prefix="vibro_checker_test_")
spec = importlib.util.spec_from_file_location("vibro_check_proof", CHECKER)
checker = importlib.util.module_from_spec(spec)
spec.loader.exec_module(checker)

failures, counts, samples = [], {}, {}


def fail(what):
    failures.append(what)
    print("FAIL:", what, flush=True)


def expect(cond, what):
    if not cond:
        fail(what)


# ---- Certificates from vibro --------------------------------------------------------------------

def prove(name, scene, *args):
    path = os.path.join(TMP, name + ".json")
    p = subprocess.run([VIBRO, "prove", os.path.join(SCENES, scene), "--json", "--out", path, *args],
                       capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        fail(f"{name}: vibro prove exit {p.returncode}: {p.stdout[:300]} {p.stderr[:300]}")
        return None
    with open(path) as fh:
        return json.load(fh)


# ---- Independent truths ---------------------------------------------------------------------------

def impact_orbits_1dof(w, f, r, x0):
    """Period-1 single-impact orbits of x'' + x = f sin wt, x >= x0: (phase, v+), closed form.
    The flight from an impact at phase φ with v+ returns to x0 one period later with ẋ⁻ = −v+/r iff
      P(1−c) sin φ − Pω s cos φ + s v⁺ = x0(1−c),   P s sin φ + Pω(1−c) cos φ + (c + 1/r) v⁺ = x0 s."""
    P, tau = f / (1 - w * w), 2 * pi / w
    c, sn = cos(tau), sin(tau)
    k = c + 1 / r
    alpha, beta = P * (1 - c) * k - P * sn * sn, -P * w * sn * k - P * w * (1 - c) * sn
    gamma = x0 * (1 - c) * k - x0 * sn * sn
    rho, delta = hypot(alpha, beta), atan2(beta, alpha)
    out = []
    for a in (asin(gamma / rho), pi - asin(gamma / rho)):
        phi = fmod(a - delta + 4 * pi, 2 * pi)
        vplus = (x0 * (1 - c) - P * (1 - c) * sin(phi) + P * w * sn * cos(phi)) / sn
        # Multipliers: the flight [[c, s], [−s, c]] then the saltation [[−r, 0], [(1+r) a/v⁻, −r]].
        vminus = -vplus / r
        acc = -x0 + f * sin(phi)
        S = [[-r, 0], [(1 + r) * acc / vminus, -r]]
        Phi = [[c, sn], [-sn, c]]
        M = [[sum(S[i][l] * Phi[l][j] for l in range(2)) for j in range(2)] for i in range(2)]
        tr, det = M[0][0] + M[1][1], M[0][0] * M[1][1] - M[0][1] * M[1][0]
        disc = tr * tr - 4 * det
        mults = [(tr / 2, sqrt(-disc) / 2), (tr / 2, -sqrt(-disc) / 2)] if disc < 0 else \
            [((tr + sqrt(disc)) / 2, mpf(0)), ((tr - sqrt(disc)) / 2, mpf(0))]
        out.append({"phase": phi, "time": phi / w, "vplus": vplus, "vminus": vminus, "multipliers": mults})
    return out


def follow_1dof(w, f, r, x0, impacts_wanted):
    """The 1-DOF sticking orbit through the release, followed here: the events (kind, time, velocity
    before) and the period. x'' = −x + f sin wt in flight (x > x0), the release where f sin wt = x0
    with f w cos wt > 0, landings bracketed on a grid and bisected at 60 digits."""
    T = 2 * pi / w
    P = f / (1 - w * w)
    phi = asin(x0 / f) if f > 0 else pi - asin(x0 / f)
    tr = phi / w

    def state(t0, v0, t):
        A, B = x0 - P * sin(w * t0), v0 - P * w * cos(w * t0)
        return P * sin(w * t) + A * cos(t - t0) + B * sin(t - t0) - x0, \
            P * w * cos(w * t) - A * sin(t - t0) + B * cos(t - t0)

    def land(t0, v0):
        push = x0 - f * sin(w * t0)  # the acceleration towards the stop at x0
        h = T / 400 if v0 == 0 else min(T / 400, 2 * v0 / abs(push) / 40)
        s = h
        while state(t0, v0, t0 + s)[0] > 0:
            s += h
            if s > 1000 * T:
                raise RuntimeError("no landing")
        a, b = t0 + s - h, t0 + s
        for _ in range(230):
            c = (a + b) / 2
            if state(t0, v0, c)[0] > 0:
                a = c
            else:
                b = c
        return (a + b) / 2, state(t0, v0, (a + b) / 2)[1]

    events = [("release", tr, mpf(0))]
    t, v = tr, mpf(0)
    count = 0
    while True:
        tL, vm = land(t, v)
        count += 1
        events.append(("impact", tL, vm))
        if r == 0:
            if x0 - f * sin(w * tL) > 0:  # pressed onto the stop: it sticks
                events.append(("stick", tL, vm))
                t_end = tL
                break
            events.append(("departure", tL, mpf(0)))
            t, v = tL, mpf(0)
            continue
        v = -r * vm
        t = tL
        if count >= impacts_wanted and v < mpf("1e-25"):
            push = x0 - f * sin(w * t)
            t_end = t + 2 * v / (push * (1 - r))  # the rest of the sequence: O(v²) = 1e-50
            events += [("accumulation", t_end, mpf(0)), ("stick", t_end, mpf(0))]
            break
    period = int(mp.ceil((t_end - tr) / T))
    return {"events": events, "period": period, "release": tr, "phase": phi}


def shooting_truth(cert):
    """Newton at 50 digits on the multiple-shooting map of an impacting orbit, written here in the
    standard form of the modal flight X_i = U_i(t) + a_i cos ω_i s + b_i sin ω_i s, from the
    certificate's midpoint: the true times and states after each impact, and the velocities before."""
    md = scene_model(cert)  # a physical scene: its modal data at 50 digits from its matrices
    wi = [mpf(x) for x in md["frequencies"]]
    TA, TB, c = ([mpf(x) for x in md[k]] for k in ("forcing", "contact", "shape"))
    x0, r, f, w = (mpf(md[k]) for k in ("stop", "restitution", "amplitude", "frequency"))
    zeta = [mpf(x) for x in md.get("damping", ["0"] * len(wi))]
    n, q = len(wi), cert["period"]
    per = 2 * n + 1
    m = len(cert["midpoint"]) // per
    T = 2 * pi / w
    # Every contact (c_j, T_j, e_j, r_j, W_jj), and the contact of each impact.
    contacts = [(c, TB, x0, r)] + [([mpf(x) for x in k["shape"]], [mpf(x) for x in k["contact"]], mpf(k["stop"]),
                                    mpf(k["restitution"])) for k in md.get("more_contacts", [])]
    contacts = [(cc, tt, e, rr, sum(x * y for x, y in zip(cc, tt))) for cc, tt, e, rr in contacts]
    hits = cert.get("impact_contacts", [0] * m)

    def flight(t0, X, V, t):
        """X_i = U_i(t) + e^{-σs}(a cos ω_d s + b sin ω_d s), U_i = P sin ωt + Q cos ωt (σ = 0 undamped)."""
        Xo, Vo = [], []
        for i in range(n):
            sg, wd = zeta[i] * wi[i], wi[i] * sqrt(1 - zeta[i] ** 2)
            det, dmp = wi[i] ** 2 - w ** 2, 2 * zeta[i] * wi[i] * w
            P, Q = TA[i] * f * det / (det ** 2 + dmp ** 2), -TA[i] * f * dmp / (det ** 2 + dmp ** 2)
            U, Ud = P * sin(w * t0) + Q * cos(w * t0), w * (P * cos(w * t0) - Q * sin(w * t0))
            a = X[i] - U
            b = (V[i] - Ud + sg * a) / wd
            s = t - t0
            e = mp.exp(-sg * s)
            Xo.append(P * sin(w * t) + Q * cos(w * t) + e * (a * cos(wd * s) + b * sin(wd * s)))
            Vo.append(w * (P * cos(w * t) - Q * sin(w * t)) +
                      e * ((b * wd - sg * a) * cos(wd * s) - (a * wd + sg * b) * sin(wd * s)))
        return Xo, Vo

    def unpack(u, j):
        return u[j * per], u[j * per + 1:j * per + 1 + n], u[j * per + 1 + n:(j + 1) * per]

    def F(*u):
        out = []
        for j in range(m):
            k = (j + 1) % m
            t, X, V = unpack(u, j)
            tn, Xn, Vn = unpack(u, k)
            tn = tn + (q * T if j == m - 1 else 0)
            Xe, Ve = flight(t, X, V, tn)
            cj, ck = contacts[hits[j]], contacts[hits[k]]
            p = -(1 + ck[3]) * sum(ci * v for ci, v in zip(ck[0], Ve)) / ck[4]
            out.append(sum(ci * x for ci, x in zip(cj[0], X)) - cj[2])
            out += [Xe[i] - Xn[i] for i in range(n)]
            out += [Ve[i] + p * ck[1][i] - Vn[i] for i in range(n)]
        return out

    u = mp.findroot(F, [mpf(x) for x in cert["midpoint"]], tol=mpf(10) ** -45)
    u = [u[i] for i in range(len(u))]
    events = []
    for j in range(m):
        prev = (j - 1) % m
        t, X, V = unpack(u, prev)
        tn = unpack(u, j)[0] + (q * T if prev == m - 1 else 0)
        Ve = flight(t, X, V, tn)[1]
        events.append(("impact", unpack(u, j)[0], sum(ci * v for ci, v in zip(contacts[hits[j]][0], Ve))))
    t0, X0, V0 = unpack(u, 0)
    return {"events": events, "section": (t0, X0, V0), "w": w}


# ---- The mutation machinery -----------------------------------------------------------------------

def ulp(x):
    return math.ulp(float(x)) if x != 0 else 5e-324


def run(label, doc, expected, raw=None):
    """expected: 'confirmed' (exit 0), 'rejected' (exit 1 or 2), 'malformed' (exit 2), or 'either'
    (0, 1 or 2: the proof's data edited, the claims still true)."""
    data = raw if raw is not None else json.dumps(doc).encode()
    code, line = checker.check_document(data)
    counts[expected] = counts.get(expected, 0) + 1
    ok = {"confirmed": code == 0, "rejected": code in (1, 2), "malformed": code == 2, "either": code in (0, 1, 2)}
    prefix = {0: "confirmed: ", 1: "not confirmed: ", 2: "not a certificate: "}[code] if code in (0, 1, 2) else "?"
    if not ok[expected] or "\n" in line or not line.startswith(prefix):
        fail(f"{label}: expected {expected}, got exit {code}: {line[:300]}")
    if code in (1, 2) and expected != "either":
        samples.setdefault(code, []).append(f"{label}: {line[:160]}")
    return code


def at(doc, path):
    for k in path:
        doc = doc[k]
    return doc


def setat(doc, path, value):
    at(doc, path[:-1])[path[-1]] = value


def mutate(base, path, value):
    doc = copy.deepcopy(base)
    setat(doc, path, value)
    return doc


def name(path):
    return "".join(f"[{k}]" if isinstance(k, int) else f".{k}" for k in path).lstrip(".")


def widened_within(pair, box_width):
    """Whether widening `pair` by its width (pair_edits) keeps it within box_width (docs/prove.md)."""
    w = max(pair[1] - pair[0], 4 * ulp(pair[1]))
    return "confirmed" if (pair[1] - pair[0]) + 2 * w <= box_width * (1 - 1e-15) else "rejected"


def pair_edits(label, base, path, truth=None, widen="confirmed"):
    """Edits of a claimed [lo, hi]: moved past the truth both ways by its width and more, swapped,
    nan and inf, widened; and, with the truth known, bounds placed 2 ulps past it."""
    lo, hi = at(base, path)
    w = max(hi - lo, 4 * ulp(hi))
    p = name(path)
    run(f"{label} {p} moved up past the truth", mutate(base, path, [lo + w + w, hi + w + w]), "rejected")
    run(f"{label} {p} moved down past the truth", mutate(base, path, [lo - w - w, hi - w - w]), "rejected")
    if lo < hi:
        run(f"{label} {p} swapped", mutate(base, path, [hi, lo]), "malformed")
    run(f"{label} {p} nan", None, "malformed", raw=json.dumps(mutate(base, path, [float("nan"), hi])).encode())
    run(f"{label} {p} -inf, inf", None, "malformed",
        raw=json.dumps(mutate(base, path, [float("-inf"), float("inf")])).encode())
    run(f"{label} {p} widened by its width", mutate(base, path, [lo - w, hi + w]), widen)
    if truth is not None:
        t = float(truth)
        expect(mpf(lo) <= truth <= mpf(hi), f"{label} {p}: the claim {[lo, hi]} contains the independent truth {t!r}")
        below = math.nextafter(math.nextafter(t, -math.inf), -math.inf)
        above = math.nextafter(math.nextafter(t, math.inf), math.inf)
        if mpf(below) < truth and lo <= below:
            run(f"{label} {p} hi 2 ulps below the truth", mutate(base, path, [lo, below]), "rejected")
        if mpf(above) > truth and above <= hi:
            run(f"{label} {p} lo 2 ulps above the truth", mutate(base, path, [above, hi]), "rejected")


def phase_of(t, w):
    x = w * t
    return x - 2 * pi * mp.floor(x / (2 * pi))


def summary_edits(label, base, truth, full=True):
    """The claims of the summary: the events (a sample), the section, the multipliers and the rest."""
    s = base["summary"]
    events = s["events"]
    picks = sorted(set(list(range(min(3, len(events)))) + [len(events) // 2, len(events) - 2, len(events) - 1]))
    picks = [k for k in picks if 0 <= k < len(events)]
    bw = s["box_width"]
    for k in picks if full else picks[:1]:
        kind, t, vb = truth["events"][k] if truth else (None, None, None)
        expect(truth is None or events[k]["kind"] == kind, f"{label}: event {k} is {events[k]['kind']}, truth {kind}")
        # A widened time stays within box_width, or breaks that claim.
        pair_edits(label, base, ["summary", "events", k, "time"], t, widened_within(events[k]["time"], bw))
        pair_edits(label, base, ["summary", "events", k, "phase"], phase_of(t, truth["w"]) if truth else None)
        pair_edits(label, base, ["summary", "events", k, "velocity_before"], vb)
        run(f"{label} events[{k}].contact = 1", mutate(base, ["summary", "events", k, "contact"], 1), "rejected")
        run(f"{label} events[{k}].contact = '0'", mutate(base, ["summary", "events", k, "contact"], "0"), "malformed")
        other = "stick" if events[k]["kind"] != "stick" else "impact"
        run(f"{label} events[{k}].kind = {other}", mutate(base, ["summary", "events", k, "kind"], other), "rejected")
    sec = truth.get("section") if truth else None
    pair_edits(label, base, ["summary", "section", "time"], sec[0] if sec else None,
               widened_within(s["section"]["time"], bw))
    for key, idx in (("X", 1), ("V", 2)):
        for i in range(len(s["section"][key])) if full else ():
            pair_edits(label, base, ["summary", "section", key, i], sec[idx][i] if sec else None,
                       widened_within(s["section"][key][i], bw))
    run(f"{label} section.X of the wrong length", mutate(base, ["summary", "section", "X"], s["section"]["X"] * 2),
        "malformed")
    run(f"{label} section.at changed", mutate(base, ["summary", "section", "at"], "just before impact 0"), "rejected")
    # The multipliers: each claimed interval, the list emptied, extended, reordered.
    mults = truth.get("multipliers") if truth else None
    for k in range(len(s["multipliers"])):
        for part in ("re", "im"):
            tv = None
            if mults:  # the multiplier of the truth inside this claim
                m_ = [x for x in mults if mpf(s["multipliers"][k]["re"][0]) <= x[0] <= mpf(s["multipliers"][k]["re"][1])
                      and mpf(s["multipliers"][k]["im"][0]) <= x[1] <= mpf(s["multipliers"][k]["im"][1])]
                expect(len(m_) >= 1, f"{label}: multiplier {k} contains a closed-form multiplier")
                tv = m_[0][0 if part == "re" else 1] if m_ else None
            pair_edits(label, base, ["summary", "multipliers", k, part], tv)
    if s["multipliers"]:
        run(f"{label} multipliers emptied", mutate(base, ["summary", "multipliers"], []), "rejected")
        run(f"{label} multipliers extended", mutate(base, ["summary", "multipliers"], s["multipliers"] + s["multipliers"][:1]),
            "rejected")
        run(f"{label} multipliers reversed (still true)", mutate(base, ["summary", "multipliers"], s["multipliers"][::-1]),
            "confirmed")
        flip = {"stable": "unstable", "unstable": "stable"}.get(s["stability"])
        if flip:
            run(f"{label} stability {flip}", mutate(base, ["summary", "stability"], flip), "rejected")
        run(f"{label} stability undecided (no claim)", mutate(base, ["summary", "stability"], "undecided"), "confirmed")
    else:
        run(f"{label} multipliers 0.5 claimed", mutate(base, ["summary", "multipliers"],
                                                       [{"re": [0.5, 0.5], "im": [0, 0]}] * 2), "rejected")
    run(f"{label} stability 'stable!'", mutate(base, ["summary", "stability"], "stable!"), "malformed")
    # Period, sequence, kind, verdict, reason, box width.
    q = s["period"]
    for p_ in (q + 1, 2 * q):
        d = mutate(base, ["summary", "period"], p_)
        d["period"] = p_
        if "sticking" in d:
            d["sticking"]["periods"] = p_
        run(f"{label} period {p_}", d, "rejected")
    run(f"{label} summary.period alone {q + 1}", mutate(base, ["summary", "period"], q + 1), "rejected")
    for bad in (0, -1, "1", 1.0, True, None, 2 ** 70):
        d = mutate(base, ["summary", "period"], bad)
        d["period"] = bad
        run(f"{label} period {bad!r}", d, "malformed")
    seq = s["sequence"]
    run(f"{label} sequence: one more impact", mutate(base, ["summary", "sequence"], seq + ["impact"]), "rejected")
    run(f"{label} sequence: the last dropped", mutate(base, ["summary", "sequence"], seq[:-1]), "rejected")
    run(f"{label} sequence: an entry changed", mutate(base, ["summary", "sequence", 0],
                                                     "stick" if seq[0] != "stick" else "impact"), "rejected")
    run(f"{label} events: the last dropped", mutate(base, ["summary", "events"], events[:-1]), "rejected")
    run(f"{label} events: one repeated", mutate(base, ["summary", "events"], events + events[-1:]), "rejected")
    other_kind = "sticking" if s["kind"] == "impact" else "impact"
    d = mutate(base, ["summary", "kind"], other_kind)
    d["kind"] = other_kind
    run(f"{label} kind {other_kind}", d, "rejected")
    run(f"{label} summary.kind alone", mutate(base, ["summary", "kind"], other_kind), "rejected")
    d = mutate(base, ["verdict"], "not-proven")
    d["summary"]["verdict"] = "not-proven"
    run(f"{label} verdict not-proven", d, "rejected")
    run(f"{label} verdict 'Proven'", mutate(base, ["verdict"], "Proven"), "malformed")
    reason = s["reason"]
    changed = reason.replace(f"period-{q} ", f"period-{q + 1} ")
    d = mutate(base, ["summary", "reason"], changed)
    d["reason"] = changed
    run(f"{label} reason: another period", d, "rejected")
    d = mutate(base, ["summary", "reason"], "exactly one orbit, trust me")
    d["reason"] = d["summary"]["reason"]
    run(f"{label} reason: not a statement", d, "rejected")
    run(f"{label} box_width halved", mutate(base, ["summary", "box_width"], bw / 2), "rejected")
    run(f"{label} box_width doubled (still true)", mutate(base, ["summary", "box_width"], bw * 2), "confirmed")
    run(f"{label} box_width -1", mutate(base, ["summary", "box_width"], -1.0), "malformed")
    run(f"{label} an unknown summary key", mutate(base, ["summary", "note"], "also proven: P = NP"), "malformed")


def model_edits(label, base):
    md = base["model"]
    n = len(md["frequencies"])
    run(f"{label} model.frequencies of the wrong length", mutate(base, ["model", "frequencies"], md["frequencies"] + ["2"]),
        "malformed")
    run(f"{label} model.shape of the wrong length", mutate(base, ["model", "shape"], md["shape"][:-1] or []), "malformed")
    amp = mpf(md["amplitude"]) * (1 + mpf("1e-6"))
    run(f"{label} model.amplitude moved by 1e-6", mutate(base, ["model", "amplitude"], mp.nstr(amp, 20)), "rejected")
    run(f"{label} model.stop moved by 1e-6",
        mutate(base, ["model", "stop"], mp.nstr(mpf(md["stop"]) + mpf("1e-6"), 20)), "rejected")
    for bad in ("nan", "inf", "1e999", "1,1", "", "[2, 1]", 1.1):
        run(f"{label} model.amplitude {bad!r}", mutate(base, ["model", "amplitude"], bad), "malformed")
    run(f"{label} model.frequency -1", mutate(base, ["model", "frequency"], "-1"), "malformed")
    run(f"{label} model.restitution 1.5", mutate(base, ["model", "restitution"], "1.5"), "malformed")
    run(f"{label} model.frequencies[0] a number", mutate(base, ["model", "frequencies", 0], 1.0), "malformed")
    expect(n >= 1, f"{label}: a model")


def ledger_edits(label, base, count=6):
    """The inequalities: enclosures moved past the truth, said not to hold, relations changed,
    listed twice or left out."""
    ineq = base["inequalities"]
    step = max(1, len(ineq) // count)
    for k in list(range(0, len(ineq), step))[:count]:
        e = ineq[k]
        lo, hi = e["enclosure"]
        w = max(hi - lo, 4 * ulp(hi))
        run(f"{label} inequalities[{k}] ({e['name']}) moved past the truth",
            mutate(base, ["inequalities", k, "enclosure"], [lo + 2 * w, hi + 2 * w] if e["relation"] != "< 0"
                   else [lo - 2 * w, hi - 2 * w]), "rejected")
        run(f"{label} inequalities[{k}] said not to hold", mutate(base, ["inequalities", k, "holds"], False), "rejected")
        run(f"{label} inequalities[{k}] another relation", mutate(base, ["inequalities", k, "relation"],
                                                                  "< 0" if e["relation"] != "< 0" else "> 0"), "rejected")
    run(f"{label} an inequality listed twice", mutate(base, ["inequalities"], ineq + ineq[:1]), "malformed")
    run(f"{label} an inequality left out", mutate(base, ["inequalities"], ineq[1:]), "rejected")
    run(f"{label} an inequality added", mutate(base, ["inequalities"], ineq + [dict(ineq[0], where="t_99")]), "rejected")


def proof_data_edits(label, base, paths):
    """The proof's own numbers nudged: rejected, or confirmed with the (unchanged, true) claims."""
    for path in paths:
        try:
            v = at(base, path)
        except (KeyError, IndexError):
            fail(f"{label}: no {name(path)} in the certificate")
            continue
        if isinstance(v, list) and len(v) == 2 and all(isinstance(x, float) for x in v):
            w = max(v[1] - v[0], 4 * ulp(v[1]))
            run(f"{label} {name(path)} widened", mutate(base, path, [v[0] - w, v[1] + w]), "either")
            run(f"{label} {name(path)} shifted", mutate(base, path, [v[0] + 3 * w, v[1] + 3 * w]), "either")
            run(f"{label} {name(path)} swapped", mutate(base, path, [v[1] + w, v[0]]), "malformed")
        elif isinstance(v, float):
            for factor in (0.5, 1 - 1e-9, 1 + 1e-9, 2.0):
                run(f"{label} {name(path)} x{factor}", mutate(base, path, v * factor), "either")
            run(f"{label} {name(path)} = 1e308", mutate(base, path, 1e308), "either")
            run(f"{label} {name(path)} = 'x'", mutate(base, path, "x"), "malformed")


def document_edits(label, base):
    """Whole documents that are not certificates."""
    text = json.dumps(base)
    run(f"{label} a JSON array", None, "malformed", raw=b"[1, 2, 3]")
    run(f"{label} a number", None, "malformed", raw=b"42")
    run(f"{label} null", None, "malformed", raw=b"null")
    run(f"{label} an empty file", None, "malformed", raw=b"")
    run(f"{label} cut in half", None, "malformed", raw=text[:len(text) // 2].encode())
    run(f"{label} binary garbage", None, "malformed", raw=bytes(range(256)) * 4)
    run(f"{label} nested 100000 deep", None, "malformed", raw=b"[" * 100000 + b"]" * 100000)
    run(f"{label} nested objects 50000 deep", None, "malformed", raw=b'{"a":' * 50000 + b"1" + b"}" * 50000)
    run(f"{label} a 5000-digit integer", None, "malformed", raw=b'{"format": ' + b"9" * 5000 + b"}")
    run(f"{label} a duplicate key", None, "malformed", raw=text.replace('"format"', '"format": 1, "format"', 1).encode())
    run(f"{label} NaN as a bare word", None, "malformed",
        raw=text.replace(json.dumps(base["summary"]["box_width"]), "NaN", 1).encode())
    run(f"{label} the format changed", mutate(base, ["format"], "vibro-proof-certificate/2"), "malformed")
    run(f"{label} an unknown key", mutate(base, ["comment"], "proven by hand"), "malformed")
    run(f"{label} the summary a list", mutate(base, ["summary"], [base["summary"]]), "malformed")
    run(f"{label} the summary missing", {k: v for k, v in base.items() if k != "summary"}, "malformed")
    run(f"{label} as a branch of one", {"branch": "b.h5", "certificates": [base]}, "confirmed")
    run(f"{label} as a branch of none", {"branch": "b.h5", "certificates": []}, "malformed")
    d = copy.deepcopy(base)
    d["summary"]["box_width"] = d["summary"]["box_width"] / 2
    run(f"{label} a branch with one false certificate", {"certificates": [base, d]}, "rejected")


# ---- The certificate made here by hand ------------------------------------------------------------

def hand_made():
    """Fig. 5's stable period-1 impact orbit (x'' + x = 1.1 sin 10t, x >= 1, r = 0.75) as a
    certificate written from docs/prove.md's format and the closed form alone: the box, the
    preconditioner (the inverse of the closed-form Jacobian of the shooting map), the windows and
    pieces of the flight, the monodromy and the multipliers."""
    w, f, r, x0 = mpf(10), mpf("1.1"), mpf("0.75"), mpf(1)
    orbit = [o for o in impact_orbits_1dof(w, f, r, x0) if abs(o["multipliers"][0][0]) < 1 and
             (o["multipliers"][0][0] ** 2 + o["multipliers"][0][1] ** 2) < 1][0]
    T = 2 * pi / w
    P = f / (1 - w * w)
    t0, vplus, vminus = orbit["time"], orbit["vplus"], orbit["vminus"]

    def flight(t, x, v, s):
        A, B = x - P * sin(w * t), v - P * w * cos(w * t)
        return P * sin(w * (t + s)) + A * cos(s) + B * sin(s), P * w * cos(w * (t + s)) - A * sin(s) + B * cos(s)

    def residual(u):
        t, x, v = u
        xe, ve = flight(t, x, v, T)
        return [x - x0, xe - x, -r * ve - v]

    u = [t0, x0, vplus]
    h = mpf(10) ** -25
    J = mp.matrix(3, 3)
    for l in range(3):
        up = list(u)
        up[l] += h
        dn = list(u)
        dn[l] -= h
        a, b = residual(up), residual(dn)
        for p in range(3):
            J[p, l] = (a[p] - b[p]) / (2 * h)
    C = mp.inverse(J)
    rad = [mpf("1e-11") * (1 + abs(x)) for x in u]
    box = [[float(x - d), float(x + d)] for x, d in zip(u, rad)]
    mid_ = [float(x) for x in u]

    def around(x, e=mpf("1e-12")):
        return [float(x - e * (1 + abs(x))), float(x + e * (1 + abs(x)))]

    # |x''| <= ω1² sqrt(A² + B²) + |P| ω² (the free and the forced amplitudes), 1 % above.
    A, B = x0 - P * sin(w * t0), vplus - P * w * cos(w * t0)
    M2 = float((sqrt(A * A + B * B) + abs(P) * w * w) * mpf("1.01"))
    a_low, b_low = float(vplus * (1 - mpf("1e-6"))), float(-vminus * (1 - mpf("1e-6")))
    ws, we = a_low / M2, b_low / M2
    edges = [ws + (float(T) - 0.9 * we - ws) * k / 400 for k in range(401)]
    pieces = [[edges[k], edges[k + 1]] for k in range(400)]
    c, sn = cos(T), sin(T)
    acc = -x0 + f * sin(w * t0)
    S = [[-r, 0], [(1 + r) * acc / vminus, -r]]
    Phi = [[c, sn], [-sn, c]]
    M = [[sum(S[i][l] * Phi[l][j] for l in range(2)) for j in range(2)] for i in range(2)]
    mults = orbit["multipliers"]
    start = a_low - M2 * ws / 2
    end = b_low - M2 * we / 2
    ineq = [{"name": "krawczyk", "where": nm, "enclosure": around(x, mpf("5e-12")), "relation": "inside the box",
             "holds": True} for nm, x in zip(("t_0", "X_0[0]", "V_0[0]"), u)]
    where = "flight 0 (impact 0 to impact 0)"
    ineq += [{"name": "duration", "where": where, "enclosure": around(T), "relation": "> 0", "holds": True},
             {"name": "contact velocity after impact", "where": where, "enclosure": around(vplus, mpf("1e-9")),
              "relation": "> 0", "holds": True},
             {"name": "contact velocity before impact", "where": where, "enclosure": around(vminus, mpf("1e-9")),
              "relation": "< 0", "holds": True},
             {"name": "second-derivative bound", "where": where, "enclosure": [0.0, M2], "relation": "finite",
              "holds": True},
             {"name": "start window a - M2 ws/2", "where": where, "enclosure": [start * 0.999, a_low], "relation": "> 0",
              "holds": True},
             {"name": "end window b - M2 we/2", "where": where, "enclosure": [end * 0.999, b_low], "relation": "> 0",
              "holds": True}]
    width = max(b[1] - b[0] for b in box)
    phase = phase_of(t0, w)
    summary = {
        "verdict": "proven",
        "reason": f"exactly one period-1 orbit with 1 impact(s) per period and no other contact in a box of width "
                  f"{width:.1e} around the orbit found (Krawczyk)",
        "kind": "impact", "period": 1, "sequence": ["impact"],
        "events": [{"kind": "impact", "contact": 0, "time": box[0], "phase": around(phase, mpf("1e-10")),
                    "velocity_before": around(vminus, mpf("1e-9"))}],
        "section": {"time": box[0], "X": [box[1]], "V": [box[2]], "at": "just after impact 0"},
        "multipliers": [{"re": around(a, mpf("1e-9")), "im": around(b, mpf("1e-9"))} for a, b in mults],
        "stability": "stable", "box_width": width}
    cert = {"format": "vibro-proof-certificate/1", "verdict": "proven", "reason": summary["reason"], "kind": "impact",
            "period": 1,
            "model": {"frequencies": ["1"], "forcing": ["1"], "contact": ["1"], "shape": ["1"], "stop": "1",
                      "restitution": "0.75", "amplitude": "1.1", "frequency": "10"},
            "libraries": "written by hand (tests/regression/prove_checker_test.py)", "precision_bits": 60,
            "summary": summary, "unknowns": ["t_0", "X_0[0]", "V_0[0]"], "midpoint": mid_, "box": box,
            "preconditioner": [[float(C[p, l]) for l in range(3)] for p in range(3)],
            "krawczyk": [around(x, mpf("5e-12")) for x in u],
            "flights": [{"from": 0, "duration": around(T), "velocity_after": around(vplus, mpf("1e-9")),
                         "velocity_before_next": around(vminus, mpf("1e-9")), "velocity_after_lower": a_low,
                         "speed_before_lower": b_low, "second_derivative_bound": M2, "start_window": ws,
                         "end_window": we, "pieces": pieces}],
            "monodromy": [[around(M[i][j], mpf("1e-9")) for j in range(2)] for i in range(2)],
            "inequalities": ineq}
    truth = {"events": [("impact", t0, vminus)], "section": (t0, [x0], [vplus]), "multipliers": mults, "w": w}
    return cert, truth


# ---- The runs -------------------------------------------------------------------------------------

started = time.monotonic()
timings = {}


def timed_check(label, cert):
    t = time.monotonic()
    code, line = checker.check_document(json.dumps(cert).encode())
    timings[label] = time.monotonic() - t
    expect(code == 0, f"{label}: the unedited certificate is confirmed ({line})")
    return code == 0


# The hand-made certificate: confirmed, and every edit judged against the closed form.
hand, hand_truth = hand_made()
if timed_check("hand-made Fig. 5 impact orbit", hand):
    summary_edits("hand-made", hand, hand_truth)
    ledger_edits("hand-made", hand, count=2)
    # A certificate for an orbit that is not one: the box moved 10 widths off the closed form.
    off = copy.deepcopy(hand)
    dt = 10 * (off["box"][0][1] - off["box"][0][0])
    off["box"][0] = [off["box"][0][0] + dt, off["box"][0][1] + dt]
    off["midpoint"][0] += dt
    run("hand-made: the box off the orbit", off, "rejected")
    # The same orbit claimed as a period-2 orbit with two impacts (its least period is 1).
    twice = copy.deepcopy(hand)
    run("hand-made: claimed period 2", dict(twice, period=2, summary=dict(twice["summary"], period=2)), "rejected")

w5, f5, r5 = mpf(10), mpf("1.1"), mpf("0.75")
closed5 = impact_orbits_1dof(w5, f5, r5, mpf(1))
for label, extra in (("fig05 stable", []),
                     ("fig05 unstable", ["--transient", "0", "--set", "initial.time=0.51387", "--set",
                                         "initial.displacement=[1.0]", "--set", "initial.velocity=[0.27569]"])):
    cert = prove(label.replace(" ", "_"), "fig05_coexistence.toml", "--kind", "impact", *extra)
    if cert is None or not timed_check(label, cert):
        continue
    lo_, hi_ = cert["summary"]["events"][0]["phase"]
    orbit = [o for o in closed5 if mpf(lo_) <= o["phase"] <= mpf(hi_)]
    expect(len(orbit) == 1, f"{label}: one closed-form orbit in the claimed phase {[lo_, hi_]}")
    if orbit:
        o = orbit[0]
        t_true = o["time"] + mp.floor((mpf(cert["summary"]["events"][0]["time"][0]) - o["time"]) / (2 * pi / w5) + mpf("0.5")) * 2 * pi / w5
        truth = {"events": [("impact", t_true, o["vminus"])], "section": (t_true, [mpf(1)], [o["vplus"]]),
                 "multipliers": o["multipliers"], "w": w5}
        summary_edits(label, cert, truth, full=label.endswith("stable") and "un" not in label)
        if "un" not in label:
            model_edits(label, cert)
            ledger_edits(label, cert)
            proof_data_edits(label, cert, [["box", 0], ["box", 2], ["midpoint", 1], ["preconditioner", 0, 0],
                                           ["preconditioner", 2, 1], ["krawczyk", 0], ["flights", 0, "start_window"],
                                           ["flights", 0, "velocity_after_lower"], ["flights", 0, "pieces", 3],
                                           ["flights", 0, "second_derivative_bound"], ["monodromy", 1, 0],
                                           ["flights", 0, "duration"]])
            document_edits(label, cert)

# The 1-DOF sticking orbits against the follower.
for label, scene, (w, f, r, x0), full in (("fig04", "fig04_subharmonic.toml", ("10", "6", "0", "1"), True),
                                         ("fig08", "fig08_preload.toml", ("2.8", "1.2", "0.75", "1"), None),
                                         ("fig10", "fig10_two_flights.toml", ("10", "4.8", "0", "1"), False),
                                         ("fig11", "fig11_clearance.toml", ("1.4", "10", "0", "-1"), False)):
    cert = prove(label, scene)
    if cert is None or not timed_check(label, cert):
        continue
    w, f, r, x0 = (mpf(x) for x in (w, f, r, x0))
    impacts = cert["summary"]["sequence"].count("impact")
    tr = follow_1dof(w, f, r, x0, impacts)
    truth_events = tr["events"]
    if r > 0:  # the certificate lists the impacts it followed, then the accumulation and the stick
        truth_events = truth_events[:1 + impacts] + truth_events[-2:]
    expect([e[0] for e in truth_events] == cert["summary"]["sequence"],
           f"{label}: the follower's sequence {[e[0] for e in truth_events][:6]}... is the certificate's")
    expect(tr["period"] == cert["summary"]["period"], f"{label}: the follower's period {tr['period']}")
    truth = {"events": truth_events, "section": (tr["release"], [x0], [mpf(0)]), "w": w, "multipliers": None}
    # The accumulation point (Fig. 8): moved by 1e-6 and 1e-9 (the edits), rejected.
    if r > 0:
        k = cert["summary"]["sequence"].index("accumulation")
        for shift in (1e-6, 1e-9, 1e-13):
            ph = cert["summary"]["events"][k]["phase"]
            run(f"{label} accumulation phase moved by {shift}",
                mutate(cert, ["summary", "events", k, "phase"], [ph[0] + shift, ph[1] + shift]), "rejected")
            tt = cert["tail"]["accumulation"]
            run(f"{label} tail.accumulation moved by {shift}",
                mutate(cert, ["tail", "accumulation"], [tt[0] + shift, tt[1] + shift]), "rejected")
        run(f"{label} tail.speed_upper halved", mutate(cert, ["tail", "speed_upper"], cert["tail"]["speed_upper"] / 2),
            "rejected")
        run(f"{label} tail after three flights fewer", dict(copy.deepcopy(cert), flights=cert["flights"][:-3],
                                                            tail=dict(cert["tail"], after_flight=cert["tail"]["after_flight"] - 3)),
            "rejected")
    for shift in (1e-9, 1e-12):
        ph = cert["release"]["phase"]
        run(f"{label} release phase moved by {shift}", mutate(cert, ["release", "phase"], [ph[0] + shift, ph[1] + shift]),
            "rejected")
    lb = cert["flights"][0]["landing"]
    run(f"{label} a landing set to [-1e308, 1e308]", mutate(cert, ["flights", 0, "landing"], [-1e308, 1e308]), "rejected")
    run(f"{label} a landing box set to [-1e308, 1e308]", mutate(cert, ["flights", 0, "landing_box"], [-1e308, 1e308]),
        "rejected")
    run(f"{label} a landing moved past the truth", mutate(cert, ["flights", 0, "landing"],
                                                          [lb[0] + 2 * (lb[1] - lb[0]) + 1e-15, lb[1] + 2 * (lb[1] - lb[0]) + 1e-15]),
        "rejected")
    if full is None:  # 2 s a check: the claims of the last impacts, the accumulation and the period
        ev = cert["summary"]["events"]
        for k in (1, len(ev) - 3, len(ev) - 2):
            pair_edits(label, cert, ["summary", "events", k, "time"], truth_events[k][1],
                       widened_within(ev[k]["time"], cert["summary"]["box_width"]))
            pair_edits(label, cert, ["summary", "events", k, "velocity_before"], truth_events[k][2])
        d = mutate(cert, ["summary", "period"], 2)
        d["period"] = d["sticking"]["periods"] = 2
        run(f"{label} period 2", d, "rejected")
        run(f"{label} sequence without the accumulation", mutate(cert, ["summary", "sequence"],
                                                                 [x for x in cert["summary"]["sequence"] if x != "accumulation"]),
            "rejected")
        continue
    summary_edits(label, cert, truth, full=full)
    if full:
        model_edits(label, cert)
        ledger_edits(label, cert)
        proof_data_edits(label, cert, [["release", "time"], ["flights", 0, "landing_box"], ["flights", 0, "start_window"],
                                       ["flights", 0, "pieces", 0], ["sticking", "end_window"], ["sticking", "rate_lower"],
                                       ["flights", 0, "landing_center"]])

# The 2-DOF chain: impacting orbits with four multipliers, against Newton on its shooting map.
for amp in ("3",):
    label = f"chain2 f={amp}"
    cert = prove(f"chain2_{amp}", "chain2.toml", "--kind", "impact", "--set", f"excitation.amplitude={amp}")
    if cert is None or not timed_check(label, cert):
        continue
    st = shooting_truth(cert)
    truth = {"events": st["events"], "section": st["section"], "w": st["w"], "multipliers": None}
    summary_edits(label, cert, truth, full=False)
    ledger_edits(label, cert, count=3)
    proof_data_edits(label, cert, [["box", 4], ["preconditioner", 3, 7], ["flights", 1, "end_window"]])

# Damped models (docs/model.md §7): the damped chain's impacting orbit, against Newton on its shooting
# map with the damped flight written here; edits of the damping ratios.
for amp in ("3",):
    label = f"chain2_damped f={amp}"
    cert = prove(f"chain2_damped_{amp}", "chain2_damped.toml", "--kind", "impact", "--set", f"excitation.amplitude={amp}")
    if cert is None or not timed_check(label, cert):
        continue
    st = shooting_truth(cert)
    truth = {"events": st["events"], "section": st["section"], "w": st["w"], "multipliers": None}
    summary_edits(label, cert, truth, full=False)
    ledger_edits(label, cert, count=3)
    proof_data_edits(label, cert, [["box", 2], ["preconditioner", 1, 4], ["flights", 0, "start_window"],
                                   ["flights", 2, "second_derivative_bound"], ["monodromy", 3, 1]])
    zeta = cert["model"]["damping"]
    for what, value, expected in (("a damping ratio moved by 1e-6", [mp.nstr(mpf(zeta[0]) + mpf("1e-6"), 20)] + zeta[1:],
                                   "rejected"),
                                  ("the damping ratios swapped", zeta[::-1] if zeta[0] != zeta[1] else
                                   [mp.nstr(mpf(zeta[0]) * 2, 20), zeta[1]], "rejected"),
                                  ("a damping ratio of 1", ["1"] + zeta[1:], "malformed"),
                                  ("a damping ratio of -0.1", ["-0.1"] + zeta[1:], "malformed"),
                                  ("damping of the wrong length", zeta + ["0.02"], "malformed"),
                                  ("damping a number", 0.02, "malformed")):
        run(f"{label} model.damping: {what}", mutate(cert, ["model", "damping"], value), expected)
    undamped = copy.deepcopy(cert)
    del undamped["model"]["damping"]
    run(f"{label}: the damping left out", undamped, "rejected")

# Several contacts: the damped tube in its two-sided support (docs/prove.md), against Newton on its
# shooting map; the contacts of the events and of the model edited.
tube_path = os.path.join(TMP, "tube.toml")
with open(tube_path, "w") as fh:
    fh.write("""title = "tube"
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
""")
cert = prove("tube", tube_path)
if cert is not None and timed_check("tube (two contacts, damped)", cert):
    st = shooting_truth(cert)
    truth = {"events": st["events"], "section": st["section"], "w": st["w"], "multipliers": None}
    summary_edits("tube", cert, truth, full=False)
    ledger_edits("tube", cert, count=3)
    proof_data_edits("tube", cert, [["box", 1], ["flights", 0, "gaps", 1, "pieces", 0], ["flights", 1, "end_window"],
                                    ["flights", 0, "gaps", 0, "second_derivative_bound"]])
    hits = cert["impact_contacts"]
    more = cert["model"]["more_contacts"][0]
    for what, path, value, expected in (
            ("an event at the other contact", ["summary", "events", 0, "contact"], 1 - hits[0], "rejected"),
            ("the impacts swapped between the contacts", ["impact_contacts"], hits[::-1], "rejected"),
            ("an impact at contact 2 (there is none)", ["impact_contacts", 0], 2, "malformed"),
            ("contact 1's stop moved by 1e-6", ["model", "more_contacts", 0, "stop"],
             mp.nstr(mpf(more["stop"]) + mpf("1e-6"), 20), "rejected"),
            ("contact 1's restitution moved by 1e-6", ["model", "more_contacts", 0, "restitution"],
             mp.nstr(mpf(more["restitution"]) - mpf("1e-6"), 20), "rejected"),
            ("contact 1's shape of the wrong length", ["model", "more_contacts", 0, "shape"], more["shape"][:1],
             "malformed"),
            ("contact 1 given an unknown key", ["model", "more_contacts", 0], dict(more, side="above"), "malformed"),
            ("a flight's gaps of the wrong contact", ["flights", 0, "gaps", 1, "contact"], 0, "malformed"),
            ("a flight's gaps of contact 1 emptied", ["flights", 0, "gaps", 1, "pieces"], [], "malformed")):
        run(f"tube: {what}", mutate(cert, path, value), expected)
    single = copy.deepcopy(cert)
    del single["model"]["more_contacts"]
    run("tube: the second contact left out of the model", single, "rejected")

# A branch: points and a segment whose parameter is an interval.
branch = os.path.join(TMP, "branch.h5")
p = subprocess.run([VIBRO, "continue", os.path.join(SCENES, "fig05_coexistence.toml"), "--kind", "impact", "--param",
                    "excitation.amplitude", "--to", "1.3", "--step", "0.001", "--max-points", "2", "--out", branch],
                   capture_output=True, text=True, timeout=600)
certs_path = os.path.join(TMP, "branch.json")
p = subprocess.run([VIBRO, "prove", os.path.join(SCENES, "fig05_coexistence.toml"), "--branch", branch, "--json", "--out",
                    certs_path], capture_output=True, text=True, timeout=600)
if p.returncode == 0:
    allc = json.load(open(certs_path))
    t = time.monotonic()
    code, line = checker.check_document(json.dumps(allc).encode())
    timings["branch (2 points, 1 segment)"] = time.monotonic() - t
    expect(code == 0, f"the branch's certificates are confirmed ({line})")
    seg = next(i for i, c in enumerate(allc["certificates"]) if c["model"]["amplitude"].startswith("["))
    c = allc["certificates"][seg]
    a_, b_ = c["model"]["amplitude"][1:-1].split(", ")
    wider = f"[{a_}, {mpf(b_) + 100 * (mpf(b_) - mpf(a_))}]"
    for label_, path, value, exp in (
            ("the segment 100 times longer", ["certificates", seg, "model", "amplitude"], wider, "rejected"),
            ("the segment's reason for another interval", ["certificates", seg, "summary", "reason"],
             c["summary"]["reason"].replace(a_, "1.0", 1), "rejected"),
            ("the segment's interval inverted", ["certificates", seg, "model", "amplitude"], f"[{b_}, {a_}]", "malformed"),
            ("a point's model given the segment's interval", ["certificates", 0, "model", "amplitude"],
             c["model"]["amplitude"], "rejected")):
        d = mutate(allc, path, value)
        if path[-1] == "reason":
            d["certificates"][seg]["reason"] = value
        run(f"branch: {label_}", d, exp)
    ph = c["summary"]["events"][0]["phase"]
    run("branch: the segment's phase moved past", mutate(allc, ["certificates", seg, "summary", "events", 0, "phase"],
                                                         [ph[1] + 1e-9, ph[1] + 2e-9]), "rejected")
    run("branch: the segment's phase widened", mutate(allc, ["certificates", seg, "summary", "events", 0, "phase"],
                                                      [ph[0] - 1e-9, ph[1] + 1e-9]), "confirmed")
else:
    fail(f"prove --branch: exit {p.returncode}: {p.stderr[:300]}")

# Through the command: one line, the exit code, no traceback.
cli_cases = [("confirmed", json.dumps(hand).encode(), 0), ("array", b"[]", 2), ("deep", b"[" * 200000, 2),
             ("inverted", json.dumps(mutate(hand, ["summary", "events", 0, "phase"], [2.0, 1.0])).encode(), 2),
             ("false multiplier", json.dumps(mutate(hand, ["summary", "multipliers", 0, "re"], [0.9, 0.95])).encode(), 1),
             ("not utf-8", b"\xff\xfe{", 2)]
for label, data, code in cli_cases:
    path = os.path.join(TMP, f"cli_{label}.json")
    with open(path, "wb") as fh:
        fh.write(data)
    for args in ([], ["--json"]):
        pr = subprocess.run([sys.executable, CHECKER, path, *args], capture_output=True, text=True, timeout=600)
        lines = pr.stdout.splitlines()
        expect(pr.returncode == code and len(lines) == 1 and "Traceback" not in pr.stderr + pr.stdout,
               f"the command on '{label}' {args}: exit {pr.returncode} (expected {code}), {len(lines)} line(s): "
               f"{pr.stdout[:200]} {pr.stderr[-300:]}")
        if args and lines:
            v = json.loads(lines[0])
            expect(v["verdict"] == {0: "confirmed", 1: "not confirmed", 2: "not a certificate"}[code],
                   f"--json verdict of '{label}': {v}")
for missing in (os.path.join(TMP, "no_such.json"), TMP):
    pr = subprocess.run([sys.executable, CHECKER, missing], capture_output=True, text=True, timeout=600)
    expect(pr.returncode == 2 and pr.stdout.startswith("not a certificate:") and "Traceback" not in pr.stderr,
           f"the command on {missing}: exit {pr.returncode}, {pr.stdout} {pr.stderr[-200:]}")

total = sum(counts.values())
print(f"{total} edits: " + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())))
for code in (1, 2):
    for line in samples.get(code, [])[:4]:
        print(f"  exit {code}: {line}")
for label, seconds in timings.items():
    print(f"checker on {label}: {seconds:.2f} s")
print(f"{time.monotonic() - started:.0f} s in all")
expect(total >= 200, f"at least 200 edits ({total})")
print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
