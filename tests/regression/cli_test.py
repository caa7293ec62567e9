#!/usr/bin/python3
"""Command-line tests of `vibro model` on every shipped scene, and of bad input (exit 2)."""
import json
import os
import subprocess
import sys
import tempfile

vibro, scenes = sys.argv[1], sys.argv[2]
failures = 0
passed = 0


def check(name, ok, detail=""):
    global failures, passed
    if ok:
        passed += 1
    else:
        failures += 1
        print(f"FAIL {name}: {detail}")


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

# `vibro simulate` with both engines on every scene.
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

# `vibro check` passes on every scene; `vibro orbit` on every periodic one (CONTRACT §2 fields).
for f in sorted(os.listdir(scenes)):
    if not f.endswith(".toml") or os.path.islink(os.path.join(scenes, f)):
        continue
    path = os.path.join(scenes, f)
    p = run("check", path, "--json")
    check(f"check {f} exit 0", p.returncode == 0, p.stdout + p.stderr)
    if p.returncode not in (0, 4):
        continue
    report = json.loads(p.stdout)
    check(f"check {f} ok", report["ok"], [r for r in report["rows"] if not r["ok"]])
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

print(f"{passed} passed, {failures} failed")
sys.exit(1 if failures else 0)
