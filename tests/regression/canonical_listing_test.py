#!/usr/bin/python3
"""An orbit's events listed from the start of its contact sequence's canonical rotation, and a
corner of the map said where the exponents and the branch follow one piece (docs/orbits.md, "Where
the orbit's listing starts"; docs/contacts.md, "Periodic orbits"), through the real `vibro` binary:

    canonical_listing_test.py VIBRO TEST_SCENES_DIR DATA_SCENES_DIR

* Issue 37's scene D (contacts_chain3_two_stops.toml): `vibro orbit --kind impact` lists its five
  impacts in the order its `sequence` reads them (0:impact 1:impact*4: contact 0's impact first;
  before, 1, 1, 1, 1, 0 from Newton's section), in the JSON, the text and Python's `vibro.orbit`.
  The truth that the printed state and the first listed event agree is a second simulation: the
  HDF5 file of `--out` simulates one period from the reported section state, and its /events must
  be the listed impacts in the listed order (contacts and contact speeds), every one after
  `section_time`.
* A single-contact impact orbit (Fig. 5, a [stop]) and a one-contact [[contact]] scene: the first
  listed impact is the first event of the file's period (their outputs are unchanged, to the bit,
  against the commit before: checked with the binaries side by side, docs/orbits.md).
* The damped symmetric chain whose two outer stops hit at one instant (contacts_symmetric_damped_corner.toml):
  `vibro simulate` names the corner in a `corner` line and `lyapunov_corner` (the exponents follow
  the first order's piece), and `vibro continue` names it in its `corner` line and JSON key.
"""
import json
import math
import os
import subprocess
import sys
import tempfile

import h5py

failures = []

# A 1-DOF oscillator with one [[contact]] above it (the two-sided scene's upper stop alone).
ONE_CONTACT = """[structure]
mass = [[1.0]]
stiffness = [[1.0]]
forcing_dof = 0
[[contact]]
dof = 0
side = "above"
position = 1.0
restitution = 0.8
[excitation]
amplitude = 4.0
frequency = 2.5
"""


def check(what, ok, detail=""):
    print(f"{'ok  ' if ok else 'FAIL'} {what}{': ' + str(detail) if detail else ''}")
    if not ok:
        failures.append(what)


def run(vibro, *args):
    p = subprocess.run([vibro, *args], capture_output=True, text=True, timeout=600)
    return p


def expand(sequence):
    """The contacts of a sequence's impacts in order ("0:impact 1:impact*4" -> [0, 1, 1, 1, 1])."""
    out = []
    for entry in sequence.split():
        who, kind = entry.split(":")
        count = 1
        if "*" in kind:
            kind, count = kind.split("*")
            count = int(count)
        if kind == "impact":
            out += [int(who)] * count
    return out


def wrap(x):
    return math.remainder(x, 2 * math.pi)


def listing_agrees_with_file(name, vibro, scene, d, h5path):
    """The file's /events (one period simulated from the reported section) against the listing."""
    with h5py.File(h5path, "r") as f:
        t = f["/events/t"][:]
        kind = f["/events/kind"][:]
        contact = f["/events/contact"][:]
        v = f["/events/v_before"][:]
        section = float(f["/orbit"].attrs["section_time"])
    check(f"{name}: the file's section is the JSON's", abs(section - d["section_time"]) == 0, (section, d["section_time"]))
    impacts = [(float(t[i]), int(contact[i]), float(v[i])) for i in range(len(t)) if int(kind[i]) == 1]
    n = len(d["impact_phases"])
    check(f"{name}: the file holds the orbit's impacts", len(impacts) >= n, (len(impacts), n))
    if len(impacts) < n:
        return
    check(f"{name}: every event after the section", all(x[0] > section for x in impacts), impacts[0][0] - section)
    got_contacts = [c for _, c, _ in impacts[:n]]
    want_contacts = d["impact_contacts"] if "impact_contacts" in d and d["impact_contacts"] else [0] * n
    check(f"{name}: the file's impacts in the listed order of contacts", got_contacts == want_contacts,
          (got_contacts, want_contacts))
    worst_v = max(abs(a[2] - b) / (1 + abs(b)) for a, b in zip(impacts, d["impact_velocities"]))
    check(f"{name}: the file's impact speeds in the listed order", worst_v < 1e-9, worst_v)



def main():
    vibro, test_scenes, data_scenes = sys.argv[1], sys.argv[2], sys.argv[3]
    tmp = tempfile.mkdtemp(prefix="canonical_listing_")

    # Scene D.
    scene_d = os.path.join(test_scenes, "contacts_chain3_two_stops.toml")
    p = run(vibro, "orbit", scene_d, "--kind", "impact", "--json")
    check("scene D: orbit --json exits 0", p.returncode == 0, p.stderr.strip())
    d = json.loads(p.stdout)
    check("scene D: sequence", d.get("sequence") == "0:impact 1:impact*4", d.get("sequence"))
    check("scene D: impacts listed in the sequence's canonical rotation",
          d["impact_contacts"] == expand(d["sequence"]), (d["impact_contacts"], d["sequence"]))
    text = run(vibro, "orbit", scene_d, "--kind", "impact").stdout.splitlines()
    first = next((l for l in text if l.startswith("impacts")), "")
    check("scene D: the text lists contact 0's impact first", first.startswith("impacts      contact 0,"), first)
    h5 = os.path.join(tmp, "d.h5")
    p = run(vibro, "orbit", scene_d, "--kind", "impact", "--out", h5)
    check("scene D: orbit --out exits 0", p.returncode == 0, p.stderr.strip())
    listing_agrees_with_file("scene D", vibro, scene_d, d, h5)
    # Python, the same JSON.
    try:
        import vibro as pyvibro
        py = pyvibro.orbit(scene_d, kind="impact")
        check("scene D: Python lists the same impacts", py["impact_contacts"] == d["impact_contacts"] and
              py["impact_phases"] == d["impact_phases"] and py["section_time"] == d["section_time"],
              (py["impact_contacts"], py["section_time"]))
    except ImportError as e:
        check("scene D: the Python package imports", False, e)

    # One contact: the listing starts at the first event after the section, as before.
    one = os.path.join(tmp, "one_contact.toml")
    with open(one, "w") as f:
        f.write(ONE_CONTACT)
    for name, scene in (("Fig. 5 [stop]", os.path.join(data_scenes, "fig05_coexistence.toml")),
                        ("one [[contact]]", one)):
        args = ["orbit", scene, "--kind", "impact"]
        p = run(vibro, *args, "--json")
        if p.returncode != 0:
            print(f"skip {name}: no impact orbit ({p.stderr.strip()})")
            continue
        dd = json.loads(p.stdout)
        h5 = os.path.join(tmp, "one.h5")
        run(vibro, *args, "--out", h5, "--force")
        listing_agrees_with_file(name, vibro, scene, dd, h5)

    # The corner: Lyapunov exponents and a branch say which piece they follow.
    corner = os.path.join(test_scenes, "contacts_symmetric_damped_corner.toml")
    p = run(vibro, "simulate", corner, "--set", "run.periods=200", "--json")
    check("corner: simulate exits 0", p.returncode == 0, p.stderr.strip())
    s = json.loads(p.stdout)
    note = s.get("lyapunov_corner", "")
    check("corner: lyapunov_corner names the corner and the piece followed",
          "contacts 0, 1" in note and "corner of the map" in note and "first order's piece" in note, note)
    text = run(vibro, "simulate", corner, "--set", "run.periods=200").stdout
    check("corner: simulate's text has a corner line after the lyapunov line",
          "\ncorner       a simultaneous impact of contacts 0, 1 at a corner of the map" in text)
    p = run(vibro, "continue", corner, "--kind", "impact", "--param", "excitation.frequency", "--to", "1.61", "--json")
    check("corner: continue exits 0", p.returncode == 0, p.stderr.strip()[-300:])
    b = json.loads(p.stdout) if p.stdout.strip() else {}
    note = b.get("corner", "")
    check("corner: the branch names the corner and the piece followed",
          "contacts 0, 1" in note and "at λ = " in note and "first order's piece" in note, note)

    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
