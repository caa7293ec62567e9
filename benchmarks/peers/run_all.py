#!/usr/bin/python3
"""vibro and its peers side by side in one run: vibro (exact engine, CVODE), SciPy solve_ivp with
events (scipy_peer.py) and Siconos Moreau–Jean time-stepping with its forcing compiled as a plugin
(siconos_peer.py), each over its own settings, on the same scenes (Fig. 8 and 5, the 1-DOF scenes
without chattering, the chains, the several-contact scenes).

Every run is a process of its own (peer_process.py, or `vibro simulate` itself), timed two ways:
  * whole process: the CPU (user + system, rusage of the child) of the whole process, interpreter
    start-up and imports included for the peers, vibro's start-up for `vibro simulate` (asked for
    what the peers compute, the events and the end state: no samples, no Lyapunov exponents);
  * call: the CPU of the engine's call inside that process (the peers' Python call with its model
    set-up; for vibro the Python module's `vibro.simulate` on a scene loaded beforehand).
Ratios are taken whole process against whole process and call against call, each against vibro's
exact engine with default settings on the same scene; `call_vs_whole` is a peer's call against a
whole vibro process (the issue's target: ≥ 100× at equal or better accuracy). vibro's times are
medians over `--vibro-repeat` processes (calls), the peers' over `--repeat` runs; the CSV keeps the
smallest and the largest for the spread.

Each scene is run for --periods forcing periods (default 20) from the scene's initial state (the
static preload equilibrium when it has none); the peers get the modal model (problem.py).
Accuracy is measured against vibro's exact engine with chatter_switch = 1e-9 (the reference):
  * event_error: the largest difference of the first 12 stick and release times, relative to the
    forcing period T, each compared with the same contact's milestone of the same rank (a milestone
    missed at one contact does not shift the others'), over the events a failed run did reach;
  * state_error: the largest difference of the modal displacements and velocities at t_end.

Usage: /usr/bin/python3 benchmarks/peers/run_all.py [--vibro build/vibro] [--out docs/peers]
       [--periods 20] [--scenes a.toml,b.toml] [--quick] [--event-driven] [--replot]
Writes PREFIX.csv (one row per run), PREFIX.json (when, from which commit and binary, the command
line, the machine's load), PREFIX.png (error against CPU time per scene, whole processes and calls)
and prints the table of docs/peers.md (table.py). Needs Debian's
python3-scipy, python3-siconos, python3-h5py, python3-matplotlib and vibro's Python module
(build/python). About 10 minutes; --quick: a smoke run of one setting per engine on two scenes.
"""
import argparse
import csv
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.dirname(HERE))
from bench_common import DEFAULT_VIBRO, ROOT, fmt, pyplot, save_figure, write_csv  # noqa: E402
import siconos_peer  # noqa: E402
import table  # noqa: E402
from problem import Problem  # noqa: E402

SCENES = [
    ("Fig. 8 (1-DOF, r = 0.75)", "fig08_preload.toml"),
    ("Fig. 5 (1-DOF, r = 0.75)", "fig05_coexistence.toml"),
    ("Fig. 11 (1-DOF clearance, r = 0)", "fig11_clearance.toml"),
    ("Fig. 4 (1-DOF, r = 0, q = 2)", "fig04_subharmonic.toml"),
    ("2-DOF chain (r = 0.5)", "chain2.toml"),
    ("2-DOF chain, 2 % damping", "chain2_damped.toml"),
    ("3-DOF chain (r = 0)", "chain3.toml"),
    ("two-sided 1-DOF (2 contacts)", "contacts_two_sided_1dof.toml"),
    ("seat and lift stop, 1-DOF (2 contacts)", "contacts_preload_clearance_1dof.toml"),
    ("2-DOF chain, 2 stops", "contacts_chain2.toml"),
    ("impact pair (2 contacts, damped)", "contacts_impact_pair.toml"),
    ("3-node beam, 5 contacts (damped)", "contacts_beam3.toml"),
]
QUICK_SCENES = ["fig08_preload.toml", "contacts_two_sided_1dof.toml"]
WALL = 60.0  # seconds of wall time after which a peer run that has not finished stops ("gave up")
PYTHON = "/usr/bin/python3"


def settings(quick, event_driven, plugin, m):
    """(engine, setting label, kind, args) for one scene."""
    # vibro computes what the peers compute: the events and the end state (no samples, no file, no
    # Lyapunov exponents, which the peers do not compute).
    same_work = ["run.lyapunov=false"]
    out = [("vibro exact", "defaults", "vibro", ['run.engine="exact"'] + same_work)]
    for rtol in ([1e-6, 1e-8, 1e-10, 1e-12] if not quick else [1e-8]):
        out.append(("vibro CVODE", f"Adams rtol {rtol:g}", "vibro",
                    ['run.engine="cvode"', 'run.method="adams"', f"run.rtol={rtol:g}", f"run.atol={rtol * 1e-2:g}"]
                    + same_work))
    for rtol in ([1e-6, 1e-8, 1e-10, 1e-12] if not quick else [1e-10]):
        out.append(("SciPy DOP853", f"rtol {rtol:g}, plastic below 1e-6", "scipy",
                    dict(rtol=rtol, plastic_below=1e-6, wall_limit=WALL)))
    for steps in ([100, 1000, 10000] if not quick else [1000]):
        out.append(("Siconos Moreau–Jean", f"h = T/{steps}", "mj", dict(steps_per_period=steps, plugin=plugin)))
    if event_driven and m == 1:
        for rtol, td in [(None, 16), (1e-6, 16), (1e-8, 16), (1e-10, 16), (1e-8, 256)]:
            tol = f"rtol = atol = {rtol:g}" if rtol else "default tolerances (rtol 10ε, atol 100ε)"
            out.append(("Siconos event-driven", f"LSODAR {tol}, TOL_ED 1e-6, h = T/{td}", "ed",
                        dict(rtol=rtol, tol_ed=1e-6, td_steps=td, wall_limit=WALL, plugin=plugin)))
    return out


def children_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(cmd):
    """(CompletedProcess, CPU seconds of the whole child process)."""
    c0 = children_cpu()
    p = subprocess.run(cmd, capture_output=True, text=True)
    return p, children_cpu() - c0


def spread(values):
    v = sorted(values)
    return v[len(v) // 2], v[0], v[-1]


def run_process(spec, repeat):
    """Runs peer_process.py SPEC `repeat` times; (result of the first run, whole-process CPUs,
    call CPUs)."""
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as fh:
        json.dump(spec, fh)
    first, whole, call = None, [], []
    try:
        for _ in range(repeat):
            p, c = timed([PYTHON, os.path.join(HERE, "peer_process.py"), fh.name])
            if p.returncode != 0 or not p.stdout.strip():
                return {"status": f"process failed: {p.stderr.strip()[-300:]}"}, [c], [float("nan")]
            out = json.loads(p.stdout.strip().splitlines()[-1])
            first = first or out
            whole.append(c)
            call.append(out["call_cpu"])
            if out.get("wall", 0) > 10:  # a long run: once is enough to time it
                break
    finally:
        os.unlink(fh.name)
    return first, whole, call


def vibro_whole(vibro, scene, periods, sets, repeat):
    """CPU of whole `vibro simulate --json` processes (no file, as the peers write none; no samples and
    no Lyapunov exponents, which the peers do not compute: `sets`)."""
    cmd = [vibro, "simulate", os.path.join(ROOT, "data", "scenes", scene) if os.sep not in scene else scene,
           "--json", "--set", f"run.periods={periods}", "--set", "run.samples_per_period=0"]
    for s in sets:
        cmd += ["--set", s]
    out = []
    for _ in range(repeat):
        p, c = timed(cmd)
        if p.returncode not in (0, 3):
            return [float("nan")]
        out.append(c)
    return out


def measure(args, p, scene, kind, arg, plugin):
    """(result dict, whole-process CPUs, call CPUs) of one setting."""
    if kind == "vibro":
        spec = {"engine": "vibro", "scene": os.path.join(ROOT, "data", "scenes", scene), "sets": arg,
                "periods": args.periods, "python_dir": args.python_dir, "repeat": args.vibro_repeat,
                "t_end": p.t_end}
        res, _, call = run_process(spec, 1)
        whole = vibro_whole(args.vibro, scene, args.periods, arg, args.vibro_repeat)
        lo_hi = (res.get("call_cpu_min", float("nan")), res.get("call_cpu_max", float("nan")))
        return res, whole, call, lo_hi
    spec = {"engine": kind, "problem": p.to_dict(), "args": arg}
    res, whole, call = run_process(spec, args.repeat)
    return res, whole, call, None


def event_error(times, contacts, ref, T):
    """Largest |t − t_ref| / T over the reference's first 12 milestones, rank by rank per contact;
    NaN when the run reached none of them."""
    worst, compared = float("nan"), 0
    for j in sorted(set(c for _, c in ref)):
        mine = [t for t, c in zip(times, contacts) if c == j]
        theirs = [t for t, c in ref if c == j]
        for a, b in zip(mine, theirs):
            d = abs(a - b) / T
            worst = d if compared == 0 else max(worst, d)
            compared += 1
    return worst, compared


def state_error(end, ref_end):
    if end is None or ref_end is None:
        return float("nan")
    return float(max(np.max(np.abs(np.array(end[0]) - ref_end[0])), np.max(np.abs(np.array(end[1]) - ref_end[1]))))


def reference(vibro, scene, periods, t_end):
    import h5py  # noqa: PLC0415
    with tempfile.TemporaryDirectory() as d:
        h5 = os.path.join(d, "ref.h5")
        cmd = [vibro, "simulate", os.path.join(ROOT, "data", "scenes", scene), "--out", h5,
               "--set", f"run.periods={periods}", "--set", "run.samples_per_period=0",
               "--set", 'run.engine="exact"', "--set", "run.chatter_switch=1e-9"]
        pr = subprocess.run(cmd, capture_output=True, text=True)
        if pr.returncode != 0:
            raise RuntimeError(f"{scene}: the reference run failed: {pr.stderr}")
        with h5py.File(h5, "r") as f:
            t, k, c = f["events/t"][:], f["events/kind"][:], f["events/contact"][:]
            ms = [(float(x), int(j)) for x, y, j in zip(t, k, c) if y in (3, 4)][:12]
            st, sX, sV = f["section/t"][:], f["section/X"][:], f["section/V"][:]
    i = int(np.argmin(np.abs(st - t_end)))
    end = (sX[i], sV[i]) if abs(st[i] - t_end) <= 1e-9 * max(1.0, t_end) else None
    return ms, end


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vibro", default=DEFAULT_VIBRO)
    ap.add_argument("--python-dir", default=None, help="vibro's Python package (default: build/python beside --vibro)")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "peers"))
    ap.add_argument("--periods", type=int, default=20)
    ap.add_argument("--scenes", default=None, help="comma-separated scene files (default: all of SCENES)")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each peer setting (a run over 10 s: one)")
    ap.add_argument("--vibro-repeat", type=int, default=15, help="vibro processes (and calls) per setting")
    ap.add_argument("--quick", action="store_true", help="one setting per engine on two scenes (a smoke run)")
    ap.add_argument("--event-driven", action="store_true", help="also Siconos' event-driven scheme (one contact)")
    ap.add_argument("--replot", action="store_true", help="only redraw PREFIX.png from PREFIX.csv")
    args = ap.parse_args()
    args.vibro = os.path.abspath(args.vibro)
    args.python_dir = args.python_dir or os.path.join(os.path.dirname(args.vibro), "python")
    if args.quick:
        args.repeat, args.vibro_repeat = 1, 3
    names = dict((f, lab) for lab, f in SCENES)
    scenes = ([(names.get(s, s), s) for s in args.scenes.split(",")] if args.scenes else
              [(names[s], s) for s in QUICK_SCENES] if args.quick else SCENES)
    if args.replot:
        with open(args.out + ".csv", newline="") as fh:
            rows = list(csv.DictReader(fh))
        provenance = None
        if os.path.exists(args.out + ".json"):
            with open(args.out + ".json") as fh:
                provenance = json.load(fh)
        plot(rows, list(dict.fromkeys(r["scene"] for r in rows)), args.out + ".png", provenance)
        return
    plugin = siconos_peer.build_plugin()
    provenance = run_provenance(args)
    print(f"run of {provenance['date']} at commit {provenance['commit']} ({provenance['vibro_version']}), "
          f"load {provenance['load_start']}", flush=True)
    rows = []
    for label, scene in scenes:
        p = Problem.from_vibro(args.vibro, scene, label, periods=args.periods)
        ref_ms, ref_end = reference(args.vibro, scene, p.periods, p.t_end)
        base = None
        print(f"== {label} ({scene}, {p.n} mode(s), {p.m} contact(s), {p.periods} periods)", flush=True)
        for engine, setting, kind, arg in settings(args.quick, args.event_driven, plugin, p.m):
            res, whole, call, vibro_call_range = measure(args, p, scene, kind, arg, plugin)
            w, w_lo, w_hi = spread(whole)
            c, c_lo, c_hi = spread(call)
            if vibro_call_range:
                c_lo, c_hi = vibro_call_range
            if base is None:
                base = (w, c)
            err, n_ms = event_error(res.get("times", []), res.get("contacts", []), ref_ms, p.T)
            st = state_error(res.get("end"), ref_end)
            status = res.get("status", "?")
            rows.append({"scene": label, "scene_file": scene, "engine": engine, "setting": setting,
                         "whole_cpu_s": fmt(w, ".5f"), "whole_cpu_min_s": fmt(w_lo, ".5f"),
                         "whole_cpu_max_s": fmt(w_hi, ".5f"), "runs": len(whole),
                         "call_cpu_s": fmt(c, ".6f"), "call_cpu_min_s": fmt(c_lo, ".6f"),
                         "call_cpu_max_s": fmt(c_hi, ".6f"),
                         "whole_ratio": fmt(w / base[0], ".3g"), "call_ratio": fmt(c / base[1], ".3g"),
                         "call_vs_whole": fmt(c / base[0], ".3g"),
                         "event_error": fmt(err, ".2e"), "n_milestones": n_ms,
                         "state_error": fmt(st, ".2e"), "impacts": res.get("impacts", ""), "status": status})
            print(f"  {engine:20s} {setting:34s} whole {w:8.4f} s (x{w / base[0]:7.3g})  call {c:9.5f} s "
                  f"(x{c / base[1]:7.3g}, vs whole x{c / base[0]:7.3g})  event {err:8.1e}  state {st:8.1e}  {status}",
                  flush=True)
    write_csv(rows, args.out + ".csv")
    provenance["load_end"] = os.getloadavg()[0]
    with open(args.out + ".json", "w") as fh:
        json.dump(provenance, fh, indent=1)
        fh.write("\n")
    print(args.out + ".csv")
    plot(rows, [s[0] for s in scenes], args.out + ".png", provenance)
    table.print_tables(rows)


def run_provenance(args):
    """When and from what the run was made: its date (UTC), the checkout's commit (with "+changes"
    when the tree differs from it), `vibro --version`, the command line and the load average."""
    def git(*a):
        r = subprocess.run(["git", "-C", ROOT, *a], capture_output=True, text=True)
        return r.stdout.strip() if r.returncode == 0 else ""
    commit = git("rev-parse", "--short=7", "HEAD") or "unknown"
    if git("status", "--porcelain", "--untracked-files=no"):
        commit += "+changes"
    version = subprocess.run([args.vibro, "--version"], capture_output=True, text=True).stdout.strip()
    return {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "commit": commit,
            "vibro_version": version, "command": " ".join([os.path.relpath(sys.argv[0], ROOT)] + sys.argv[1:]),
            "periods": args.periods, "repeat": args.repeat, "vibro_repeat": args.vibro_repeat,
            "load_start": os.getloadavg()[0], "cpus": os.cpu_count()}


STYLE = {"vibro exact": ("*", "k"), "vibro CVODE": ("o", "tab:blue"), "SciPy DOP853": ("s", "tab:orange"),
         "Siconos Moreau–Jean": ("^", "tab:green"), "Siconos event-driven": ("v", "tab:purple")}


def plot(rows, labels, path, provenance=None):
    """Error against CPU per scene: filled markers the whole processes, hollow ones the calls."""
    plt = pyplot()
    cols = 4
    nrows = math.ceil((len(labels) + 1) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.2 * cols, 3.6 * nrows), squeeze=False)
    for ax, label in zip(axes.flat, labels):
        for engine, (marker, color) in STYLE.items():
            for key, filled in (("whole_cpu_s", True), ("call_cpu_s", False)):
                pts = sorted((float(r[key]), max(float(r["event_error"]), 1e-16)) for r in rows
                             if r["scene"] == label and r["engine"] == engine and r["status"] == "ok"
                             and r["event_error"] not in ("", "nan") and r[key] not in ("", "nan"))
                if pts:
                    ax.loglog([x for x, _ in pts], [y for _, y in pts], marker + ("-" if filled else ":"), ms=7,
                              color=color, mfc=color if filled else "none", lw=0.8)
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("CPU time [s]")
        ax.set_ylabel("stick/release time error / T")
        ax.grid(True, which="both", alpha=0.3)
    leg = axes.flat[len(labels)]
    for engine, (marker, color) in STYLE.items():
        if any(r["engine"] == engine for r in rows):
            leg.plot([], [], marker, color=color, ms=8, linestyle="none", label=engine)
    leg.plot([], [], "o-", color="gray", ms=7, label="filled: whole process\n(interpreter or vibro start-up)")
    leg.plot([], [], "o:", color="gray", mfc="none", ms=7, label="hollow: the call alone")
    leg.text(0.5, 0.02, "errors below 1e-16 drawn at 1e-16;\nruns that failed are not drawn",
             ha="center", fontsize=8, transform=leg.transAxes)
    leg.legend(loc="center", fontsize=9)
    leg.axis("off")
    for ax in list(axes.flat)[len(labels) + 1:]:
        ax.axis("off")
    when = (f", {provenance['date']}, commit {provenance['commit']}" if provenance else "")
    fig.suptitle("vibro and its peers: error of the first 12 stick/release times against vibro's exact engine "
                 f"vs CPU time (one run of benchmarks/peers/run_all.py{when})", fontsize=10)
    save_figure(fig, path)


if __name__ == "__main__":
    main()
