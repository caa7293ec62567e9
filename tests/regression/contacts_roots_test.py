#!/usr/bin/python3
"""Starts and roots with several contacts (docs/contacts.md, "No root of any gap is skipped"),
through the real `vibro` binary.

    contacts_roots_test.py VIBRO TEST_SCENES_DIR [--search N]

* tests/scenes/contacts_quad_start_two_stops.toml (issue 37, scene A): two masses at rest on
  preloaded stops. The start is on both stops in quad as in double: the same events (no impact at
  t = 5.9e-9 or 2.8e-8), both contacts stuck from t = 0.
* tests/scenes/contacts_pair_after_release.toml (scene B): every dense sample and section point of
  the double and the quad run inside every gap, the gaps recomputed here from /samples/X and the
  model's mode shapes; status ok; double's events equal quad's and both equal those of the
  independent 40-digit reference (tests/reference/contacts/reference.py, compare.py).
* tests/scenes/contacts_pair_chatter_one_point.toml (scene C): two contacts chattering into one
  accumulation point end `undetermined` in every engine (double, quad, CVODE), where the
  independent reference raises Undetermined, with a message that names both contacts.
* --search N: the first N scenes of tests/reference/contacts/random_search.py (seed 1), the same
  checks on random scenes with 3-6 contacts, impact pairs included.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "reference", "contacts"))
from checks import check, finish  # noqa: E402
import compare  # noqa: E402
import random_search  # noqa: E402


def simulate(vibro, scene, out, *sets):
    cmd = [vibro, "simulate", scene, "--out", out, "--force"]
    for s in sets:
        cmd += ["--set", s]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600)


def scene_contacts(path):
    import tomllib
    with open(path, "rb") as fh:
        sc = tomllib.load(fh)
    out = []
    for c in sc["contact"]:
        dofs = tuple(c["dofs"]) if "dofs" in c else (c["dof"],)
        out.append((dofs, c["side"], float(c["position"]), float(c["restitution"])))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("vibro")
    ap.add_argument("scenes")
    ap.add_argument("--search", type=int, default=0)
    args = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="contacts_roots_")

    # Scene A: the start at rest on both stops, quad as double.
    a = os.path.join(args.scenes, "contacts_quad_start_two_stops.toml")
    runs = {}
    for prec in ("double", "quad"):
        out = os.path.join(tmp, f"A_{prec}.h5")
        p = simulate(args.vibro, a, out, "run.periods=4", f'run.precision="{prec}"')
        check(f"scene A {prec}: exit 0", p.returncode == 0, p.stderr)
        runs[prec] = compare.read_h5(out)
    for prec, (ev, T, status) in runs.items():
        first = [(e.kind, e.contact) for e in ev if e.t == 0.0]
        check(f"scene A {prec}: both contacts stick at t = 0, nothing else", sorted(first) == [("stick", 0), ("stick", 1)],
              first)
        early = [e for e in ev if 0.0 < e.t < 1e-3]
        check(f"scene A {prec}: no event in (0, 1e-3)", not early, early)
    res = compare.compare(runs["quad"][0], runs["double"][0], runs["quad"][1], tol=1e-12, vtol=1e-9)
    check("scene A: double's events are quad's", res.ok and res.matched == len(runs["quad"][0]), res)

    # Scene B: no gap flown through, double and quad.
    b = os.path.join(args.scenes, "contacts_pair_after_release.toml")
    cs = scene_contacts(b)
    runs = {}
    for prec in ("double", "quad"):
        out = os.path.join(tmp, f"B_{prec}.h5")
        p = simulate(args.vibro, b, out, f'run.precision="{prec}"')
        check(f"scene B {prec}: exit 0 (was numerical-failure)", p.returncode == 0, p.stderr)
        worst, where = random_search.sample_violations(out, cs)
        check(f"scene B {prec}: every sample inside every gap", worst <= 1, f"{worst:.3g} x tolerance: {where}")
        runs[prec] = compare.read_h5(out)
        check(f"scene B {prec}: status ok", runs[prec][2] == "ok", runs[prec][2])
        check(f"scene B {prec}: 6 periods", runs[prec][0] and runs[prec][0][-1].t > 68.97, runs[prec][0][-1:])
    res = compare.compare(runs["quad"][0], runs["double"][0], runs["quad"][1], tol=1e-7, vtol=1e-5)
    check("scene B: double's events are quad's", res.ok, res)
    # ... and the independent 40-digit event-driven reference's (tests/reference/contacts/reference.py).
    import reference
    ref_csv = os.path.join(tmp, "B_reference.csv")
    code = reference.main([b, "--out", ref_csv])
    check("scene B: the reference runs", code == 0, code)
    if code == 0:
        ref = compare.read_csv(ref_csv)
        for prec, tol in (("double", 1e-11), ("quad", 1e-12)):
            res = compare.compare(ref, runs[prec][0], runs[prec][1], tol=tol, vtol=1e-9)
            check(f"scene B {prec}: the reference's events", res.ok and res.matched > 150, res)

    # Scene C: two contacts chattering into one accumulation point: undetermined in every engine,
    # where the independent reference stops (it raises Undetermined for such a sequence), with a
    # message that names both contacts and never says they are dependent.
    c = os.path.join(args.scenes, "contacts_pair_chatter_one_point.toml")
    import reference
    try:
        reference.main([c, "--out", os.path.join(tmp, "C_reference.csv")])
    except SystemExit:
        pass
    sim = reference.Simulation(reference.Scene("C", open(c).read()))
    t_ref = None
    try:
        sim.run(10)
    except reference.Undetermined as e:
        t_ref = float(str(e).rsplit("t = ", 1)[1])
    check("scene C: the reference finds two contacts chattering to one point", t_ref is not None)
    for label, sets in (("double", []), ("quad", ['run.precision="quad"']), ("cvode", ['run.engine="cvode"'])):
        out = os.path.join(tmp, f"C_{label}.h5")
        p = simulate(args.vibro, c, out, *sets)
        ev, T, status = compare.read_h5(out)
        check(f"scene C {label}: undetermined (exit 3), never ok", status == "undetermined" and p.returncode == 3,
              (status, p.returncode, p.stderr))
        check(f"scene C {label}: the message names both contacts, not dependence",
              "contacts 0 (q1 - q0 >= -0.394224) and 1 (q0 >= -0.461731) chatter together" in p.stderr
              and "dependent" not in p.stderr, p.stderr)
        if t_ref is not None and ev:
            tol = 1e-6 if label == "cvode" else 1e-11
            check(f"scene C {label}: stops where the reference does", abs(ev[-1].t - t_ref) <= tol * T,
                  (ev[-1].t, t_ref))

    # Scenes the random search found (tests/reference/contacts/random_search.py, seed 1), each run
    # through the search's own checks: every sample inside every gap, no numerical failure, double's
    # events equal to quad's up to where a run left undetermined stopped.
    for name in ("contacts_resting_beside_held",):
        path = os.path.join(args.scenes, name + ".toml")
        with open(path) as fh:
            text = fh.read()
        work = os.path.join(tmp, name)
        os.makedirs(work, exist_ok=True)
        _, kind, msg, *_ = random_search.check((args.vibro, 0, text, scene_contacts(path), work))
        check(f"{name}: the random search's checks", kind != "fail", msg)
    # contacts_resting_beside_held: contact 0 (r = 0) left at zero velocity beside held contact 1 is
    # pushed against its stop by contact 4's impact (it was flown through by 0.0042 once). Contacts 0
    # and 4 (coupled: both on q0) strike in turn, each slower, toward one accumulation point: the
    # 60-digit reference (reference.py --dps 60) stops undetermined there, at t = 4.8490094858760575,
    # after the impacts 4, 0, 4 at 4.8490093829, …94419, …94859. Each precision follows the same
    # impacts and stops undetermined at that instant, naming both contacts (it went on `ok` after
    # merging them into one impact LCP before).
    for prec in ("double", "quad"):
        out = os.path.join(tmp, f"resting_{prec}.h5")
        extra = ['run.precision="quad"'] if prec == "quad" else []
        p = simulate(args.vibro, os.path.join(args.scenes, "contacts_resting_beside_held.toml"), out, *extra)
        ev, T, status = compare.read_h5(out)
        named = re.search(r"contacts 0 \(([^)]*)\) and 4 \(([^)]*)\) chatter together", p.stderr)
        at = re.search(r"(?:near t =|at t =) ([0-9.]+)", p.stderr)
        check(f"resting beside held ({prec}): undetermined (exit 3) naming contacts 0 and 4",
              status == "undetermined" and p.returncode == 3 and named is not None, (status, p.stderr[-500:]))
        check(f"resting beside held ({prec}): stops at the reference's instant t = 4.8490094858760575",
              at is not None and abs(float(at.group(1)) - 4.8490094858760575) < 1e-12, p.stderr[-500:])
        want = [(4, 4.849009382917575), (0, 4.849009441886082), (4, 4.849009485876053)]
        got = [(e.contact, e.t) for e in ev if 4.849 < e.t < 4.8491 and e.kind == "impact"][:3]
        check(f"resting beside held ({prec}): the impacts 4, 0, 4 before it = reference's within 1e-12",
              len(got) == 3 and all(a[0] == b[0] and abs(a[1] - b[1]) < 1e-12 for a, b in zip(got, want)), got)

    if args.search:
        code = random_search.main([args.vibro, "--count", str(args.search), "--seed", "1",
                                   "--keep", os.path.join(tmp, "search")])
        check(f"random search: {args.search} scenes, none failed", code == 0)
    finish()


if __name__ == "__main__":
    main()
