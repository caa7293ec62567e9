"""`validate`, `partition` and the contact keys with several contacts (docs/validation.md,
docs/contacts.md), against independent truths.

The truth of the validation tests is the closed form of the symmetric two-sided 1-DOF oscillator
(docs/contacts_reference.md): a unit mass on a unit spring (ω1 = 1) between rigid stops at ±Δ,
forced by a sin ωt, restitution r at both stops. Its symmetric period-1 orbit hits +Δ at phase φ
with speed V and −Δ half a period later, where V solves

    (k1² + k2²) V² − 2 Δ k1 V + Δ² − U² = 0,
    k1 = (1 + r) tan(θ/2) / (2 ω1),  k2 = (1 − r) / (2 ω),  θ = ω1 π / ω,  U = a / (ω1² − ω²),

and φ = atan2((Δ − k1 V)/U, k2 V/U). Both roots are orbits (the larger one stable here); the state
just after the impact on +Δ is x = Δ, ẋ = −r V at t = φ/ω. Nothing here is computed by vibro: the
branch CSV is written from these formulas alone.

The truth of the partition test is `vibro orbit` itself at each cell's parameters, an independent
path (a transient, then Newton) to the orbit that continuation followed."""
import csv
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import vibro

from conftest import CLI, SCENES

SCRIPTS = os.path.join(os.path.dirname(__file__), "..", "..", "scripts")
TWO_SIDED = os.path.join(SCENES, "contacts_two_sided_1dof.toml")
R = 0.8
SETS = {"excitation.amplitude": 1.0, "contact[0].restitution": R, "contact[1].restitution": R}
SET_ARGS = [a for k, v in SETS.items() for a in ("--set", f"{k}={v!r}")]


def closed_form(w, r=R, w1=1.0, a=1.0, delta=1.0):
    """The symmetric orbits at forcing frequency w: [(V, φ)], larger V first."""
    theta = w1 * math.pi / w
    k1 = (1 + r) * math.tan(theta / 2) / (2 * w1)
    k2 = (1 - r) / (2 * w)
    u = a / (w1 ** 2 - w ** 2)
    qa, qb, qc = k1 * k1 + k2 * k2, -2 * delta * k1, delta * delta - u * u
    disc = qb * qb - 4 * qa * qc
    out = []
    for s in (1, -1):
        v = (-qb + s * math.sqrt(disc)) / (2 * qa)
        if v > 0:
            out.append((v, math.atan2((delta - k1 * v) / u, k2 * v / u) % (2 * math.pi)))
    return out


def test_closed_form_as_stated():
    # The oracle itself: the values quoted in docs/contacts.md (r = 0.5) and the issue (r = 0.8).
    assert abs(closed_form(2.5)[0][0] - 1.79902274247141) < 1e-13
    v, phi = closed_form(2.5, r=0.5)[0]
    assert abs(v - 1.8851757279765) < 1e-12 and abs(phi - 2.9980627698639) < 1e-12


def run(*args, timeout=600):
    return subprocess.run([CLI, *args], capture_output=True, text=True, timeout=timeout)


def write_csv(path, rows, header):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows)


HEADER = ["value", "time", "displacement_1", "velocity_1", "period", "stable", "sequence"]
OMEGAS = (2.2, 2.5, 2.8, 3.0, 3.5)


def closed_form_rows():
    """Both orbits at each ω: the state just after the impact on +Δ, claimed period 1, the
    stability (the larger root stable, the smaller unstable: checked below against vibro's
    multipliers) and the sequence, written from either stop."""
    rows = []
    for i, w in enumerate(OMEGAS):
        for k, (v, phi) in enumerate(closed_form(w)):
            sequence = "0:impact 1:impact" if i % 2 else "1:impact 0:impact"
            rows.append([repr(w), repr(phi / w), "1.0", repr(-R * v), 1, 1 if k == 0 else 0, sequence])
    return rows


def validate_json(csv_path, *extra):
    p = run("validate", TWO_SIDED, csv_path, "--param", "excitation.frequency", *SET_ARGS, "--json", *extra)
    return p, (json.loads(p.stdout) if p.stdout.strip().startswith("{") else None)


def test_closed_form_branch_is_confirmed_point_by_point(tmp_path):
    rows = closed_form_rows()
    write_csv(tmp_path / "b.csv", rows, HEADER)
    p, j = validate_json(str(tmp_path / "b.csv"))
    assert p.returncode == 0, p.stdout + p.stderr
    assert len(j["points"]) == len(rows) == 2 * len(OMEGAS)
    for row, pt in zip(rows, j["points"]):
        assert pt["verdict"] == "confirmed", pt
        # The claimed state is the closed form's: vibro's orbit passes through it to rounding.
        assert pt["distance"] < 1e-12, pt
        assert pt["period"] == 1 and pt["sticking_fraction"] == 0.0
        # One impact on each stop, whichever stop the claim starts from.
        assert sorted(pt["sequence"].split()) == ["0:impact", "1:impact"], pt
        # Two impacts of restitution r and no damping: det DF = r⁴ (docs/contacts.md).
        mu = [complex(a, b) for a, b in pt["floquet_multipliers"]]
        assert abs(abs(np.prod(mu)) - R ** 4) < 1e-10, pt
        assert pt["stable"] == (row[5] == 1)


def test_wrong_state_and_wrong_sequence_are_refuted(tmp_path):
    (v, phi), = closed_form(2.5)[:1]
    rows = [
        ["2.5", repr(phi / 2.5), "1.0", repr(-R * v), 1, 1, "0:impact 1:impact"],          # confirmed
        ["2.5", repr(phi / 2.5), "1.0", repr(-R * v + 1e-3), 1, 1, "0:impact 1:impact"],   # state off
        ["2.5", repr(phi / 2.5), "1.0", repr(-R * v), 1, 1, "0:impact 0:impact"],           # sequence
        ["2.5", repr(phi / 2.5), "1.0", repr(-R * v), 1, 1, "0:impact*2 1:impact"],         # sequence
        ["2.5", repr(phi / 2.5), "1.0", repr(-R * v), 1, 1, ""],                            # no claim
    ]
    write_csv(tmp_path / "e.csv", rows, HEADER)
    p, j = validate_json(str(tmp_path / "e.csv"))
    assert p.returncode == 4, p.stdout + p.stderr
    verdicts = [pt["verdict"] for pt in j["points"]]
    assert verdicts == ["confirmed", "no-orbit-near", "sequence-differs", "sequence-differs", "confirmed"]
    assert j["disagreements"] == 3
    # The message says both sequences.
    detail = j["points"][2]["detail"]
    assert "claimed sequence 0:impact 0:impact" in detail and "vibro's orbit has" in detail, detail
    assert sorted(detail.split("vibro's orbit has ")[1].split()) == ["0:impact", "1:impact"], detail
    # The file holds both sequences per point.
    p, j2 = validate_json(str(tmp_path / "e.csv"), "--out", str(tmp_path / "e.h5"))
    v = vibro.read(str(tmp_path / "e.h5"))["validation"]
    assert list(v["claimed_sequence"]) == [r[6] for r in rows]
    assert list(v["sequence"]) == [pt["sequence"] for pt in j["points"]]
    assert list(v["verdict"]) == verdicts
    # The text table names the verdict and vibro's sequence.
    p = run("validate", TWO_SIDED, str(tmp_path / "e.csv"), "--param", "excitation.frequency", *SET_ARGS)
    assert p.returncode == 4 and "sequence-differs" in p.stdout and "sequence" in p.stdout.splitlines()[0]


def test_python_validate_takes_the_sequence_column():
    (v, phi), = closed_form(2.8)[:1]
    table = {"value": np.array([2.8, 2.8, 2.8]), "time": np.full(3, phi / 2.8),
             "displacement_1": np.ones(3), "velocity_1": np.full(3, -R * v),
             "sequence": np.array(["1:impact 0:impact", "1:impact 1:impact", ""])}
    scene = vibro.load_scene(TWO_SIDED, set=SETS)
    d = vibro.validate(scene, table, "excitation.frequency")
    assert [pt["verdict"] for pt in d["points"]] == ["confirmed", "sequence-differs", "confirmed"]
    # The same claims through a CSV and the command line.
    # A structured array with an object column (None: no claim).
    rec = np.zeros(2, dtype=[("value", "f8"), ("time", "f8"), ("displacement", "f8", (1,)),
                             ("velocity", "f8", (1,)), ("sequence", "O")])
    rec["value"], rec["time"] = 2.8, phi / 2.8
    rec["displacement"][:, 0], rec["velocity"][:, 0] = 1.0, -R * v
    rec["sequence"] = ["0:impact 0:impact", None]
    d = vibro.validate(scene, rec, "excitation.frequency")
    assert [pt["verdict"] for pt in d["points"]] == ["sequence-differs", "confirmed"]
    with pytest.raises(ValueError, match="sequence.*expected strings"):
        vibro.validate(scene, {**table, "sequence": np.zeros(3)}, "excitation.frequency")
    with pytest.raises(ValueError, match=r"branch row 1 \(sequence\).*0:bounce"):
        vibro.validate(scene, {**table, "sequence": np.array(["", "0:bounce", ""])}, "excitation.frequency")


def test_bad_sequences_are_bad_input(tmp_path):
    (v, phi), = closed_form(2.5)[:1]
    good = ["2.5", repr(phi / 2.5), "1.0", repr(-R * v), 1, 1]
    for sequence, expect in [("0:impact 2:impact", "the scene has 2 contacts"),
                             ("0:impact 1:bounce", "unknown event kind"),
                             ("0+0:impact", "named twice")]:
        write_csv(tmp_path / "bad.csv", [good + [sequence]], HEADER)
        p = run("validate", TWO_SIDED, str(tmp_path / "bad.csv"), "--param", "excitation.frequency", *SET_ARGS,
                "--out", str(tmp_path / "never.h5"))
        assert p.returncode == 2, (sequence, p.stdout, p.stderr)
        assert expect in p.stderr and "bad.csv:2" in p.stderr, p.stderr
        assert not (tmp_path / "never.h5").exists()
    # A sequence claimed on a scene with one contact.
    write_csv(tmp_path / "one.csv", [["1.2", "0.1", "1.5", "0.1", 1, "", "0:impact"]], HEADER)
    p = run("validate", os.path.join(SCENES, "fig08_preload.toml"), str(tmp_path / "one.csv"),
            "--param", "excitation.amplitude")
    assert p.returncode == 2 and "one contact" in p.stderr and "one.csv:2" in p.stderr, p.stderr


def test_param_contact_key(tmp_path):
    # --param contact[1].position: the row at the closed form's Δ = 1 is confirmed; the same state
    # claimed with the upper stop moved to 1.05 is no orbit of that scene.
    (v, phi), = closed_form(2.5)[:1]
    rows = [["1.0", repr(phi / 2.5), "1.0", repr(-R * v), 1, 1, "0:impact 1:impact"],
            ["1.05", repr(phi / 2.5), "1.0", repr(-R * v), 1, 1, "0:impact 1:impact"]]
    write_csv(tmp_path / "d.csv", rows, HEADER)
    p = run("validate", TWO_SIDED, str(tmp_path / "d.csv"), "--param", "contact[1].position", *SET_ARGS,
            "--set", "excitation.frequency=2.5", "--json")
    j = json.loads(p.stdout)
    assert [pt["verdict"] for pt in j["points"]] == ["confirmed", "no-orbit-near"], j
    # A contact the scene does not have: exit 2 naming the key and how many contacts there are.
    for cmd in (["validate", TWO_SIDED, str(tmp_path / "d.csv"), "--param", "contact[2].position"],
                ["sweep", TWO_SIDED, "--param", "contact[2].position", "--from", "1", "--to", "2"],
                ["partition", TWO_SIDED, "--params", "excitation.frequency,contact[2].position", "--range1", "1,2",
                 "--range2", "1,2", "--sticking-fraction", "0.5"],
                ["simulate", TWO_SIDED, "--set", "contact[2].restitution=0.5"]):
        p = run(*cmd)
        assert p.returncode == 2, (cmd, p.stderr)
        assert "contact[2]" in p.stderr and "the scene has 2 contacts" in p.stderr, (cmd, p.stderr)


def test_contact_zero_of_a_stop_is_the_stop():
    # On a [stop] scene, contact[0].restitution is stop.restitution: the same branch, point by point.
    path = os.path.join(SCENES, "fig08_preload.toml")
    a = json.loads(run("continue", path, "--param", "stop.restitution", "--to", "0.6", "--json").stdout)
    b = json.loads(run("continue", path, "--param", "contact[0].restitution", "--to", "0.6", "--json").stdout)
    assert len(a["points"]) > 3
    assert [p["value"] for p in a["points"]] == [p["value"] for p in b["points"]]
    assert [p["sticking_fraction"] for p in a["points"]] == [p["sticking_fraction"] for p in b["points"]]


def test_branch_to_csv_writes_the_sequence(tmp_path):
    # A branch file as `vibro continue --out` writes it for several contacts (/branch/sequence),
    # made here from the closed form, exported by scripts/branch_to_csv.py and validated.
    h5py = pytest.importorskip("h5py")
    pts = [(w, *closed_form(w)[0]) for w in OMEGAS]

    def branch_file(path, sequences):
        with h5py.File(path, "w") as f:
            b = f.create_group("branch")
            b["value"] = np.array([w for w, _, _ in pts])
            b["section_time"] = np.array([phi / w for w, _, phi in pts])
            b["X"] = b["q"] = np.ones((len(pts), 1))
            b["V"] = b["q_dot"] = np.array([[-R * v] for _, v, _ in pts])
            b["stable"] = np.ones(len(pts), dtype=np.uint8)
            b["sticking_fraction"] = np.full(len(pts), np.nan)
            b["sequence"] = np.array(sequences, dtype=h5py.string_dtype())
            b.attrs["period"] = 1

    branch_file(tmp_path / "b.h5", ["0:impact 1:impact"] * len(pts))
    p = subprocess.run([sys.executable, os.path.join(SCRIPTS, "branch_to_csv.py"), str(tmp_path / "b.h5"),
                        str(tmp_path / "b.csv")], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    with open(tmp_path / "b.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["sequence"] for r in rows] == ["0:impact 1:impact"] * len(pts)
    p, j = validate_json(str(tmp_path / "b.csv"))
    assert p.returncode == 0 and all(pt["verdict"] == "confirmed" for pt in j["points"]), p.stdout + p.stderr
    # One entry wrong: that point is refuted, the others confirmed.
    branch_file(tmp_path / "w.h5", ["0:impact 1:impact"] * (len(pts) - 1) + ["1:impact 1:impact"])
    subprocess.run([sys.executable, os.path.join(SCRIPTS, "branch_to_csv.py"), str(tmp_path / "w.h5"),
                    str(tmp_path / "w.csv")], check=True)
    p, j = validate_json(str(tmp_path / "w.csv"))
    assert p.returncode == 4
    assert [pt["verdict"] for pt in j["points"]] == ["confirmed"] * (len(pts) - 1) + ["sequence-differs"]
    # One contact: every entry empty, no column.
    branch_file(tmp_path / "e.h5", [""] * len(pts))
    subprocess.run([sys.executable, os.path.join(SCRIPTS, "branch_to_csv.py"), str(tmp_path / "e.h5"),
                    str(tmp_path / "e.csv")], check=True)
    with open(tmp_path / "e.csv") as fh:
        assert "sequence" not in fh.readline()


# ---- partition ----

def coarse_cycle(text):
    """A contact sequence as a cyclic word, independently of vibro: runs expanded, each run of
    impacts at j ending in j's accumulation one entry, reduced to its shortest repeating unit, and
    as the least rotation (so that two words of one orbit compare equal)."""
    entries = []
    for e in text.split():
        name, _, count = e.partition("*")
        entries += [name] * (int(count) if count else 1)
    acc = [i for i, e in enumerate(entries) if e.endswith(":accumulation")]
    if acc:
        entries = entries[acc[-1] + 1:] + entries[:acc[-1] + 1]
        out = []
        for e in entries:
            if e.endswith(":accumulation"):
                j = e.split(":")[0]
                while out and out[-1] == j + ":impact":
                    out.pop()
                out.append(j + ":chattering")
            else:
                out.append(e)
        entries = out
    n = len(entries)
    for p in range(1, n + 1):
        if n % p == 0 and entries == entries[:p] * (n // p):
            entries = entries[:p]
            break
    return min(tuple(entries[i:] + entries[:i]) for i in range(len(entries)))


def test_partition_cells_agree_with_orbit():
    # The (ω, f) plane of the two-sided scene. Each column is cut into cells by its crossings of
    # the sticking-fraction levels; `vibro orbit` at three points of every cell finds an orbit whose
    # sticking fraction has the same levels below it throughout the cell, one level more or less
    # than the next cell (the level crossed between them), and whose contact sequence is that of
    # the partition's span holding the point.
    levels = [0.05, 0.1]
    p = run("partition", TWO_SIDED, "--params", "excitation.frequency,excitation.amplitude", "--range1", "0.7,0.8",
            "--steps1", "1", "--range2", "4,6", "--sticking-fraction", ",".join(map(str, levels)), "--json")
    assert p.returncode == 0, p.stderr
    j = json.loads(p.stdout)
    checked = 0
    for col in j["columns"]:
        assert col["status"] == "ok", col
        spans = col.get("sequences", [])
        assert spans, col
        crossings = sorted(x["value"] for x in col["crossings"])
        assert crossings, col
        edges = [spans[0]["from"]] + crossings + [spans[-1]["to"]]
        counts = []
        for lo, hi in zip(edges, edges[1:]):
            seen = set()
            for f in (0.25, 0.5, 0.75):
                v = lo + f * (hi - lo)
                o = json.loads(run("orbit", TWO_SIDED, "--set", f"excitation.frequency={col['value1']!r}",
                                   "--set", f"excitation.amplitude={v!r}", "--json").stdout)
                assert o["status"] == "converged", (col["value1"], v, o)
                seen.add(sum(o["sticking_fraction"] > lv for lv in levels))
                for span in spans:
                    if span["from"] <= v <= span["to"]:
                        assert coarse_cycle(o["sequence"]) == coarse_cycle(span["sequence"]), (v, o, span)
                        checked += 1
            assert len(seen) == 1, (col["value1"], lo, hi, seen)
            counts.append(seen.pop())
        assert all(abs(a - b) == 1 for a, b in zip(counts, counts[1:])), (col["value1"], edges, counts)
    assert checked >= 9


def test_python_partition_has_the_spans():
    # vibro.partition returns the command line's JSON, and the spans as a structured array.
    args = ["--params", "excitation.frequency,excitation.amplitude", "--range1", "0.75,0.8", "--steps1", "1",
            "--range2", "4.5,5.5", "--sticking-fraction", "0.05"]
    want = json.loads(run("partition", TWO_SIDED, *args, "--json").stdout)
    d = vibro.partition(vibro.load_scene(TWO_SIDED), ("excitation.frequency", "excitation.amplitude"), (0.75, 0.8),
                        (4.5, 5.5), 0.05, steps1=1)
    assert d["columns"] == want["columns"]
    spans = [(c["value1"], sp["from"], sp["to"], sp["sequence"]) for c in want["columns"] for sp in c["sequences"]]
    assert spans and [tuple(r) for r in d["sequences"].tolist()] == spans
    # One contact: no spans.
    one = vibro.partition(vibro.load_scene(os.path.join(SCENES, "fig08_preload.toml")),
                          ("excitation.frequency", "excitation.amplitude"), (2.8, 3.0), (1.0, 1.5), 0.5, steps1=1,
                          from2=1.2)
    assert len(one["sequences"]) == 0 and all("sequences" not in c for c in one["columns"])


def test_branch_reader_reads_the_sequence(tmp_path):
    # `continue --from FILE --point K` reads /branch/sequence when the file has it: one string per
    # point, else bad input naming the dataset (a one-contact branch with the dataset added).
    h5py = pytest.importorskip("h5py")
    path = os.path.join(SCENES, "fig08_preload.toml")
    out = tmp_path / "b.h5"
    p = run("continue", path, "--param", "excitation.amplitude", "--to", "1.3", "--out", str(out), "--json")
    assert p.returncode == 0, p.stderr
    with h5py.File(out, "a") as f:
        n = len(f["branch/value"])
        if "sequence" in f["branch"]:
            del f["branch/sequence"]
        f["branch/sequence"] = np.array([""] * n, dtype=h5py.string_dtype())
    restart = ["continue", path, "--param", "excitation.amplitude", "--to", "1.35", "--from", str(out), "--point", "1"]
    p = run(*restart, "--json")
    assert p.returncode == 0, p.stderr
    for bad in (np.zeros(n), np.array([""] * (n + 1), dtype=h5py.string_dtype())):
        with h5py.File(out, "a") as f:
            del f["branch/sequence"]
            f["branch/sequence"] = bad
        p = run(*restart)
        assert p.returncode == 2 and "/branch/sequence" in p.stderr, p.stderr


@pytest.mark.parametrize("key,value", [("contact[1].position", 1.1), ("contact[0].restitution", 0.3)])
def test_sweep_in_a_contact_key_is_the_scene_with_it_set(key, value):
    # sweep sets contact[i].position/restitution without parsing the scene again
    # (frontend.hpp, SceneWith); its first run starts from the scene's initial state, so it is the
    # run of the scene parsed with --set KEY=VALUE: the same attractor, to the bit.
    sweep = json.loads(run("sweep", TWO_SIDED, "--param", key, "--from", repr(value), "--to", repr(value + 0.05),
                           "--steps", "1", "--one-way", "--json").stdout)
    sim = json.loads(run("simulate", TWO_SIDED, "--set", f"{key}={value!r}", "--json").stdout)
    a, b = sweep["points"][0], sim["attractor"]
    assert a["kind"] == b["kind"] and a["sticking_fraction"] == b["sticking_fraction"], (a, b)
    assert a["stick_phases"] == b["stick_phases"]


# ---- score ----

def test_score_matches_events_per_contact(tmp_path):
    # vibro's own events of the two-sided scene scored against its run: everything matched, with
    # or without their contacts. The same times with the contacts swapped (an impact on the other
    # stop at the same instant) are not the same motion: with the contact column every event is
    # unmatched, the first divergence naming the contact; without it they match (the column is
    # what tells the stops apart).
    ev = vibro.simulate(vibro.load_scene(TWO_SIDED)).events
    t, kind, contact = np.asarray(ev["t"]), np.asarray(ev["kind"]), np.asarray(ev["contact"])
    assert set(contact) == {0, 1}
    own = vibro.score(TWO_SIDED, ev)
    assert own["agrees"] and own["unmatched"] == 0 and own["matched"] == len(ev)
    swapped = vibro.score(TWO_SIDED, {"t": t, "kind": kind, "contact": 1 - contact})
    assert not swapped["agrees"] and swapped["matched"] == 0
    assert "at contact" in swapped["first_divergence"]["why"], swapped["first_divergence"]
    blind = vibro.score(TWO_SIDED, {"t": t, "kind": kind})
    assert blind["agrees"] and blind["matched"] == len(ev)
    # The same through a CSV and the command line.
    names = {1: "impact", 2: "accumulation", 3: "stick", 4: "release", 5: "grazing"}
    for name, cs in (("good", contact), ("swapped", 1 - contact)):
        write_csv(tmp_path / f"{name}.csv", [[repr(float(a)), names[int(b)], int(c)] for a, b, c in zip(t, kind, cs)],
                  ["t", "kind", "contact"])
        p = run("score", TWO_SIDED, str(tmp_path / f"{name}.csv"), "--json")
        assert p.returncode == (0 if name == "good" else 4), p.stderr
        j = json.loads(p.stdout)
        assert j["matched"] == (len(ev) if name == "good" else 0)
    # A contact the scene does not have, or a row without one when others have it: exit 2.
    rows = [[repr(float(a)), names[int(b)], int(c)] for a, b, c in zip(t, kind, contact)]
    write_csv(tmp_path / "bad.csv", [rows[0][:2] + [2]] + rows[1:], ["t", "kind", "contact"])
    p = run("score", TWO_SIDED, str(tmp_path / "bad.csv"))
    assert p.returncode == 2 and "bad.csv:2: contact 2: the scene has 2 contacts" in p.stderr, p.stderr
    write_csv(tmp_path / "some.csv", [rows[0][:2] + [""]] + rows[1:], ["t", "kind", "contact"])
    p = run("score", TWO_SIDED, str(tmp_path / "some.csv"))
    assert p.returncode == 2 and "some.csv:2: no contact" in p.stderr, p.stderr


def test_continued_branch_exported_and_validated(tmp_path):
    # The round trip: a branch computed by `vibro continue` (from the closed form's state at
    # ω = 2.5), exported by branch_to_csv.py with its sequence column, is confirmed point by point
    # by `vibro validate`; the same file with one point's sequence made wrong refutes that point.
    v, phi = closed_form(2.5)[0]
    start = ["--set", "excitation.frequency=2.5", "--set", f"initial.time={phi / 2.5!r}",
             "--set", "initial.displacement=[1.0]", "--set", f"initial.velocity=[{-R * v!r}]"]
    p = run("continue", TWO_SIDED, *SET_ARGS, *start, "--transient", "0", "--param", "excitation.frequency",
            "--to", "3.0", "--out", str(tmp_path / "b.h5"))
    assert p.returncode == 0, p.stderr
    subprocess.run([sys.executable, os.path.join(SCRIPTS, "branch_to_csv.py"), str(tmp_path / "b.h5"),
                    str(tmp_path / "b.csv")], check=True)
    with open(tmp_path / "b.csv") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], rows[1:]
    # The sequence column, then the strobe_J columns (which validate reads past).
    k = header.index("sequence")
    assert header[k + 1:] == ["strobe_0", "strobe_1"] and len(body) >= 5, header
    assert all(sorted(r[k].split()) == ["0:impact", "1:impact"] for r in body), body
    p, j = validate_json(str(tmp_path / "b.csv"))
    assert p.returncode == 0, p.stdout + p.stderr
    assert all(pt["verdict"] == "confirmed" and pt["distance"] < 1e-9 for pt in j["points"])
    # Every point against the closed form: the largest |multiplier| is r² (a complex pair).
    assert all(abs(max(abs(complex(a, b)) for a, b in pt["floquet_multipliers"]) - R ** 2) < 1e-9
               for pt in j["points"])
    body[len(body) // 2][k] = "0:impact 0:impact"
    write_csv(tmp_path / "w.csv", body, header)
    p, j = validate_json(str(tmp_path / "w.csv"))
    assert p.returncode == 4
    verdicts = [pt["verdict"] for pt in j["points"]]
    assert verdicts.count("sequence-differs") == 1 and verdicts[len(body) // 2] == "sequence-differs"
    # The strobe_J columns carry no claim but are read as every column is (fuzz/surfaces.py found a
    # duplicated or non-finite strobe column accepted): once, and empty or a finite number.
    body[len(body) // 2][k] = body[0][k]  # the sequence made right again
    s0 = header.index("strobe_0")
    write_csv(tmp_path / "dup.csv", [r + [r[s0]] for r in body], header + ["strobe_0"])
    p, _ = validate_json(str(tmp_path / "dup.csv"))
    assert p.returncode == 2 and f"dup.csv:1:{len(header) + 1} (strobe_0): column 'strobe_0' given twice" in p.stderr, p.stderr
    for bad in ("nan", "inf", "x"):
        rows_bad = [list(r) for r in body]
        rows_bad[1][s0] = bad
        write_csv(tmp_path / "bad.csv", rows_bad, header)
        p, _ = validate_json(str(tmp_path / "bad.csv"))
        assert p.returncode == 2 and f"bad.csv:3:{s0 + 1} (strobe_0): '{bad}' is not a finite number" in p.stderr, p.stderr
    rows_empty = [list(r) for r in body]
    rows_empty[1][s0] = ""  # NaN strobe, as branch_to_csv.py writes it
    write_csv(tmp_path / "empty.csv", rows_empty, header)
    p, _ = validate_json(str(tmp_path / "empty.csv"))
    assert p.returncode == 0, p.stdout + p.stderr
