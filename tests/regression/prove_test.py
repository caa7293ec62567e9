#!/usr/bin/env python3
"""`vibro prove` and its independent checker (docs/prove.md), against truths that are not vibro's:

- the paper's 1-DOF r = 0 closed forms (eqs (32), (33), (38)) for Fig. 4's subharmonic sticking orbit:
  the release phase asin(1/f) lies in the proven enclosure, eq. (33) changes sign across the proven
  landing time, and just above f_free-flight (eq. (38)) no period-q sticking orbit is proven;
- the closed form of period-1 single-impact orbits of the undamped 1-DOF oscillator (derived below)
  for Fig. 5's two coexisting impact orbits, the stable one and the unstable one: inside the boxes,
  and the stability verdicts agree with the closed-form multipliers;
- mutations: a certificate whose numbers are altered is rejected by the checker; the same box around
  a parameter or an orbit moved by 10x the box width is not a proof.
All with mpmath at 50 digits. Usage: prove_test.py VIBRO CHECKER SCENES_DIR
"""
import copy
import json
import os
import subprocess
import sys
import tempfile

from mpmath import mp, mpf, asin, sin, cos, sqrt, atan2, pi, hypot, fmod

mp.dps = 50
VIBRO, CHECKER, SCENES = sys.argv[1], sys.argv[2], sys.argv[3]
TMP = tempfile.mkdtemp(prefix="vibro_prove_test_")
failures = []
passed = []


def expect(cond, what):
    passed.append(what)
    if not cond:
        failures.append(what)
        print("FAIL:", what)


def prove(scene, *args, out=None):
    cmd = [VIBRO, "prove", os.path.join(SCENES, scene), "--json", *args]
    if out:
        cmd += ["--out", out]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    summary = json.loads(p.stdout) if p.stdout.strip() else None
    return p.returncode, summary, p.stderr


def check(cert_path):
    p = subprocess.run([sys.executable, CHECKER, cert_path, "--json"], capture_output=True, text=True, timeout=600)
    return p.returncode, (json.loads(p.stdout) if p.stdout.strip() else None)


def checked_mutant(cert, mutate, name):
    c = copy.deepcopy(cert)
    mutate(c)
    path = os.path.join(TMP, name + ".json")
    with open(path, "w") as fh:
        json.dump(c, fh)
    code, verdict = check(path)
    expect((code, verdict["verdict"]) in ((1, "not confirmed"), (2, "not a certificate")),
           f"mutation '{name}' is rejected (exit {code}, {verdict})")


def inside(x, pair):
    return mpf(pair[0]) <= x <= mpf(pair[1])


# ---- Fig. 4: 1-DOF, r = 0, ω = 10, f = 6, x0 = 1 (the paper's non-dimensional case) ----------
cert4 = os.path.join(TMP, "fig04.json")
code, s, err = prove("fig04_subharmonic.toml", out=cert4)
expect(code == 0 and s["verdict"] == "proven", f"Fig. 4 proven (exit {code}: {s and s['reason']} {err})")
expect(s["period"] == 2 and s["sequence"] == ["release", "impact", "stick"], "Fig. 4: period 2, release-impact-stick")
w, f = mpf(10), mpf(6)
t1 = asin(1 / f) / w  # (32): sin ωt'_1 = 1/f, cos ωt'_1 > 0
rel, land = s["events"][0], s["events"][1]
expect(inside(w * t1, rel["phase"]), f"(32): release phase {w * t1} in {rel['phase']}")
expect(inside(t1, rel["time"]), f"(32): release time in {rel['time']}")


def eq33(t0):  # x_B(t'_0) of the paper's eq. (33) (ω_1 = 1), minus 1
    g = sqrt(f * f - 1)
    return (-w * w / (1 - w * w) * cos(t0 - t1) - w * g / (1 - w * w) * sin(t0 - t1)
            + f / (1 - w * w) * sin(w * t0) - 1)


lo, hi = (mpf(x) for x in land["time"])
expect(eq33(lo) > 0 > eq33(hi), f"(33) changes sign across the proven landing [{lo}, {hi}]: {eq33(lo)}, {eq33(hi)}")
expect(hi - lo <= mpf("1e-10"), "Fig. 4: landing enclosure width <= 1e-10")
expect(land["velocity_before"][1] < 0, "Fig. 4: the landing is transversal")
code, v = check(cert4)
expect(code == 0 and v["verdict"] == "confirmed", f"checker confirms Fig. 4 ({v})")

# Eq. (38): the largest amplitude of period-q sticking orbits; just above it none is proven.
q = 2
f_ff = sqrt(1 + w * w * ((1 - cos(2 * q * pi / w)) / sin(2 * q * pi / w)) ** 2)
for factor, must in ((mpf("1.000001"), False), (mpf("0.999999"), None)):
    amp = mp.nstr(f_ff * factor, 17)
    code, s2, err = prove("fig04_subharmonic.toml", "--kind", "sticking", "--period", str(q),
                          "--set", f"excitation.amplitude={amp}")
    if must is False:
        expect(code == 4 and s2["verdict"] == "not-proven" and s2["reason"],
               f"above f_free-flight = {f_ff} (f = {amp}): not proven, with a reason (exit {code})")
    else:
        expect((code == 0 and s2["period"] == q) or (code == 4 and s2["reason"]),
               f"just below f_free-flight (f = {amp}): proven with period {q} or a reason (exit {code})")

# ---- Chattering (r > 0): Fig. 8 and Fig. 5's sticking orbit -------------------------------------
# Truth: the accumulation point lies where the reaction is positive, and the release of the next
# period is eq. (32)'s phase asin(omega_1^2 x0/f) for the 1-DOF scene (omega_1 = 1, x0 = 1).
for scene, f_ in (("fig08_preload.toml", mpf("1.2")), ("fig05_coexistence.toml", mpf("1.1"))):
    path = os.path.join(TMP, scene.replace(".toml", "_chatter.json"))
    code, s, err = prove(scene, out=path)
    expect(code == 0 and s["verdict"] == "proven" and "accumulation" in s["sequence"],
           f"{scene}: the chattering sticking orbit is proven (exit {code}: {s and s['reason']})")
    if code != 0:
        continue
    expect(s["sequence"][-2:] == ["accumulation", "stick"] and s["sequence"].count("impact") >= 10,
           f"{scene}: impacts, then the accumulation point and sticking ({len(s['sequence'])} events)")
    expect(inside(asin(1 / f_), s["events"][0]["phase"]), f"{scene}: (32) release phase in {s['events'][0]['phase']}")
    acc = [e for e in s["events"] if e["kind"] == "accumulation"][0]
    expect(acc["time"][1] - acc["time"][0] <= 1e-10, f"{scene}: accumulation time enclosed within 1e-10 ({acc['time']})")
    # The exact engine's accumulation point (vibro orbit, another code path: the engine's prediction).
    p = subprocess.run([VIBRO, "orbit", os.path.join(SCENES, scene), "--json"], capture_output=True, text=True, timeout=600)
    stick = json.loads(p.stdout)["stick_phases"][0][0] % (2 * float(pi))
    expect(acc["phase"][0] - 1e-11 <= stick <= acc["phase"][1] + 1e-11,
           f"{scene}: the engine's accumulation phase {stick} in {acc['phase']}")
    speeds = [-e["velocity_before"][0] for e in s["events"] if e["kind"] == "impact"]
    expect(all(b < a for a, b in zip(speeds, speeds[1:])), f"{scene}: the landing speeds decrease")
    code, v = check(path)
    expect(code == 0 and v["verdict"] == "confirmed", f"checker confirms {scene}'s chattering orbit ({v})")
    cert = json.load(open(path))

    def faster_tail(c):  # a speed bound below the last speed after impact
        c["tail"]["speed_upper"] *= 0.5

    def stronger_reaction(c):
        c["tail"]["reaction_lower"] *= 1.5

    def drop_impacts(c):  # the tail claimed after fewer followed impacts
        c["flights"] = c["flights"][:-3]
        c["tail"]["after_flight"] -= 3

    for fn in (faster_tail, stronger_reaction, drop_impacts):
        checked_mutant(cert, fn, scene + "_" + fn.__name__)

# Near the end of Fig. 8's sticking branch, f_max = 1.289238516627 (docs/chattering.md, the quad
# engine's bisection): just above it no sticking orbit is proven; just below, a proof or a reason.
for amp, above in (("1.289239516627", True), ("1.289238616627", True), ("1.289238416627", False),
                   ("1.289228516627", False), ("1.28", False)):
    code, s2, err = prove("fig08_preload.toml", "--kind", "sticking", "--set", f"excitation.amplitude={amp}")
    if above:
        expect(code == 4 and s2["verdict"] == "not-proven" and s2["reason"],
               f"f = {amp} > f_max: no sticking orbit proven (exit {code}: {s2 and s2['reason']})")
    else:
        expect(code == 0 or (code == 4 and "fails" in s2["reason"]),
               f"f = {amp} < f_max: proven, or the bound that failed is named (exit {code}: {s2 and s2['reason']})")
        if float(amp) <= 1.289228516627:  # 1e-5 below f_max and lower: proven
            expect(code == 0 and s2["period"] == 1, f"f = {amp}, 1e-5 or more below f_max: proven (exit {code})")

# ---- Fig. 10: r = 0, a landing with R < 0 (the body departs at once), then a second flight -------
cert10 = os.path.join(TMP, "fig10.json")
code, s10, err = prove("fig10_two_flights.toml", out=cert10)
expect(code == 0 and s10["sequence"] == ["release", "impact", "departure", "impact", "stick"],
       f"Fig. 10 proven with two flights (exit {code}: {s10 and s10['reason']})")
code, v = check(cert10)
expect(code == 0 and v["verdict"] == "confirmed", f"checker confirms Fig. 10 ({v})")
if os.path.exists(cert10):
    def stick_at_departure(c):  # claim that the first landing sticks: its reaction is negative
        c["flights"] = c["flights"][:1]
    checked_mutant(json.load(open(cert10)), stick_at_departure, "fig10_stick_at_departure")

# ---- Fig. 5: r = 0.75, ω = 10, f = 1.1: period-1 single-impact orbits in closed form ----------
# ẍ + x = f sin ωt, x ≥ 1: with P = f/(1 − ω²), τ = 2π/ω, c = cos τ, s = sin τ, the flight from an impact
# at phase φ with v⁺ returns to x0 = 1 one period later with ẋ⁻ = −v⁺/r iff
#   P(1−c) sin φ − Pω s cos φ + s v⁺ = x0(1−c),   P s sin φ + Pω(1−c) cos φ + (c + 1/r) v⁺ = x0 s.
r, f5, x0 = mpf("0.75"), mpf("1.1"), mpf(1)
P, tau = f5 / (1 - w * w), 2 * pi / w
c, sn = cos(tau), sin(tau)
k = c + 1 / r
alpha, beta, gamma = P * (1 - c) * k - P * sn * sn, -P * w * sn * k - P * w * (1 - c) * sn, x0 * (1 - c) * k - x0 * sn * sn
rho, delta = hypot(alpha, beta), atan2(beta, alpha)
orbits = []
for a in (asin(gamma / rho), pi - asin(gamma / rho)):
    phi = fmod(a - delta + 4 * pi, 2 * pi)
    vplus = (x0 * (1 - c) - P * (1 - c) * sin(phi) + P * w * sn * cos(phi)) / sn
    orbits.append((phi, vplus))


def multipliers_modulus(phi, vplus):
    """|μ|² bounds of the closed-form monodromy: flight [[c, s],[−s, c]] (ω_1 = 1) then the saltation."""
    vminus = -vplus / r
    acc = -x0 + f5 * sin(phi)  # free acceleration at the impact (x = x0)
    S = [[-r, 0], [(1 + r) * acc / vminus, -r]]
    Phi = [[c, sn], [-sn, c]]
    M = [[sum(S[i][l] * Phi[l][j] for l in range(2)) for j in range(2)] for i in range(2)]
    tr, det = M[0][0] + M[1][1], M[0][0] * M[1][1] - M[0][1] * M[1][0]
    disc = tr * tr - 4 * det
    if disc < 0:
        return [det, det]
    return [((tr + sqrt(disc)) / 2) ** 2, ((tr - sqrt(disc)) / 2) ** 2]


runs = {
    "stable": [],
    "unstable": ["--transient", "0", "--set", "initial.time=0.51387", "--set", "initial.displacement=[1.0]",
                 "--set", "initial.velocity=[0.27569]"],
}
certs = {}
for label, extra in runs.items():
    path = os.path.join(TMP, f"fig05_{label}.json")
    code, s, err = prove("fig05_coexistence.toml", "--kind", "impact", *extra, out=path)
    expect(code == 0 and s["verdict"] == "proven", f"Fig. 5 {label} impact orbit proven (exit {code}: {s and s['reason']})")
    if code != 0:
        continue
    certs[label] = path
    ev = s["events"][0]
    match = [o for o in orbits if inside(o[0], ev["phase"])]
    expect(len(match) == 1, f"Fig. 5 {label}: a closed-form impact phase in {ev['phase']} ({[float(o[0]) for o in orbits]})")
    if match:
        phi, vplus = match[0]
        expect(inside(vplus, s["section"]["V"][0]), f"Fig. 5 {label}: closed-form v+ {vplus} in {s['section']['V'][0]}")
        expect(inside(-vplus / r, ev["velocity_before"]), f"Fig. 5 {label}: closed-form v- in {ev['velocity_before']}")
        mods = multipliers_modulus(phi, vplus)
        truth = "stable" if max(mods) < 1 else "unstable" if max(mods) > 1 else "?"
        expect(s["stability"] == truth == label, f"Fig. 5 {label}: stability {s['stability']}, closed form {truth}")
    expect(s["box_width"] <= 1e-10, f"Fig. 5 {label}: box width {s['box_width']} <= 1e-10")
    for key in ("phase", "velocity_before"):
        expect(ev[key][1] - ev[key][0] <= 1e-10, f"Fig. 5 {label}: {key} enclosure width <= 1e-10")
    code, v = check(path)
    expect(code == 0 and v["verdict"] == "confirmed", f"checker confirms Fig. 5 {label} ({v})")

# ---- The 2-DOF chain (physical scene, modes from M and K): impacting orbits, 4 x 4 monodromy ----
for amp, expected_impacts in (("3", 3), ("5", 6)):
    path = os.path.join(TMP, f"chain2_{amp}.json")
    code, s, err = prove("chain2.toml", "--kind", "impact", "--set", f"excitation.amplitude={amp}", out=path)
    expect(code == 0 and s["verdict"] == "proven", f"chain2 f = {amp}: proven (exit {code}: {s and s['reason']})")
    if code == 0:
        expect(len(s["sequence"]) == expected_impacts, f"chain2 f = {amp}: {expected_impacts} impacts ({s['sequence']})")
        expect(s["box_width"] <= 1e-10, f"chain2 f = {amp}: box width {s['box_width']} <= 1e-10")
        expect(len(s["multipliers"]) == 4 and s["stability"] in ("stable", "unstable"),
               f"chain2 f = {amp}: four multipliers, stability decided ({s['stability']})")
        code, v = check(path)
        expect(code == 0 and v["verdict"] == "confirmed", f"checker confirms chain2 f = {amp} ({v})")
        flip = "unstable" if s["stability"] == "stable" else "stable"
        checked_mutant(json.load(open(path)), lambda c: c["summary"].__setitem__("stability", flip), f"chain2_{amp}_{flip}")

# ---- Mutations: the checker rejects altered numbers; a moved orbit is not proven in the box -----
if "stable" in certs:
    cert = json.load(open(certs["stable"]))
    width = max(b[1] - b[0] for b in cert["box"])

    def move_parameter(c):
        c["model"]["amplitude"] = repr(1.1 + 10 * width)

    def move_orbit(c):  # midpoint and box together, 10 box widths along the first unknown
        c["midpoint"][0] += 10 * width
        c["box"][0] = [c["box"][0][0] + 10 * width, c["box"][0][1] + 10 * width]

    def alter_enclosure(c):
        e = next(e for e in c["inequalities"] if e["name"] == "contact velocity before impact")
        e["enclosure"] = [e["enclosure"][0] * 1.01, e["enclosure"][1] * 1.01]

    def hole_in_pieces(c):
        p = c["flights"][0]["pieces"]
        p[1][0] = p[1][0] + (p[1][1] - p[1][0]) / 2

    def alter_monodromy(c):
        c["monodromy"][0][1] = [c["monodromy"][0][1][0] + 1e-6, c["monodromy"][0][1][1] + 1e-6]

    def widen_window(c):
        c["flights"][0]["start_window"] *= 3

    def claim_unstable(c):
        c["summary"]["stability"] = "unstable"

    def drop_inequality(c):
        c["inequalities"].append(dict(c["inequalities"][0], where="t_9"))

    for fn in (move_parameter, move_orbit, alter_enclosure, hole_in_pieces, alter_monodromy, widen_window,
               claim_unstable, drop_inequality):
        checked_mutant(cert, fn, fn.__name__)
if os.path.exists(cert4):
    cert = json.load(open(cert4))

    def move_release(c):
        c["release"]["phase"] = [c["release"]["phase"][0] + 1e-9, c["release"]["phase"][1] + 1e-9]

    def move_landing(c):
        lo_, hi_ = c["flights"][0]["landing_box"]
        c["flights"][0]["landing_box"] = [lo_ + 10 * (hi_ - lo_), hi_ + 10 * (hi_ - lo_)]
        c["flights"][0]["landing_center"] += 10 * (hi_ - lo_)

    def wrong_period(c):
        c["period"] = 3
        c["sticking"]["periods"] = 3

    def change_restitution(c):
        c["model"]["restitution"] = "0.5"

    for fn in (move_release, move_landing, wrong_period, change_restitution):
        checked_mutant(cert, fn, fn.__name__)

# ---- Along a branch: every stored point of `vibro continue` proven from its own state --------
branch = os.path.join(TMP, "branch.h5")
p = subprocess.run([VIBRO, "continue", os.path.join(SCENES, "fig05_coexistence.toml"), "--kind", "impact",
                    "--param", "excitation.amplitude", "--to", "1.3", "--step", "0.05", "--max-points", "4",
                    "--out", branch], capture_output=True, text=True, timeout=600)
expect(p.returncode == 0, f"a branch to prove ({p.stderr})")
certs_path = os.path.join(TMP, "branch.json")
p = subprocess.run([VIBRO, "prove", os.path.join(SCENES, "fig05_coexistence.toml"), "--branch", branch, "--json",
                    "--out", certs_path], capture_output=True, text=True, timeout=600)
b = json.loads(p.stdout) if p.stdout.strip() else {}
expect(p.returncode == 0 and b.get("proven") == b.get("total") == 4,
       f"--branch: every point proven (exit {p.returncode}, {b.get('proven')} of {b.get('total')})")
values = [pt["value"] for pt in b.get("points", [])]
expect(len(set(values)) == len(values) == 4, f"--branch: four distinct parameter values {values}")
code, v = check(certs_path)
expect(code == 0 and "certificates" in v["reason"], f"the checker confirms every certificate of the branch ({v})")
# Steps of 0.05: the segments are proven in halved pieces that cover them.
for seg in b.get("segments", []):
    expect(seg["proven"], f"segment [{seg['from']}, {seg['to']}] proven in {len(seg['pieces'])} piece(s)")
    bounds = []
    for piece in seg["pieces"]:
        text = piece["reason"].split("for every amplitude in ")[1].split("]")[0] + "]"
        bounds.append([mpf(x) for x in text[1:-1].split(",")])
    bounds.sort()
    lo_, hi_ = sorted((mpf(repr(seg["from"])), mpf(repr(seg["to"]))))
    covered = bounds and bounds[0][0] <= lo_ and bounds[-1][1] >= hi_ and all(
        bounds[i][1] == bounds[i + 1][0] for i in range(len(bounds) - 1))
    expect(covered, f"the pieces of [{seg['from']}, {seg['to']}] cover it without a hole")
if code == 0:
    allc = json.load(open(certs_path))
    def second_point_amplitude(c):  # point 1's proof claimed at the last point's amplitude
        points = [i for i, x in enumerate(c["certificates"]) if not x["model"]["amplitude"].startswith("[")]
        c["certificates"][points[1]]["model"]["amplitude"] = c["certificates"][points[-1]]["model"]["amplitude"]
    checked_mutant(allc, second_point_amplitude, "branch_swapped_parameter")

# Validated continuation: with small steps, every parameter value between neighbouring points is
# proven (the parameter as an interval in Krawczyk's test); the checker reads the intervals.
branch = os.path.join(TMP, "branch_fine.h5")
p = subprocess.run([VIBRO, "continue", os.path.join(SCENES, "fig05_coexistence.toml"), "--kind", "impact",
                    "--param", "excitation.amplitude", "--to", "1.3", "--step", "0.001", "--max-points", "4",
                    "--out", branch], capture_output=True, text=True, timeout=600)
certs_path = os.path.join(TMP, "branch_fine.json")
p = subprocess.run([VIBRO, "prove", os.path.join(SCENES, "fig05_coexistence.toml"), "--branch", branch, "--json",
                    "--out", certs_path], capture_output=True, text=True, timeout=600)
b = json.loads(p.stdout) if p.stdout.strip() else {}
expect(p.returncode == 0 and b.get("segments_proven") == 3 and len(b.get("segments", [])) == 3,
       f"--branch, steps of 1e-3: the 3 segments between the points proven ({b.get('segments_proven')})")
for seg in b.get("segments", []):
    expect(len(seg["pieces"]) == 1 and "for every amplitude in [" in seg["pieces"][0]["reason"],
           f"a short segment is proven whole, its theorem names its interval ({seg['pieces'][0]['reason'][:80]})")
code, v = check(certs_path)
expect(code == 0 and "7 certificates" in v["reason"], f"the checker confirms points and segments ({v})")
if code == 0:
    allc = json.load(open(certs_path))
    seg_index = next(i for i, c in enumerate(allc["certificates"]) if c["model"]["amplitude"].startswith("["))

    def wider_segment(c):  # the same box claimed for a parameter interval 100 times longer
        a, b_ = (float(x) for x in c["certificates"][seg_index]["model"]["amplitude"][1:-1].split(","))
        c["certificates"][seg_index]["model"]["amplitude"] = f"[{a!r}, {a + 100 * (b_ - a)!r}]"
    checked_mutant(allc, wider_segment, "branch_wider_segment")

# ---- --from ORBIT.h5: the orbit stored by `vibro orbit --out` ----------------------------------
orbit_file = os.path.join(TMP, "orbit.h5")
p = subprocess.run([VIBRO, "orbit", os.path.join(SCENES, "fig05_coexistence.toml"), "--kind", "impact", "--out", orbit_file],
                   capture_output=True, text=True, timeout=600)
code, s, err = prove("fig05_coexistence.toml", "--kind", "impact", "--from", orbit_file)
expect(p.returncode == 0 and code == 0 and s["stability"] == "stable", f"--from ORBIT.h5: proven (exit {code}: {err})")
code, s, err = prove("fig05_coexistence.toml", "--from", branch)
expect(code == 2 and "/orbit" in err, f"--from a file without /orbit: bad input (exit {code}: {err})")

# ---- Never hangs: the time limit ends a proof with the reason -------------------------------
code, s, err = prove("chain2.toml", "--kind", "impact", "--set", "excitation.amplitude=5", "--time-limit", "0.001")
expect(code == 4 and "time limit" in (s or {}).get("reason", ""), f"--time-limit: exit 4, reason given (exit {code}: {s and s['reason']})")

# ---- Not proven, and bad input --------------------------------------------------------------
path = os.path.join(TMP, "chain2.json")
code, s, err = prove("chain2.toml", out=path)
expect(code == 4 and s["verdict"] == "not-proven" and "chattering (r > 0) of a model with more than one mode" in s["reason"],
       f"a chattering sticking orbit of 2 modes: exit 4 with the reason (exit {code}, {s and s['reason']})")
code, v = check(path)
expect(code == 1 and v["verdict"] == "not confirmed", "the checker rejects a not-proven certificate")
path = os.path.join(TMP, "damped.json")
code, s, err = prove("chain2_damped.toml", out=path)
expect(code == 4 and s["verdict"] == "not-proven" and "more than one mode" in s["reason"] and os.path.exists(path),
       f"a damped 2-DOF chattering sticking orbit: exit 4 with the reason, a certificate saying so (exit {code}: {err})")
code, s, err = prove("fig04_subharmonic.toml", out=os.path.join(TMP, "missing_dir", "c.json"))
expect(code == 2 and "no directory" in err, f"--out into a missing directory: bad input before any work (exit {code})")
code, s, err = prove("no_such_scene.toml")
expect(code == 2, f"a missing scene is bad input (exit {code})")

# ---- Bounded and interruptible (issue 38): a stop request is no verdict; every limit holds -------
import resource  # noqa: E402
import signal  # noqa: E402
import time  # noqa: E402


def cpu_seconds(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


fig5 = os.path.join(SCENES, "fig05_coexistence.toml")
for sig in (signal.SIGINT, signal.SIGTERM):
    # Signalled once it says it is ready and has computed for half a second (inside the transient).
    child = subprocess.Popen([VIBRO, "prove", fig5, "--transient", "10000000", "--out", os.path.join(TMP, "stopped.json")],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             env=dict(os.environ, VIBRO_SIGNAL_READY="1"))
    ready = child.stderr.readline()
    start = cpu_seconds(child.pid)
    limit = time.monotonic() + 300
    while cpu_seconds(child.pid) < start + 0.5 and child.poll() is None and time.monotonic() < limit:
        time.sleep(0.02)
    still_running = child.poll() is None
    sent = time.monotonic()
    child.send_signal(sig)
    try:
        out, err = child.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        child.kill()
        out, err = child.communicate()
    elapsed = time.monotonic() - sent
    expect("ready" in ready and still_running, f"{sig.name}: prove was inside its transient when signalled ({ready})")
    expect(child.returncode == 130 and "verdict" not in out and "interrupted" in err
           and not os.path.exists(os.path.join(TMP, "stopped.json")),
           f"{sig.name} during the transient: exit 130, no verdict, nothing written (exit {child.returncode}, "
           f"{elapsed:.2f} s: {out[:200]} {err[-200:]})")

# --time-limit covers the transient and the orbit search (it ran past 120 s before).
try:
    p = subprocess.run([VIBRO, "prove", fig5, "--transient", "10000000", "--time-limit", "2", "--json"],
                       capture_output=True, text=True, timeout=120)
    s = json.loads(p.stdout) if p.stdout.strip() else {}
    expect(p.returncode == 4 and "time limit of 2 s" in s.get("reason", "") and "orbit search" in s["reason"],
           f"--time-limit 2 ends the transient: exit 4 with the reason (exit {p.returncode}: {s.get('reason')})")
except subprocess.TimeoutExpired:
    expect(False, "--time-limit 2 with --transient 10000000 was still running after 120 s")
try:
    p = subprocess.run([VIBRO, "prove", os.path.join(SCENES, "fig04_subharmonic.toml"), "--json", "--time-limit", "0.001",
                        "--kind", "impact", "--transient", "1000000"], capture_output=True, text=True, timeout=120)
    s = json.loads(p.stdout) if p.stdout.strip() else {}
    expect(p.returncode == 4 and "time limit" in s.get("reason", ""), f"--time-limit 0.001 over a search: exit 4 ({s})")
except subprocess.TimeoutExpired:
    expect(False, "--time-limit 0.001 over a search of 10^6 periods was still running after 120 s")

# Bounded memory for any --period: Fig. 5 with --period 4096 under a 2 GiB address-space limit
# (it ended with bad_alloc, exit 1, at 8 GB); the orbit found has least period 1: it is proven at
# period 1, and the result says that 1 divides the period asked for (issue 40).


def limit_memory():
    resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))


for period in ("4096", "2"):
    path = os.path.join(TMP, f"fig05_period{period}.json")
    p = subprocess.run([VIBRO, "prove", fig5, "--period", period, "--kind", "impact", "--json", "--out", path],
                       capture_output=True, text=True, timeout=600, preexec_fn=limit_memory)
    s = json.loads(p.stdout) if p.stdout.strip() else {}
    expect(p.returncode == 0 and s.get("period") == 1 and s.get("requested_period") == int(period) and
           f"its least period 1 divides the requested period {period}" in s.get("reason", ""),
           f"--period {period} on Fig. 5 (a period-1 orbit): proven with its least period 1 stated, under 2 GiB "
           f"(exit {p.returncode}: {s.get('reason')} {p.stderr[-200:]})")
    code, v = check(path)
    expect(code == 0, f"--period {period}: the checker confirms the least period and the statement ({v})")
    if code == 0:
        cert = json.load(open(path))
        checked_mutant(cert, lambda c: c["summary"].__setitem__("requested_period", 3), f"period{period}_requested_3")
        checked_mutant(cert, lambda c: c["summary"].pop("requested_period"), f"period{period}_no_requested")
        checked_mutant(cert, lambda c: (c.__setitem__("period", 2), c["summary"].__setitem__("period", 2)),
                       f"period{period}_claimed_2")
code, s, err = prove("fig04_subharmonic.toml", "--period", "4")
expect(code == 0 and s["period"] == 2 and s.get("requested_period") == 4,
       f"Fig. 4 --period 4: its period-2 sticking orbit proven, least period 2 stated (exit {code}: {s and s['reason']})")
code, s, err = prove("fig04_subharmonic.toml", "--period", "3")
expect(code == 4 and "does not divide 3" in s["reason"], f"Fig. 4 --period 3: not proven ({s and s['reason']})")

# The messages give the true reason (issue 37 item 12): an undamped r = 0 2-DOF orbit whose plastic
# impacts leave the stop at once was "the orbit found has no impact".
code, s, err = prove("chain2.toml", "--set", "stop.restitution=0", "--set", "excitation.amplitude=1", "--set",
                     "excitation.frequency=1.2", "--set", "stop.position=-0.5")
expect(code == 4 and "no impact" not in s["reason"] and "plastic impact" in s["reason"] and "r = 0" in s["reason"],
       f"r = 0, 2 DOF, plastic impacts with departures: the reason says so ({s and s['reason']})")

# The text is what the checker checks: every printed interval contains the JSON's (rounded outward).
p = subprocess.run([VIBRO, "prove", fig5, "--kind", "impact"], capture_output=True, text=True, timeout=600)
code, s, err = prove("fig05_coexistence.toml", "--kind", "impact")
import re  # noqa: E402
printed = re.findall(r"\[([-0-9.e+]+), ([-0-9.e+]+)\]", p.stdout)
claimed = [e[k] for e in s["events"] for k in ("phase", "velocity_before")] + \
    [m[k] for m in s["multipliers"] for k in ("re", "im")]
expect(len(printed) == len(claimed) and all(mpf(a) <= mpf(c[0]) and mpf(b) >= mpf(c[1])
                                            for (a, b), c in zip(printed, claimed)),
       f"the printed intervals contain the JSON's: {printed} vs {claimed}")
expect("contact 0" in p.stdout, "the printed events name their contact")

# --branch: --time-limit bounds the whole command (every point after it: not proven, the reason).
p = subprocess.run([VIBRO, "prove", fig5, "--branch", branch, "--json", "--time-limit", "0.001"],
                   capture_output=True, text=True, timeout=600)
b = json.loads(p.stdout) if p.stdout.strip() else {}
expect(p.returncode == 4 and b.get("proven", 1) == 0 and all("time limit" in pt["summary"]["reason"] for pt in b["points"]),
       f"--branch --time-limit 0.001: no point proven, each says the time limit (exit {p.returncode})")

print(f"{len(passed) - len(failures)} of {len(passed)} checks passed")
sys.exit(1 if failures else 0)
