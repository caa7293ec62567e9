#!/usr/bin/python3
"""The proof checker cannot be fooled on the certificates prove_checker_test.py does not edit
(docs/prove.md, "What the checker checks"; issue 37): sticking orbits of several modes (the 2-DOF
chain, r = 0), sticking orbits held on sets of contacts (scene A of issue 37:
tests/scenes/contacts_quad_start_two_stops.toml) and a segment of a branch (the tube in its loose
support over the amplitude).

The truth each edit is judged against: every claim of the unedited certificate contains the true
value (prove.sticking_modes, prove.held_set and prove.segments check that against 50-digit truths
computed without vibro), so a claimed interval moved past itself by twice its width excludes the
truth, and an event, contact, kind, sequence, stability, period or multiplier count changed is false.
Each such edit must be rejected: exit 1 "not confirmed" or exit 2 "not a certificate". Edits that
break the file's form (an unknown key, a key left out, a value of the wrong type, nan, infinity,
bounds swapped, a list of the wrong length) must be rejected too; a claim widened stays true and may
be confirmed or rejected (the checker bounds claimed times by the box width), never anything else.
Never a traceback: the checker answers in one line.
Usage: prove_checker_kinds_test.py VIBRO CHECKER TEST_SCENES
"""
import copy
import importlib.util
import json
import os
import subprocess
import sys
import tempfile

VIBRO, CHECKER, TEST_SCENES = sys.argv[1:4]
TMP = tempfile.mkdtemp(prefix="vibro_checker_kinds_")
spec = importlib.util.spec_from_file_location("vibro_check_proof", CHECKER)
checker = importlib.util.module_from_spec(spec)
spec.loader.exec_module(checker)
sys.setrecursionlimit(10000)

failures = []
counts = {"rejected": 0, "confirmed": 0}

CHAIN2 = """title = "2-DOF chain, preload, r = 0"
[structure]
mass        = [[1.0, 0.0], [0.0, 1.0]]
stiffness   = [[2.0, -1.0], [-1.0, 1.0]]
forcing_dof = 0
contact_dof = 1
[stop]
position    = 1.0
restitution = 0.0
[excitation]
amplitude = 0.8
frequency = 0.8
[run]
periods = 200
"""
TUBE = """title = "tube"
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
"""


def fail(what):
    failures.append(what)
    print("FAIL:", what, flush=True)


def run(cmd):
    return subprocess.run(cmd, capture_output=True, text=True, timeout=900)


def write(name, text):
    path = os.path.join(TMP, name)
    with open(path, "w") as fh:
        fh.write(text)
    return path


def proven(label, scene, *args):
    out = os.path.join(TMP, label + ".json")
    p = run([VIBRO, "prove", scene, "--out", out, *args])
    if p.returncode != 0:
        fail(f"{label}: vibro prove exit {p.returncode}: {p.stdout[:300]} {p.stderr[:300]}")
        return None
    doc = json.load(open(out))
    code, line = checker.check_document(json.dumps(doc).encode())
    if code != 0:
        fail(f"{label}: the unedited certificate is confirmed ({line})")
        return None
    return doc


def judge(label, doc, expected, raw=None):
    """expected: 'rejected' (exit 1 or 2), 'malformed' (exit 2) or 'any' (0, 1 or 2)."""
    data = raw if raw is not None else json.dumps(doc).encode()
    code, line = checker.check_document(data)
    counts["confirmed" if code == 0 else "rejected"] += 1
    if "checker failed" in line or "\n" in line:
        fail(f"{label}: the checker's own failure or more than one line: {line[:300]}")
    elif expected == "rejected" and code not in (1, 2):
        fail(f"{label}: confirmed ({line[:200]})")
    elif expected == "malformed" and code != 2:
        fail(f"{label}: exit {code}, expected 2 ({line[:200]})")


def edits(label, doc, at=None):
    """The edits of the certificate `doc` (of doc["certificates"][at] when `at` is given)."""
    def edit(name, fn, expected="rejected"):
        d = copy.deepcopy(doc)
        fn(d["certificates"][at] if at is not None else d)
        judge(f"{label}: {name}", d, expected)

    c0 = doc["certificates"][at] if at is not None else doc
    s0 = c0["summary"]
    ev = s0["events"]
    contacts = 1 + max([e["contact"] for e in ev] + [len(c0["model"].get("more_contacts", []))])

    def both(key, v):
        def f(c):
            c[key] = v
            c["summary"][key] = v
        return f
    edit("period 2", both("period", 2))
    edit("kind changed", both("kind", "sticking" if c0["kind"] == "impact" else "impact"))
    edit("verdict 'not-proven'", both("verdict", "not-proven"))
    for i, e in enumerate(ev):
        edit(f"event {i} at another contact", lambda c, i=i: c["summary"]["events"][i].__setitem__(
            "contact", (ev[i]["contact"] + 1) % max(2, contacts)))
        other = next(k for k in ("impact", "stick", "release", "accumulation") if k != e["kind"])
        edit(f"event {i} a {other}", lambda c, i=i, k=other: c["summary"]["events"][i].__setitem__("kind", k))
        for key in ("time", "phase", "velocity_before"):
            lo, hi = e[key]
            d = 2 * (hi - lo) + 1e-9 * (1 + abs(lo))
            sign = 1 if i % 2 == 0 else -1  # each event moved one way, the next the other (the cost of a full check each)
            edit(f"event {i} {key} moved past itself ({sign:+d})", lambda c, i=i, key=key, v=[lo + sign * d, hi + sign * d]:
                 c["summary"]["events"][i].__setitem__(key, v))
            if i == 0:
                edit(f"event {i} {key} widened", lambda c, i=i, key=key, v=[lo - 10 * (hi - lo) - 1e-12, hi + 10 * (hi - lo) + 1e-12]:
                     c["summary"]["events"][i].__setitem__(key, v), "any")
            if lo < hi:
                edit(f"event {i} {key} bounds swapped", lambda c, i=i, key=key: c["summary"]["events"][i].__setitem__(
                    key, [hi, lo]), "malformed")
    if len(ev) > 1:
        edit("events 0 and 1 swapped", lambda c: c["summary"]["events"].__setitem__(slice(0, 2), c["summary"]["events"][1::-1]))
    edit("the last event left out", lambda c: c["summary"]["events"].pop())
    edit("an event repeated", lambda c: c["summary"]["events"].append(copy.deepcopy(ev[-1])))
    seq = s0["sequence"]
    if len(set(seq)) > 1:
        edit("the sequence rotated", lambda c: c["summary"].__setitem__("sequence", seq[1:] + seq[:1]))
    edit("the sequence one short", lambda c: c["summary"].__setitem__("sequence", seq[:-1]))
    edit("the sequence one longer", lambda c: c["summary"].__setitem__("sequence", seq + seq[-1:]))
    edit("stability 'unstable'", lambda c: c["summary"].__setitem__(
        "stability", "unstable" if s0["stability"] != "unstable" else "stable"))
    edit("stability 'undecided'", lambda c: c["summary"].__setitem__("stability", "undecided"), "any")
    edit("a multiplier 0.5 added", lambda c: c["summary"]["multipliers"].append({"re": [0.5, 0.6], "im": [0.0, 0.0]}))
    for k, m in enumerate(s0["multipliers"]):
        for part in ("re", "im"):
            lo, hi = m[part]
            d = 2 * (hi - lo) + 1e-9
            edit(f"multiplier {k} {part} moved past itself", lambda c, k=k, part=part, v=[lo + d, hi + d]:
                 c["summary"]["multipliers"][k].__setitem__(part, v))
    if s0["multipliers"]:
        edit("the multipliers emptied", lambda c: c["summary"].__setitem__("multipliers", []))
    sec = s0["section"]
    for key in ("X", "V"):
        for k, (lo, hi) in enumerate(sec[key]):
            d = 2 * (hi - lo) + 1e-9
            edit(f"section {key}[{k}] moved past itself", lambda c, key=key, k=k, v=[lo + d, hi + d]:
                 c["summary"]["section"][key].__setitem__(k, v))
        edit(f"section {key} one short", lambda c, key=key: c["summary"]["section"][key].pop(), "malformed")
        edit(f"section {key} one longer", lambda c, key=key: c["summary"]["section"][key].append(sec[key][-1]), "malformed")
    lo, hi = sec["time"]
    edit("section time moved past itself", lambda c: c["summary"]["section"].__setitem__(
        "time", [lo + 2 * (hi - lo) + 1e-9, hi + 2 * (hi - lo) + 1e-9]))
    edit("section placed elsewhere", lambda c: c["summary"]["section"].__setitem__("at", sec["at"] + " 2"))
    edit("box width claimed 4 times smaller", lambda c: c["summary"].__setitem__("box_width", s0["box_width"] / 4))
    # A model entry moved: the certificate then claims the enclosures for another model. At a point
    # they are ~1e-11 wide and 1e-6 moves the orbit out of them; a segment's hold every orbit of an
    # interval of the parameter (~1e-3 wide on the tube), so there 1e-6 may leave a true theorem, which
    # the checker, recomputing with the edited model, may confirm; 1e-2 moves the orbit out of them.
    segment = any(isinstance(v, str) and v.startswith("[") for v in c0["model"].values())
    for key, v in c0["model"].items():
        if isinstance(v, str) and not v.startswith("["):
            try:
                x = float(v)
            except ValueError:
                continue
            edit(f"model.{key} moved by 1e-6", lambda c, key=key, x=x: c["model"].__setitem__(key, repr(x * (1 + 1e-6) + 1e-9)),
                 "any" if segment else "rejected")
            if segment:
                edit(f"model.{key} moved by 1e-2", lambda c, key=key, x=x: c["model"].__setitem__(key, repr(x * (1 + 1e-2) + 1e-9)))
    # The file's form: unknown keys, keys left out, wrong types, nan and infinity, wrong lengths.
    optional = ("stability_note", "requested_period", "modal_data", "structure")
    for path in ((), ("summary",), ("summary", "section"), ("summary", "events", 0), ("model",)):
        def at_path(c, path=path):
            x = c
            for p in path:
                x = x[p]
            return x
        edit(f"{'.'.join(map(str, path)) or 'the certificate'}: an unknown key",
             lambda c, at_path=at_path: at_path(c).__setitem__("note", 1), "malformed")
        for key in at_path(c0):
            if key in optional:
                continue
            edit(f"{'.'.join(map(str, path + (key,)))} left out", lambda c, at_path=at_path, key=key: at_path(c).pop(key))
            v = at_path(c0)[key]
            edit(f"{'.'.join(map(str, path + (key,)))} of another type",
                 lambda c, at_path=at_path, key=key, v=v: at_path(c).__setitem__(key, 1.5 if isinstance(v, str) else "x"))
    for name, value in (("nan", float("nan")), ("infinity", float("inf"))):
        for path in (("summary", "events", 0, "phase"), ("summary", "section", "X", 0), ("box", 0), ("midpoint", 0)):
            d = copy.deepcopy(doc)
            x = d["certificates"][at] if at is not None else d
            for p in path[:-1]:
                x = x[p]
            x[path[-1]] = [value, value] if isinstance(x[path[-1]], list) else value
            judge(f"{label}: {'.'.join(map(str, path))} {name}", None, "malformed", raw=json.dumps(d).encode())
    for key in ("box", "midpoint", "krawczyk", "unknowns"):
        if key in c0 and isinstance(c0[key], list):
            edit(f"{key} one short", lambda c, key=key: c[key].pop())
            edit(f"{key} one longer", lambda c, key=key: c[key].append(copy.deepcopy(c0[key][-1])))


# Sticking orbits of several modes: the 2-DOF chain, r = 0.
doc = proven("chain2", write("chain2.toml", CHAIN2))
if doc is not None:
    edits("chain2 (sticking, 2 modes)", doc)
    for what, fn in (("the held duration moved past itself",
                      lambda c: c["sticking"].__setitem__("duration", [c["sticking"]["duration"][1] * 2 + 1e-9,
                                                                       c["sticking"]["duration"][1] * 2 + 2e-9])),
                     ("the held phase's pieces emptied", lambda c: c["sticking"].__setitem__("pieces", []))):
        d = copy.deepcopy(doc)
        if "sticking" in d and isinstance(d["sticking"], dict) and "duration" in d["sticking"]:
            fn(d)
            judge(f"chain2: {what}", d, "rejected")

# Sticking orbits held on sets of contacts: scene A of issue 37.
doc = proven("scene_a", os.path.join(TEST_SCENES, "contacts_quad_start_two_stops.toml"))
if doc is not None:
    edits("scene A (held on sets)", doc)
    seg = doc["segments"]
    for what, fn in (("segment 0's held set emptied", lambda c: c["segments"][0].__setitem__("held", [])),
                     ("segment 0's held set another", lambda c: c["segments"][0].__setitem__(
                         "held", [1 - x for x in seg[0]["held"]] if seg[0]["held"] else [0])),
                     ("the last segment left out", lambda c: c["segments"].pop()),
                     ("segment 0 repeated", lambda c: c["segments"].insert(0, copy.deepcopy(seg[0]))),
                     ("the coupling W_01 moved past itself", lambda c: c["coupling"]["W"][0].__setitem__(
                         1, [c["coupling"]["W"][0][1][1] + 1e-6, c["coupling"]["W"][0][1][1] + 2e-6]))):
        d = copy.deepcopy(doc)
        fn(d)
        judge(f"scene A: {what}", d, "rejected")

# A segment of a branch: the tube over the amplitude.
tube = write("tube.toml", TUBE)
h5 = os.path.join(TMP, "tube.h5")
p = run([VIBRO, "continue", tube, "--kind", "impact", "--param", "excitation.amplitude", "--to", "0.31", "--step", "0.002",
         "--max-points", "2", "--out", h5])
out = os.path.join(TMP, "tube_branch.json")
p = run([VIBRO, "prove", tube, "--branch", h5, "--out", out])
if p.returncode != 0:
    fail(f"prove --branch: exit {p.returncode}: {p.stdout[-300:]} {p.stderr[-300:]}")
else:
    doc = json.load(open(out))
    code, line = checker.check_document(json.dumps(doc).encode())
    if code != 0:
        fail(f"tube branch: the unedited certificates are confirmed ({line})")
    else:
        seg = next(i for i, c in enumerate(doc["certificates"]) if c["model"]["amplitude"].startswith("["))
        # The segment edited in a file of its own certificate (as the checker takes it) to keep the cost down.
        edits("tube branch segment", dict(doc, certificates=[doc["certificates"][seg]]), 0)
        d = copy.deepcopy(doc)
        d["certificates"].pop(seg)
        judge("tube branch: the segment left out", d, "any")
        d = copy.deepcopy(doc)
        d["branch"] = 3
        judge("tube branch: the branch name a number", d, "malformed")
        d = copy.deepcopy(doc)
        d["certificates"] = []
        judge("tube branch: no certificate", d, "malformed")

# Through the command: one line and the exit code, never a traceback.
path = os.path.join(TMP, "cli.json")
with open(path, "w") as fh:
    fh.write('{"format": 1, "verdict": "proven", "kind": "sticking", "unknowns": [], "segments": NaN}')
pr = run([sys.executable, CHECKER, path])
if pr.returncode != 2 or len(pr.stdout.splitlines()) != 1 or "Traceback" in pr.stderr:
    fail(f"the command on a NaN: exit {pr.returncode}, {pr.stdout[:200]} {pr.stderr[-300:]}")

total = sum(counts.values())
print(f"{total} edits: {counts['rejected']} rejected, {counts['confirmed']} confirmed (widened claims)")
if total < 200:
    fail(f"at least 200 edits ({total})")
print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
