#!/usr/bin/python3
"""Command-line tests: every command on the shipped scenes, their JSON and HDF5 output, and bad input (exit 2)."""
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

vibro, scenes = sys.argv[1], sys.argv[2]


def run(*args):
    return subprocess.run([vibro, *args], capture_output=True, text=True, timeout=300)


for f in sorted(os.listdir(scenes)):
    if not f.endswith(".toml"):
        continue
    path = os.path.join(scenes, f)
    p = run("model", path, "--json")
    check(f"model {f}", p.returncode == 0, p.stderr)
    if p.returncode == 0:
        j = json.loads(p.stdout)
        for key in ("frequencies", "forcing", "contact", "constrained_frequencies",
                    "static_reaction", "modes_kept"):
            check(f"model {f} has {key}", key in j, p.stdout)
        check(f"model {f} constrained count",
              len(j["constrained_frequencies"]) == j["modes_kept"] - 1, p.stdout)
    p = run("model", path)
    check(f"model {f} (text)", p.returncode == 0 and "frequencies" in p.stdout, p.stderr)
    # Every contact of the scene file (its [[contact]] tables, or the [stop] as one), with the
    # side, position and restitution written there (issue 37: contact 0 only was shown).
    import tomllib
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    tables = doc.get("contact", [])
    pj = run("model", path, "--json")
    if pj.returncode == 0 and tables:
        cs = json.loads(pj.stdout).get("contacts", [])
        check(f"model {f} --json lists every contact", len(cs) == len(tables) and all(
              c["side"] == t.get("side", "below") and c["position"] == t["position"] and
              c["restitution"] == t.get("restitution", 0.0) for c, t in zip(cs, tables)), (cs, tables))
        shown = [l for l in p.stdout.splitlines() if l.startswith("contact ") and not l.startswith("contact T_B")]
        check(f"model {f} (text) lists every contact",
              [l.split()[1] for l in shown] == [str(j) for j in range(len(tables))] and
              all(f"r {t.get('restitution', 0.0):g}" in l for l, t in zip(shown, tables)), p.stdout)

def several_contacts(path):
    """Whether the scene has two or more [[contact]] tables (docs/contacts.md)."""
    import tomllib
    with open(path, "rb") as fh:
        return len(tomllib.load(fh).get("contact", [])) > 1


def compliant(path):
    """A compliant stop (a stiffness on [stop] or a [[contact]], docs/compliant.md): `simulate` (both
    engines), `model` and `check` run it; the commands built on the rigid model refuse it before any
    computation."""
    with open(path, "rb") as fh:
        t = tomllib.load(fh)
    return "stiffness" in t.get("stop", {}) or any("stiffness" in c for c in t.get("contact", []))


def refused_compliant(tag, p):
    check(f"{tag}: a compliant stop refused, located, exit 2", p.returncode == 2 and "compliant stop" in p.stderr
          and p.stdout == "", p.stdout[-300:] + p.stderr[-300:])


# `validate` and `score` hold their scene apart from the other commands' (their own SCENE and
# --set): a compliant scene is refused by them too, before the CSV is read (they answered exit 4,
# `score` with the contact phases of the compliant stop as sticks and releases).
with tempfile.TemporaryDirectory() as d:
    import tomllib
    events = os.path.join(d, "events.csv")
    with open(events, "w") as fh:
        fh.write("t,kind\n0.05,impact\n")
    for f in sorted(os.listdir(scenes)):
        path = os.path.join(scenes, f)
        if not f.endswith(".toml") or not compliant(path):
            continue
        with open(path, "rb") as fh:
            structure = tomllib.load(fh)["structure"]
        n = len(structure.get("mass") or structure.get("frequencies"))
        branch = os.path.join(d, f"{f}.csv")
        with open(branch, "w") as fh:
            fh.write(",".join(["value", "time"] + [f"displacement_{i + 1}" for i in range(n)] +
                              [f"velocity_{i + 1}" for i in range(n)]) + "\n")
            fh.write(",".join(["1.0", "0.0"] + ["0.0"] * (2 * n)) + "\n")
        refused_compliant(f"validate {f}", run("validate", path, branch, "--param", "excitation.amplitude"))
        refused_compliant(f"score {f}", run("score", path, events))
        refused_compliant(f"score {f} --set", run("score", path, events, "--set", "run.periods=3"))

# A count option given a word: one short line naming the option (CLI::NonNegativeNumber wrote its
# range out to DBL_MAX, 330 characters).
fig5 = os.path.join(scenes, "fig05_coexistence.toml")
for args in (("orbit", fig5, "--transient", "x"), ("prove", fig5, "--transient", "x"),
             ("prove", fig5, "--bifurcation", "b.h5", "--point", "x"),
             ("continue", fig5, "--param", "excitation.amplitude", "--to", "2", "--transient", "-1")):
    p = run(*args)
    lines = p.stderr.strip().splitlines()
    check(f"{' '.join(args[:1] + args[2:])}: exit 2, one short line naming the option",
          p.returncode == 2 and lines and args[-2] in lines[0] and "integer" in lines[0] and len(lines[0]) < 120,
          p.stderr[:400])

# --bifurcation given neither a file nor KIND:KEY=VALUE: the option named, and both forms.
for spec in ("branch-point=nan", "branch-point:excitation.amplitude", "nofile.h5"):
    p = run("prove", fig5, "--bifurcation", spec)
    check(f"prove --bifurcation {spec}: exit 2 naming the option and both forms",
          p.returncode == 2 and p.stderr.startswith(f"--bifurcation {spec}:") and "KIND:KEY=VALUE" in p.stderr,
          p.stderr[:300])

# Several contacts: every command takes them; `prove` proves the orbit (exit 0) or says why not
# (exit 4, a reason docs/prove.md lists; prove.scenes checks each); simulate (either engine), orbit,
# continue and check run them.
for f in sorted(os.listdir(scenes)):
    path = os.path.join(scenes, f)
    if not f.endswith(".toml") or not several_contacts(path):
        continue
    if compliant(path):
        refused_compliant(f"prove {f}", run("prove", path))
        # `orbit` takes a compliant stop (docs/compliant.md, "Periodic orbits"): its contact phases and
        # the rigid model's orbit beside it.
        p = run("orbit", path, "--json")
        j = json.loads(p.stdout) if p.returncode == 0 else {}
        check(f"orbit {f}: a compliant orbit with its contact phases and the rigid model's orbit",
              p.returncode == 0 and j.get("status") == "converged" and j.get("contact_phases")
              and j.get("rigid_model", {}).get("status") == "converged", p.stdout[-300:] + p.stderr)
        continue
    p = run("prove", path)
    check(f"prove {f}: a verdict (proven, or not proven with its reason)",
          p.returncode in (0, 4) and p.stdout.startswith("verdict"), p.stdout[-300:] + p.stderr)
    # `orbit` takes them: the orbit each scene settles on, with its contact sequence.
    p = run("orbit", path, "--json")
    j = json.loads(p.stdout) if p.returncode == 0 else {}
    check(f"orbit {f} converges with a contact sequence", p.returncode == 0 and j.get("status") == "converged"
          and ":" in j.get("sequence", ""), p.stdout + p.stderr)
    p = run("simulate", path, "--json", "--set", "run.periods=20", "--set", "run.samples_per_period=0")
    j = json.loads(p.stdout) if p.returncode == 0 else {}
    check(f"simulate {f} per-contact counts", p.returncode == 0 and j.get("status") == "ok" and
          sum(c["impacts"] for c in j.get("contacts", [])) == j["counts"]["impacts"] and
          len(j["contacts"]) > 1, p.stdout + p.stderr)

# `vibro simulate` with both engines on every scene (several contacts too).
for f in sorted(os.listdir(scenes)):
    if not f.endswith(".toml"):
        continue
    path = os.path.join(scenes, f)
    for engine in ("exact", "cvode"):
        p = run("simulate", path, "--json", "--set", f'run.engine="{engine}"', "--set", "run.periods=20",
                "--set", "run.samples_per_period=0")
        check(f"simulate {f} {engine}", p.returncode == 0, p.stderr)
        if p.returncode == 0:
            j = json.loads(p.stdout)
            check(f"simulate {f} {engine} summary", j["status"] == "ok" and j["engine"] == engine
                  and set(j["counts"]) >= {"impacts", "accumulations", "sticks", "releases"}
                  and set(j["attractor"]) >= {"kind", "period", "impacts_per_period",
                                               "sticking_fraction", "stick_phases"}, p.stdout)
            check(f"simulate {f} {engine} solver stats", ("solver" in j) == (engine == "cvode"), p.stdout)

# `vibro check` passes on every scene; `vibro orbit` on every periodic one (docs/output.md fields).
# Several contacts: with 200 periods, so that the 2-DOF chain's transient (|μ| = 0.33) has reached
# its orbit within the 1e-9 the check asks of the Poincaré solver (docs/contacts.md).
for f in sorted(os.listdir(scenes)):
    if not f.endswith(".toml") or os.path.islink(os.path.join(scenes, f)):
        continue
    path = os.path.join(scenes, f)
    several = several_contacts(path)
    p = run("check", path, "--json", *(("--set", "run.periods=200") if several else ()))
    if several and p.returncode in (0, 4):
        rows = json.loads(p.stdout)["rows"]
        periodic = json.loads(p.stdout)["exact_kind"] in ("sticking-periodic", "impact-periodic")
        check(f"check {f} has its contact sequence", not periodic or
              any(r["quantity"] == "contact sequence" for r in rows), rows)
    check(f"check {f} exit 0", p.returncode == 0, p.stdout + p.stderr)
    if p.returncode not in (0, 4):
        continue
    report = json.loads(p.stdout)
    check(f"check {f} ok", report["ok"], [r for r in report["rows"] if not r["ok"]])
    if compliant(path):  # the exact engine against CVODE, and the Poincaré solver on a periodic attractor
        periodic = report["exact_kind"] in ("sticking-periodic", "contact-periodic", "impact-periodic")
        check(f"check {f}: compliant, the engines compared, the orbit solved when periodic",
              report["orbit_status"] == ("converged" if periodic else "not attempted")
              and report["cvode_kind"] == report["exact_kind"], report)
        continue
    if report["exact_kind"] != "sticking-periodic":
        continue
    p = run("orbit", path, "--json")
    check(f"orbit {f} exit 0", p.returncode == 0, p.stderr)
    if p.returncode == 0:
        j = json.loads(p.stdout)
        check(f"orbit {f} fields", {"status", "period", "sticking_fraction", "stick_phases",
                                    "impacts_per_period", "floquet_multipliers", "stable",
                                    "newton_iterations", "residual"} <= set(j), j)
        check(f"orbit {f} converged and stable", j["status"] == "converged" and j["stable"], j)

# `vibro check --precision quad`: the quad engine as a fourth opinion runs on every shipped scene
# (damped sticking of two or more modes included, docs/engines.md), agrees with the exact engine to
# 1e-9 where the attractor is periodic, and says so in the table and the JSON.
for f in sorted(os.listdir(scenes)):
    if not f.endswith(".toml") or os.path.islink(os.path.join(scenes, f)) or several_contacts(os.path.join(scenes, f)):
        continue
    p = run("check", os.path.join(scenes, f), "--precision", "quad", "--json")
    if compliant(os.path.join(scenes, f)):
        refused_compliant(f"check --precision quad {f}", p)
        continue
    check(f"check --precision quad {f} exit 0", p.returncode == 0, p.stdout + p.stderr)
    if p.returncode in (0, 4):
        report = json.loads(p.stdout)
        quad_rows = [r for r in report["rows"] if r.get("quad") is not None]
        periodic = report["exact_kind"] in ("sticking-periodic", "impact-periodic")
        check(f"check --precision quad {f} has quad values", report.get("quad_kind") == report["exact_kind"]
              and (len(quad_rows) >= 2 or not periodic)
              and all(abs(r["quad"] - r["exact"]) <= 1e-9 for r in quad_rows), report)
# The large scenes too (the 50-node beam: damped sticking of 49 constrained modes), over 2 periods.
large = os.path.join(scenes, "large")
for f in sorted(os.listdir(large)):
    if not f.endswith(".toml"):
        continue
    p = run("check", os.path.join(large, f), "--precision", "quad", "--set", "run.periods=2", "--json")
    check(f"check --precision quad large/{f} exit 0", p.returncode == 0, p.stdout + p.stderr)
    if p.returncode in (0, 4):
        report = json.loads(p.stdout)
        status = [r for r in report["rows"] if r["quantity"] == "status"]
        check(f"check --precision quad large/{f} ran the quad engine", report.get("quad_kind") == report["exact_kind"]
              and len(status) == 1 and "quad ok" in status[0]["note"], report)
# A period-2 sticking orbit: the Poincaré solver's record may start one forcing period later than the
# simulation's, so its stick phases read 2π less; they are the same orbit (phases compared mod 2π).
p = run("check", os.path.join(scenes, "fig05_coexistence.toml"), "--set", "stop.restitution=0.5",
        "--set", "excitation.amplitude=2", "--json")
check("check of a period-2 sticking orbit: phases agree modulo 2π", p.returncode == 0
      and json.loads(p.stdout)["exact_kind"] == "sticking-periodic", p.stdout[:600])
p = run("check", os.path.join(scenes, "fig08_preload.toml"), "--precision", "octuple")
check("check --precision octuple: exit 2", p.returncode == 2, p.stderr)

with tempfile.TemporaryDirectory() as d:
    h5 = os.path.join(d, "orbit.h5")
    p = run("orbit", os.path.join(scenes, "chain2.toml"), "--out", h5)
    check("orbit --out", p.returncode == 0 and os.path.exists(h5), p.stderr)
    p = run("plot", h5, "--out", os.path.join(d, "orbit"))
    check("plot of an orbit draws its multipliers",
          p.returncode == 0 and os.path.getsize(os.path.join(d, "orbit_multipliers.png")) > 5000, p.stderr)
    p = run("orbit", os.path.join(scenes, "chain3.toml"), "--json", "--kind", "impact", "--period", "1",
            "--set", "stop.restitution=0.5", "--set", "excitation.frequency=2.0", "--set",
            "excitation.amplitude=2.0")
    j = json.loads(p.stdout) if p.returncode == 0 else {}
    check("unstable impact orbit reported unstable", j.get("status") == "converged"
          and j.get("stable") is False and "impact_phases" in j
          and max(abs(complex(*m)) for m in j["floquet_multipliers"]) > 1, p.stdout + p.stderr)

# The least period (issue 40): --period 2 on Fig. 5 finds the period-1 orbit and says so. Truth: the
# period-1 orbit itself (--period 1): the same impact phase once per period, and its multipliers squared.
fig5 = os.path.join(scenes, "fig05_coexistence.toml")
p1 = run("orbit", fig5, "--json", "--kind", "impact", "--period", "1")
p2 = run("orbit", fig5, "--json", "--kind", "impact", "--period", "2")
j1 = json.loads(p1.stdout) if p1.returncode == 0 else {}
j2 = json.loads(p2.stdout) if p2.returncode == 0 else {}
ok = j1.get("status") == j2.get("status") == "converged"
if ok:
    mu1 = sorted((complex(*m) ** 2 for m in j1["floquet_multipliers"]), key=lambda z: (z.real, z.imag))
    mu2 = sorted((complex(*m) for m in j2["floquet_multipliers"]), key=lambda z: (z.real, z.imag))
    ok = (j1["period"] == j1["least_period"] == 1 and j2["period"] == 2 and j2["least_period"] == 1
          and len(j2["impact_phases"]) in (1, 2) and all(abs(x - j1["impact_phases"][0]) < 1e-8 for x in j2["impact_phases"])
          and len(mu1) == len(mu2) and all(abs(a - b) < 1e-8 for a, b in zip(mu1, mu2)))
check("orbit --period 2 on Fig. 5: the period-1 orbit, least_period 1 (JSON)", ok, p1.stdout + p2.stdout + p2.stderr)
p = run("orbit", fig5, "--kind", "impact", "--period", "2")
check("orbit --period 2 on Fig. 5: a 'least period 1' line", p.returncode == 0 and "least period 1:" in p.stdout, p.stdout)
p = run("orbit", fig5, "--kind", "impact", "--period", "1")
check("orbit --period 1: no 'least period' line", p.returncode == 0 and "least period" not in p.stdout, p.stdout)
p = run("orbit", os.path.join(scenes, "fig04_subharmonic.toml"), "--json")
j = json.loads(p.stdout) if p.returncode == 0 else {}
check("orbit on Fig. 4's period-2 orbit: least_period 2", j.get("period") == 2 and j.get("least_period") == 2,
      p.stdout + p.stderr)

# Studies: coexisting attractors of Fig. 5, the same for one and two threads; a basin map and its plot.
fig5 = os.path.join(scenes, "fig05_coexistence.toml")
outs = []
for threads in ("1", "2"):
    p = run("attractors", fig5, "--samples", "60", "--threads", threads, "--json", "--set", "run.periods=100")
    check(f"attractors --threads {threads}", p.returncode == 0, p.stderr)
    outs.append(p.stdout)
check("attractors: same answer for 1 and 2 threads", outs[0] == outs[1], outs)
j = json.loads(outs[0]) if outs[0] else {"attractors": []}
kinds = {(a["kind"], a["period"]) for a in j["attractors"]}
check("attractors: Fig. 5 sticking and single-impact orbits",
      ("sticking-periodic", 1) in kinds and ("impact-periodic", 1) in kinds, kinds)
check("attractors: fields", all({"kind", "period", "impacts_per_period", "sticking_fraction", "stick_phases",
                                 "basin_fraction", "basin_fraction_error", "example_initial_state"} <= set(a)
                                for a in j["attractors"]) and "unresolved_fraction" in j, j)
with tempfile.TemporaryDirectory() as d:
    h5 = os.path.join(d, "basin.h5")
    p = run("basin", fig5, "--grid", "12,10", "--out", h5, "--set", "run.periods=60")
    check("basin --out", p.returncode == 0 and os.path.exists(h5), p.stderr)
    p = run("plot", h5, "--out", os.path.join(d, "b"))
    check("basin plot", p.returncode == 0 and os.path.getsize(os.path.join(d, "b_basin.png")) > 5000, p.stderr)
    p = run("basin", fig5, "--x", "X7", "--grid", "2,2")
    check("basin: bad coordinate exit 2", p.returncode == 2 and "X7" in p.stderr, p.stderr)

# Continuation and partitions: JSON fields (docs/output.md and the extensions), the HDF5 file and
# its plot, the 1-DOF existence boundary f_ff(ω, 1) = √(1 + ω² tan²(π/ω)) (docs/model.md §6.3), bad input.
fig8 = os.path.join(scenes, "fig08_preload.toml")
p = run("continue", fig8, "--set", "stop.restitution=0.0", "--param", "excitation.amplitude",
        "--to", "8", "--json")
check("continue exit 0", p.returncode == 0, p.stderr)
br = json.loads(p.stdout) if p.returncode == 0 else {}
check("continue fields", {"status", "points", "bifurcations", "end"} <= set(br)
      and all({"value", "sticking_fraction", "stick_phases", "stable", "floquet_multipliers", "events"}
              <= set(pt) for pt in br.get("points", []))
      and all({"kind", "value", "detail", "bracket"} <= set(b) for b in br.get("bifurcations", [])), br)
fff = (1 + 2.8 ** 2 * __import__("math").tan(__import__("math").pi / 2.8) ** 2) ** 0.5
check("continue ends at f_ff(2.8, 1)", br.get("end") == "sticking-lost"
      and abs(br["bifurcations"][-1]["value"] - fff) < 1e-9, br.get("bifurcations"))
with tempfile.TemporaryDirectory() as d:
    h5 = os.path.join(d, "branch.h5")
    p = run("continue", fig8, "--set", "stop.restitution=0.0", "--param", "excitation.amplitude",
            "--to", "8", "--out", h5)
    check("continue --out", p.returncode == 0 and os.path.exists(h5), p.stderr)
    import h5py
    with h5py.File(h5, "r") as f:
        b = f["branch"]
        check("branch file matches the JSON", len(b["value"]) == len(br.get("points", []))
              and b.attrs["param"] == "excitation.amplitude" and b.attrs["end"] == "sticking-lost"
              and abs(f["bifurcations/value"][-1] - fff) < 1e-9
              and f["bifurcations/kind"][-1].decode() == "sticking-lost"
              and f.attrs["status"] == "ok", dict(b.attrs))
    p = run("plot", h5, "--out", os.path.join(d, "c"))
    check("branch plot", p.returncode == 0 and os.path.getsize(os.path.join(d, "c_branch.png")) > 5000, p.stderr)
    p = run("continue", fig8, "--param", "excitation.amplitude", "--to", "2", "--out", "/proc/nope.h5")
    check("continue: unwritable --out exit 2", p.returncode == 2 and "nope.h5" in p.stderr, p.stderr)
    h5 = os.path.join(d, "part.h5")
    p = run("partition", fig8, "--set", "stop.restitution=0.0", "--params",
            "excitation.frequency,excitation.amplitude", "--range1", "2.8,5", "--steps1", "1",
            "--range2", "1.05,12", "--from2", "1.5", "--sticking-fraction", "0.5", "--json", "--out", h5)
    check("partition exit 0", p.returncode == 0, p.stderr)
    part = json.loads(p.stdout) if p.returncode == 0 else {"columns": []}
    for col in part["columns"]:
        w = col["value1"]
        top = (1 + w * w * __import__("math").tan(__import__("math").pi / w) ** 2) ** 0.5
        lost = [b["value"] for b in col["bifurcations"] if b["kind"] == "sticking-lost"]
        check(f"partition column {w}: f_ff", col["status"] == "ok" and lost
              and abs(max(lost) - top) < 1e-9 and len(col["crossings"]) >= 1, col)
    check("partition: two columns", len(part["columns"]) == 2, part)
    p = run("plot", h5, "--out", os.path.join(d, "p"))
    check("partition plot", p.returncode == 0 and os.path.getsize(os.path.join(d, "p_partition.png")) > 5000, p.stderr)
    p = run("partition", fig8, "--params", "excitation.frequency,excitation.amplitude", "--range1", "5,2",
            "--range2", "1,3", "--sticking-fraction", "1.5", "--out", os.path.join(d, "bad.h5"))
    check("partition: bad input exit 2, both problems, nothing written",
          p.returncode == 2 and "--range1" in p.stderr and "1.5" in p.stderr
          and not os.path.exists(os.path.join(d, "bad.h5")), p.stderr)

# Three mistakes: three located messages, exit 2, nothing on stdout.
with tempfile.TemporaryDirectory() as d:
    bad = os.path.join(d, "bad.toml")
    with open(bad, "w") as out:
        out.write("[structure]\nfrequencies = [1.0]\nforcing = [1.0]\ncontact = [1.0]\n"
                  "[stop]\nposition = 1.0\nrestitution = 1.5\n"
                  "[excitation]\namplitude = -2.0\nfrequency = 2.8\n[run]\nchater = \"none\"\n")
    p = run("model", bad, "--json")
    check("bad scene exit 2", p.returncode == 2, p.returncode)
    lines = [l for l in p.stderr.splitlines() if l.startswith(bad + ":")]
    check("bad scene three messages", len(lines) == 3, p.stderr)
    check("bad scene no stdout", p.stdout == "", p.stdout)
    p = run("model", os.path.join(d, "missing.toml"))
    check("missing file exit 2", p.returncode == 2, p.stderr)
    p = run("model", os.path.join(scenes, "chain2.toml"), "--set", "stop.restitution=2",
            "--set", "excitation.frequency=-1")
    check("--set errors exit 2", p.returncode == 2 and p.stderr.count("--set") >= 2, p.stderr)
    p = run("model", os.path.join(scenes, "chain2.toml"), "--json", "--set",
            "structure.modes=1")
    check("--set modes", p.returncode == 0 and json.loads(p.stdout)["modes_kept"] == 1, p.stderr)
    p = run("frobnicate")
    check("unknown command exit 2", p.returncode == 2, p.returncode)

# Quiet, exact messages: only what applies is printed; zeros print as 0; inputs are echoed as given.
chain3, fig05 = os.path.join(scenes, "chain3.toml"), os.path.join(scenes, "fig05_coexistence.toml")
p = run("orbit", chain3)
status = p.stdout.splitlines()[0] if p.stdout else ""
check("orbit from the default start: status without a warning, the distance as information",
      status == "status       converged" and "from start   distance 0.225 (after a transient of 200 periods)" in p.stdout,
      p.stdout)
p = run("orbit", fig05, "--set", "initial.time=0.51387", "--set", "initial.displacement=[1.0]",
        "--set", "initial.velocity=[0.27569]")
check("orbit from a chosen start it does not pass through: says so",
      "converged at distance 0.119 from the start state" in p.stdout and "not one through it" in p.stdout, p.stdout)
# Fig. 5 at r = 0.8, f = 3: impacts, one plastic-free stick and no accumulation point.
p = run("simulate", fig05, "--set", "stop.restitution=0.8", "--set", "excitation.amplitude=3")
check("simulate without a chattering sequence: no chattering line",
      p.returncode == 0 and "0 accumulations" in p.stdout and "chattering" not in p.stdout, p.stdout)
p = run("simulate", os.path.join(scenes, "default.toml"))
check("simulate with chattering: the chattering line", "chattering   200 accumulation points predicted" in p.stdout,
      p.stdout)
# s_A = Σ_i ψ_i(B) ψ_i(A) / m_i = (M⁻¹)_BA = 0 exactly for a lumped chain forced and stopped at
# different masses (diagonal M).
for name in ("chain2.toml", "chain3.toml", "chain10_stiff.toml", "large/beam50.toml"):
    p = run("model", os.path.join(scenes, name))
    check(f"model {name}: s_A printed as 0 (lumped masses)", "s_A, s_B            0, 1\n" in p.stdout, p.stdout)
# A plastic impact (r = 0) of a 2-DOF impact orbit: the saltation matrix is singular, so the
# monodromy matrix has an exact multiplier 0 (computed as ~1e-18).
p = run("orbit", os.path.join(scenes, "chain2.toml"), "--set", "stop.restitution=0", "--set", "excitation.frequency=2.0",
        "--set", "excitation.amplitude=4", "--kind", "impact", "--period", "1")
mu = next((l for l in p.stdout.splitlines() if l.startswith("multipliers")), "")
check("orbit with an exact zero multiplier: printed as 0 (|μ| = 0), no 1e-18",
      ", 0 (|μ| = 0)" in mu and "e-1" not in mu, mu)
p = run("simulate", os.path.join(scenes, "fig08_preload.toml"), "--set", "stop.restitution=2.3")
check("an input is echoed as given: 2.3, not 2.2999999999999998",
      p.returncode == 2 and "stop.restitution = 2.3:" in p.stderr and "2.29999" not in p.stderr, p.stderr)
p = run("sweep", os.path.join(scenes, "fig08_preload.toml"), "--param", "stop.restitution", "--from", "0.3",
        "--to", "2.3")
check("a sweep bound is echoed as given: --to 2.3",
      p.returncode == 2 and "--to 2.3 (--param stop.restitution)" in p.stderr and "2.29999" not in p.stderr, p.stderr)

# Issue 24: the edges a user reaches.
tests_scenes = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scenes")
chain2 = os.path.join(scenes, "chain2.toml")
# --guess starts Newton at the guess: Fig. 5's unstable one-impact orbit from its exact impact
# state (phase, ẋ_B after the impact) converges to that state (a 200-period transient from there
# reaches the sticking orbit instead).
phase, v_after = 5.138714103028858, 0.2756851049583854
p = run("orbit", os.path.join(scenes, "fig05_coexistence.toml"), "--kind", "impact", "--guess",
        f"{phase!r},{v_after!r}", "--json")
check("orbit --guess converges at the guess", p.returncode == 0, p.stdout + p.stderr)
if p.returncode == 0:
    j = json.loads(p.stdout)
    check("orbit --guess: the unstable impact orbit through the guess",
          j["status"] == "converged" and j["stable"] is False and len(j["impact_phases"]) == 1
          and abs(j["impact_phases"][0] - phase) < 1e-9
          and abs(j["impact_velocities"][0] + v_after / 0.75) < 1e-9, p.stdout)
# A refused attempt after a transient suggests --transient 0 first.
p = run("orbit", chain2, "--kind", "impact", "--transient", "20")
check("orbit hint: --transient 0 first", p.returncode != 0 and "--transient 0" in p.stderr
      and p.stderr.index("--transient 0") < p.stderr.index("--guess"), p.stderr)
# A release state of the chain with a rounding residue ẋ_B = −2.8e-17 is at rest on the stop;
# moving into the stop (−1e-9) it stays refused.
for vB, code in (("-2.8e-17", 0), ("-1e-9", 2)):
    p = run("simulate", chain2, "--json", "--set", "initial.displacement=[0.4375, 1.0]",
            "--set", f"initial.velocity=[0.6251, {vB}]", "--set", "run.periods=2")
    check(f"initial state on the stop with ẋ_B = {vB}: exit {code}", p.returncode == code, p.stderr)
# The default start at rest on the stop sticks from t = 0 (it rounded 1 ulp above the stop).
p = run("simulate", os.path.join(tests_scenes, "modal3_preload.toml"), "--json")
# Over its one period: the stick at t = 0, the release, one impact at 9.8 (no chattering sequence
# at t = 6.4e-9 any more).
check("modal 3-DOF preload: sticks from t = 0",
      p.returncode == 0 and json.loads(p.stdout)["counts"] == {"impacts": 1, "accumulations": 0, "sticks": 1,
                                                               "releases": 1, "grazings": 0},
      p.stdout + p.stderr)
# A long period is found by recurrence of the section, the search limit said.
p = run("simulate", os.path.join(tests_scenes, "damped3_clearance.toml"), "--json", "--set",
        "excitation.amplitude=0.5", "--set", "excitation.frequency=0.7", "--set", "run.periods=100000",
        "--set", "run.samples_per_period=0")
if p.returncode == 0:
    a = json.loads(p.stdout)["attractor"]
    check("period 136 by recurrence", a["kind"] == "not-periodic" and a["searched_period"] == 32
          and a["recurrence_period"] == 136 and a["recurrence_distance"] < 1e-10, a)
else:
    check("simulate damped 3-DOF 1e5 periods", False, p.stderr)
# Near the end of sticking (f_max = 1.2062880835761711 for the chain at ω = 0.8): orbit takes
# the quad fallback; CVODE at rtol 1e-12 ends undetermined (exit 3), not numerical-failure.
f_max = 1.2062880835761711
for df in (1e-10, 1e-11):
    p = run("orbit", chain2, "--json", "--set", f"excitation.amplitude={f_max - df!r}")
    j = json.loads(p.stdout) if p.stdout else {}
    check(f"orbit at f_max - {df}: converged with quad evaluations",
          p.returncode == 0 and j.get("status") == "converged" and j.get("quad_evaluations", 0) > 0,
          p.stdout + p.stderr)
for df in (-1e-8, 1e-8):
    p = run("simulate", chain2, "--json", "--set", f"excitation.amplitude={f_max + df!r}",
            "--set", 'run.engine="cvode"', "--set", "run.rtol=1e-12", "--set", "run.samples_per_period=0")
    j = json.loads(p.stdout) if p.stdout else {}
    check(f"cvode at f_max {df:+g}: undetermined", p.returncode == 3 and j.get("status") == "undetermined",
          p.stdout + p.stderr)

# Several contacts closing at one instant with W_01 ≠ 0: the orbit is found, and says it has no
# Jacobian (the map is discontinuous there) instead of printing multipliers (docs/contacts.md).
coupled = os.path.join(tests_scenes, "contacts_coupled_simultaneous.toml")
no_jacobian = "the orbit passes through a simultaneous impact of coupled contacts: the map has no Jacobian there"
p = run("orbit", coupled)
check("orbit through coupled simultaneous impacts (text)", p.returncode == 0 and "sequence     0+1:impact" in p.stdout
      and f"multipliers  none: {no_jacobian}" in p.stdout and "stable       -" in p.stdout, p.stdout + p.stderr)
with tempfile.TemporaryDirectory() as d:
    out = os.path.join(d, "orbit.h5")
    p = run("orbit", coupled, "--json", "--out", out)
    j = json.loads(p.stdout) if p.returncode == 0 else {}
    check("orbit through coupled simultaneous impacts (JSON)", j.get("status") == "converged" and
          j.get("no_jacobian") == no_jacobian and j.get("floquet_multipliers") == [] and j.get("stable") is None
          and j.get("sequence") == "0+1:impact", p.stdout + p.stderr)
    if p.returncode == 0:
        import h5py
        with h5py.File(out, "r") as f:
            a = f["orbit"].attrs
            seq = a.get("sequence")
            seq = seq.decode() if isinstance(seq, bytes) else seq
            nj = a.get("no_jacobian")
            nj = nj.decode() if isinstance(nj, bytes) else nj
            check("orbit --out: /orbit@sequence and @no_jacobian", seq == "0+1:impact" and nj == no_jacobian and
                  a["multipliers"].shape == (0, 2), dict(a))

finish()
