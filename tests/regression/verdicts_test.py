#!/usr/bin/python3
"""Verdicts a ground truth can stand behind (docs/validation.md), through the real `vibro` binary:

- `vibro score` can fail. A naive fixed-step simulator (written here: RK4 with contacts seen only at
  the ends of its steps) steps over the low-speed contacts of data/benchmarks/grazing_near_1dof;
  the events vibro has and it missed are divergences, the first at vibro's first impact
  (t = 9.3965), exit 4. One stick of 21: matched fraction 1/21, exit 4, no "agrees".
- `score` checks its input before running anything: times beyond the scene's run (1e308, 1e9),
  decreasing or repeated times, duplicate columns, --window inf: exit 2 naming the row; a UTF-8
  BOM is dropped; /dev/zero is refused at once; a stop request while a CSV is read is answered
  within a second (exit 130).
- `vibro validate` judges the state as claimed: Fig. 8 rows with velocity −5 or −1e3 (the body
  0.0125 above the stop, the orbit's velocity +0.0575) are no-orbit-near, −1e308 is not a state
  (exit 2); a check simulation that ends undetermined is `undetermined`, with no hint of
  run.precision = "quad" where quad cannot run (it now runs every scene); a stop request during the preparation of 20 000
  or 100 000 rows is answered within a second with the JSON printed.
"""
import csv
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

vibro, scenes, scripts = sys.argv[1], sys.argv[2], sys.argv[3]
bench = os.path.join(os.path.dirname(scenes), "benchmarks")
fig8 = os.path.join(scenes, "fig08_preload.toml")
R0 = ["--set", "stop.restitution=0.0"]


def run(*args, timeout=600):
    return subprocess.run([vibro, *args], capture_output=True, text=True, timeout=timeout)


def write_rows(path, header, rows, prefix=""):
    with open(path, "w", newline="", encoding="utf-8") as f:
        f.write(prefix + ",".join(header) + "\n")
        for r in rows:
            f.write(",".join(str(x) for x in r) + "\n")


def naive_grazing(h):
    """A fixed-step RK4 integrator of data/benchmarks/grazing_near_1dof (Ẍ + X = f sin ωt, stop at
    x0 = −1, r = 0.8) that sees a contact only when a step ends below the stop: it steps over
    contacts whose penetration lasts less than a step, the low-speed contacts of this scene."""
    f, w, x0, r = 0.75007500000000005, 0.5, -1.0, 0.80000000000000004
    t_end = 20 * 2 * math.pi / w
    x, v = 0.0, 0.50004999999999999
    events = []

    def acc(t, x_):
        return -x_ + f * math.sin(w * t)

    for k in range(int(t_end / h)):
        t = k * h
        k1x, k1v = v, acc(t, x)
        k2x, k2v = v + h / 2 * k1v, acc(t + h / 2, x + h / 2 * k1x)
        k3x, k3v = v + h / 2 * k2v, acc(t + h / 2, x + h / 2 * k2x)
        k4x, k4v = v + h * k3v, acc(t + h, x + h * k3x)
        x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
        v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        if x < x0 and v < 0:
            events.append(((k + 1) * h, "impact", v))
            x, v = x0, -r * v
    return events


def proc_rchar(pid):
    try:
        with open(f"/proc/{pid}/io") as f:
            for line in f:
                if line.startswith("rchar:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return -1


def interrupt_when(p, ready, what, limit=1.5):
    """Waits (up to 300 s) until ready() holds, sends SIGINT and returns (exit code, seconds to
    exit, stdout)."""
    t0 = time.time()
    while not ready() and p.poll() is None and time.time() - t0 < 300:
        time.sleep(0.02)
    check(f"{what}: still running when interrupted", p.poll() is None, p.returncode)
    sent = time.time()
    p.send_signal(signal.SIGINT)
    try:
        out, _ = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        out, _ = p.communicate()
    took = time.time() - sent
    check(f"{what}: exit 130 within {limit} s", p.returncode == 130 and took < limit, (p.returncode, took))
    return p.returncode, took, out


with tempfile.TemporaryDirectory() as d:
    # ---- score can fail (issue 24 item 3) ----
    gscene = os.path.join(bench, "grazing_near_1dof.toml")
    with open(os.path.join(bench, "grazing_near_1dof.csv")) as f:
        reference = list(csv.DictReader(f))
    naive = naive_grazing(0.125)
    check("the naive simulator steps over the first contacts", len(naive) >= 1 and naive[0][0] > 30, naive)
    path = os.path.join(d, "naive.csv")
    write_rows(path, ["t", "kind", "velocity"], [(repr(t), k, repr(v)) for t, k, v in naive])
    p = run("score", gscene, path, "--json")
    check("score naive: exit 4", p.returncode == 4, (p.returncode, p.stderr))
    rep = json.loads(p.stdout) if p.stdout else {}
    div = rep.get("first_divergence") or {}
    t_first = float(reference[0]["t"])  # vibro's first impact, as the quad reference has it
    check("score naive: first divergence at vibro's first impact, which it missed",
          div.get("side") == "vibro" and div.get("kind") == "impact" and abs(div.get("t", 0) - t_first) < 1e-9,
          div)
    imp = next((k for k in rep.get("kinds", []) if k["kind"] == "impact"), {})
    check("score naive: vibro ran the whole scene (20 impacts)", imp.get("ours") == len(reference) == 20, imp)
    check("score naive: matched fraction below one half", imp.get("matched_fraction") is not None
          and imp["matched_fraction"] < 0.5 and imp["unmatched_ours"] >= 18 and rep.get("agrees") is False, imp)
    p = run("score", gscene, path)
    check("score naive table: says it diverges", p.returncode == 4 and "verdict: diverges" in p.stdout
          and "t = 9.3964948679" in p.stdout and "agrees" not in p.stdout, p.stdout)
    # The reference itself agrees, exit 0.
    p = run("score", gscene, os.path.join(bench, "grazing_near_1dof.csv"), "--json")
    check("score reference: exit 0, agrees", p.returncode == 0 and json.loads(p.stdout).get("agrees") is True,
          p.stdout[-400:] + p.stderr)

    # One stick of 21: chatter_1dof's reference with 20 of its 21 sticks removed.
    cscene = os.path.join(bench, "chatter_1dof.toml")
    with open(os.path.join(bench, "chatter_1dof.csv")) as f:
        rows = list(csv.DictReader(f))
    sticks = [i for i, r in enumerate(rows) if r["kind"] == "stick"]
    check("chatter_1dof has 21 sticks", len(sticks) == 21, len(sticks))
    kept = [r for i, r in enumerate(rows) if r["kind"] != "stick" or i == sticks[0]]
    path = os.path.join(d, "one_stick.csv")
    write_rows(path, ["t", "kind", "velocity"], [(r["t"], r["kind"], r["velocity"]) for r in kept])
    p = run("score", cscene, path, "--json")
    check("score 1 of 21 sticks: exit 4", p.returncode == 4, (p.returncode, p.stderr))
    rep = json.loads(p.stdout) if p.stdout else {}
    st = next((k for k in rep.get("kinds", []) if k["kind"] == "stick"), {})
    check("score 1 of 21 sticks: matched fraction 1/21", st.get("matched") == 1 and st.get("ours") == 21
          and abs((st.get("matched_fraction") or 0) - 1 / 21) < 1e-12 and st.get("unmatched_ours") == 20, st)
    p = run("score", cscene, path)
    line = next((x for x in p.stdout.splitlines() if x.startswith("stick")), "")
    check("score 1 of 21 sticks table: 4.8 % matched, no claim of agreement",
          "4.8" in line and "verdict: diverges" in p.stdout and "no divergence" not in p.stdout, p.stdout)

    # ---- score checks its input (issue 25) ----
    def bad_score(tag, text, expect, *extra, timeout=60, prefix=""):
        path = os.path.join(d, tag + ".csv")
        with open(path, "w", encoding="utf-8") as f:
            f.write(prefix + text)
        t0 = time.time()
        try:
            p = run("score", cscene, path, *extra, timeout=timeout)
        except subprocess.TimeoutExpired:
            check(f"score {tag}: exit 2 in time", False, "timed out")
            return None
        check(f"score {tag}: exit 2 naming {expect}", p.returncode == 2 and expect in p.stderr
              and len(p.stdout) == 0, (p.returncode, p.stderr[-600:], time.time() - t0))
        return p

    first = f"{rows[0]['t']},{rows[0]['kind']}\n"
    bad_score("t1e308", "t,kind\n" + first + "1e308,impact\n", "t1e308.csv:3: time 1e+308 is after the end")
    bad_score("t1e9", "t,kind\n" + first + "1e9,impact\n", "t1e9.csv:3: time 1000000000 is after the end")
    bad_score("before", "t,kind\n-5,impact\n" + first, "before.csv:2: time -5 is before the scene's start")
    bad_score("decreasing", "t,kind\n2.0,impact\n1.0,impact\n", "decreasing.csv:3: time 1 is earlier")
    bad_score("repeated", "t,kind\n1.0,impact\n1.0,impact\n", "repeated.csv:3: the same time and kind")
    bad_score("dupcol", "t,kind,t\n1.0,impact,1.0\n", "dupcol.csv:1:3: column 't' given twice")
    bad_score("window", "t,kind\n" + first, "--window inf: expected a finite positive number", "--window", "inf")
    # Equal times of different kinds are allowed (an accumulation point and its stick).
    path = os.path.join(d, "bom.csv")
    with open(os.path.join(bench, "chatter_1dof.csv"), encoding="utf-8") as f:
        text = f.read()
    with open(path, "w", encoding="utf-8") as f:
        f.write("\ufeff" + text)
    p = run("score", cscene, path, "--json")
    check("score: UTF-8 BOM dropped, equal times of an accumulation and its stick accepted",
          p.returncode == 0 and json.loads(p.stdout).get("agrees") is True, (p.returncode, p.stderr[-400:]))
    # Rows split across the reader's 64 KiB blocks: the reference interleaved with comment lines
    # of varied lengths (about 4 MB), CRLF line ends, no final line end: read as the plain file.
    path = os.path.join(d, "padded.csv")
    with open(os.path.join(bench, "chatter_1dof.csv"), encoding="utf-8") as f:
        lines = f.read().splitlines()
    with open(path, "w", encoding="utf-8", newline="") as f:
        for i, ln in enumerate(lines):
            f.write("#" + "p" * ((i * 7919) % 5000) + "\r\n" + ln + ("\r\n" if i + 1 < len(lines) else ""))
    check("padded CSV crosses many blocks", os.path.getsize(path) > (3 << 20), os.path.getsize(path))
    p = run("score", cscene, path, "--json")
    q = run("score", cscene, os.path.join(bench, "chatter_1dof.csv"), "--json")
    check("score: a CSV read across blocks gives the plain file's result", p.returncode == 0
          and p.stdout == q.stdout, (p.returncode, p.stderr[-300:]))
    t0 = time.time()
    try:
        p = run("score", cscene, "/dev/zero", timeout=60)
        check("score /dev/zero: exit 2 at once", p.returncode == 2 and "/dev/zero:1: a NUL byte" in p.stderr
              and time.time() - t0 < 30, (p.returncode, p.stderr))
    except subprocess.TimeoutExpired:
        check("score /dev/zero: exit 2 at once", False, "still reading after 60 s")

    # A stop request while a CSV is read (a FIFO fed without end): exit 130 within a second.
    def fifo_case(tag, header, args):
        fifo = os.path.join(d, tag + ".fifo")
        os.mkfifo(fifo)
        fed = [0]
        stop = threading.Event()

        def feed():
            try:
                with open(fifo, "w") as f:
                    f.write(header)
                    chunk = ("#" + "x" * 998 + "\n") * 64
                    while not stop.is_set():
                        f.write(chunk)
                        fed[0] += len(chunk)
            except (BrokenPipeError, OSError):
                pass

        p = subprocess.Popen([vibro, *args[:1], args[1], fifo, *args[2:]], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
        th = threading.Thread(target=feed, daemon=True)
        th.start()
        # Observable: vibro has read 4 MiB of the comment lines.
        interrupt_when(p, lambda: fed[0] > (4 << 20), f"{tag} reading a CSV")
        stop.set()

    fifo_case("score_fifo", "t,kind\n", ["score", cscene])
    fifo_case("validate_fifo", "value,time,displacement_1,velocity_1\n",
              ["validate", fig8, "--param", "excitation.amplitude"])

    # ---- validate judges the claimed state (issue 25) ----
    h5 = os.path.join(d, "b.h5")
    p = run("continue", fig8, *R0, "--param", "excitation.amplitude", "--to", "8", "--out", h5)
    check("continue fig8 r = 0", p.returncode == 0, p.stderr)
    out_csv = os.path.join(d, "b.csv")
    q = subprocess.run(["/usr/bin/python3", os.path.join(scripts, "branch_to_csv.py"), h5, out_csv],
                       capture_output=True, text=True)
    check("branch_to_csv", q.returncode == 0, q.stderr)
    with open(out_csv) as f:
        branch = list(csv.DictReader(f))
    row = dict(branch[1])
    check("the row: 0.0125 above the stop, velocity +0.06",
          abs(float(row["displacement_1"]) - 1.0131) < 1e-3 and 0.05 < float(row["velocity_1"]) < 0.07, row)
    for vel in ("-5", "-1e3"):
        r = dict(row, velocity_1=vel)
        path = os.path.join(d, f"v{vel}.csv")
        write_rows(path, list(r.keys()), [list(r.values())])
        p = run("validate", fig8, path, *R0, "--param", "excitation.amplitude", "--tolerance", "1e-12", "--json")
        j = json.loads(p.stdout) if p.stdout else {"points": [{}]}
        pt = j["points"][0]
        # The distance of the claimed state from the orbit at the same time: |Δẋ| / (1 + |z|∞).
        want = abs(float(vel) - float(row["velocity_1"])) / (1 + abs(float(row["displacement_1"])))
        check(f"validate velocity {vel}: no-orbit-near, exit 4", p.returncode == 4
              and pt.get("verdict") == "no-orbit-near", (p.returncode, pt, p.stderr))
        check(f"validate velocity {vel}: distance of the claim ({want:.4g})",
              pt.get("distance") is not None and abs(pt["distance"] - want) < 1e-6 * want, pt.get("distance"))
    r = dict(row, velocity_1="-1e308")
    path = os.path.join(d, "vhuge.csv")
    write_rows(path, list(r.keys()), [list(r.values())])
    try:
        p = run("validate", fig8, path, *R0, "--param", "excitation.amplitude", timeout=120)
        check("validate velocity -1e308: exit 2 naming the row", p.returncode == 2
              and "vhuge.csv:2: velocity_1 = -1e+308: not a state of the scene" in p.stderr,
              (p.returncode, p.stderr))
    except subprocess.TimeoutExpired:
        check("validate velocity -1e308: exit 2 naming the row", False, "still running after 120 s")
    # The rows as exported still confirm, at distances of rounding.
    p = run("validate", fig8, out_csv, *R0, "--param", "excitation.amplitude", "--json")
    j = json.loads(p.stdout) if p.stdout else {"points": []}
    check("validate the branch as exported: all confirmed", p.returncode == 0 and j["points"]
          and all(x["verdict"] == "confirmed" and x["distance"] < 1e-12 for x in j["points"]),
          (p.returncode, [(x["verdict"], x["distance"]) for x in j["points"] if x["verdict"] != "confirmed"]))

    # A stop request during the preparation of 20 000 and 100 000 rows (read, then each row's
    # scene): observable once the file is read; JSON printed, exit 130 within a second.
    for n in (20000, 100000):
        path = os.path.join(d, f"big{n}.csv")
        write_rows(path, list(branch[0].keys()), [list(branch[i % len(branch)].values()) for i in range(n)])
        size = os.path.getsize(path)
        p = subprocess.Popen([vibro, "validate", fig8, path, *R0, "--param", "excitation.amplitude", "--json"],
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        rc, took, out = interrupt_when(p, lambda: proc_rchar(p.pid) >= size, f"validate {n} rows")
        try:
            j = json.loads(out)
        except ValueError:
            j = None
        check(f"validate {n} rows interrupted: JSON printed", j is not None and "points" in j, out[-300:])

    # ---- validate names an undetermined check (issue 24 item 7) ----
    scene3 = os.path.join(d, "damped3.toml")
    with open(scene3, "w") as f:
        f.write("""[structure]
mass        = [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 0.5]]
stiffness   = [[2.5, -1.5, 0.0], [-1.5, 2.3, -0.8], [0.0, -0.8, 0.8]]
forcing_dof = 0
contact_dof = 2
damping_ratios = [0.02, 0.02, 0.02]
[stop]
position    = -0.5
restitution = 0.6
[excitation]
amplitude = 0.8
frequency = 0.3
[run]
periods = 500
""")
    h5 = os.path.join(d, "d3.h5")
    p = run("continue", scene3, "--param", "excitation.frequency", "--to", "0.6", "--out", h5, "--json")
    check("continue the damped 3-DOF chain", p.returncode == 0, p.stderr[-500:])
    out_csv = os.path.join(d, "d3.csv")
    subprocess.run(["/usr/bin/python3", os.path.join(scripts, "branch_to_csv.py"), h5, out_csv], check=False)
    with open(out_csv) as f:
        rows3 = list(csv.DictReader(f))
    last = os.path.join(d, "d3last.csv")
    write_rows(last, list(rows3[-1].keys()), [list(rows3[-1].values())])
    check("the last point is near ω = 0.4517236893", abs(float(rows3[-1]["value"]) - 0.4517236893) < 1e-6,
          rows3[-1]["value"])
    p = run("validate", scene3, last, "--param", "excitation.frequency", "--json")
    j = json.loads(p.stdout) if p.stdout else {"points": [{}]}
    pt = j["points"][0]
    check("validate at the end of sticking: undetermined, not stability-differs", p.returncode == 4
          and pt.get("verdict") == "undetermined" and j.get("undetermined") == 1 and j.get("disagreements") == 0,
          (p.returncode, pt))
    # The hint names only what can run: quad precision now runs damped sticking of several modes.
    q = run("simulate", scene3, "--set", f"excitation.frequency={rows3[-1]['value']}", "--set",
            'run.precision="quad"', "--set", "run.periods=20", "--set", "run.lyapunov=false")
    check("the hint suggests quad precision, and quad runs this scene",
          'Use run.precision = "quad"' in pt.get("detail", "") and "undetermined" in pt.get("detail", "")
          and q.returncode in (0, 3) and "no closed form" not in q.stderr, (pt.get("detail"), q.returncode, q.stderr[-300:]))

finish()
