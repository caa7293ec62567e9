#!/usr/bin/python3
"""Peers side by side in one run: vibro (exact engine, CVODE), SciPy solve_ivp with events,
Siconos Moreau–Jean time-stepping and Siconos event-driven (LSODAR) on the same scenes.

Each scene is run for --periods forcing periods (default 20) from vibro's default initial state;
the peers get the modal model that `vibro model --json` prints (problem.py). Accuracy is measured
against vibro's exact engine with chatter_switch = 1e-9 (the reference), three ways:
  * event_error: the largest difference of the first 12 stick and release times, relative to
    the forcing period T (over the events a failed run did reach; n_milestones says how many);
  * sp_error: the sticking fraction over the last 5 periods (from the stick/release times; for
    Moreau–Jean the share of steps with a positive contact impulse) minus the reference's;
  * state_error: the largest difference of the modal displacements and velocities at t_end.
cpu_s is the CPU time of one run: for vibro the whole `vibro simulate` process (start-up
included; the mean of REPEAT processes, each a few ms), for the peers the Python call (model
set-up included, interpreter and imports not). startup_s is vibro's fixed cost per process
(loading, the scene: docs/performance.md, "Start-up"; timed without --out, as the peers write no
file): the work of P periods is
taken as the CPU of P more periods in steady running, (cpu(101 P) − cpu(P))/100, from REPEAT
processes of each (a difference of 100 P periods, far above the spread of a few-ms process even on
the scenes whose 20 periods take 30 µs), and startup_s = cpu(P) minus that work.
cpu_ratio = cpu_s / cpu_s of vibro's exact engine with default settings on the same scene (its
whole process); cpu_ratio_work = cpu_s / the work of that engine alone (start-up excluded), the
measure that compares like with like, since the peers' times exclude their interpreter's start-up.

Usage: /usr/bin/python3 benchmarks/peers/run_all.py [--vibro build/vibro] [--out docs/peers]
       [--periods 20] [--scenes a.toml,b.toml] [--quick]
Writes PREFIX.csv (one row per run) and PREFIX.png (event error against CPU time, per scene);
--replot redraws PREFIX.png from PREFIX.csv.
Needs Debian's python3-scipy, python3-siconos, python3-h5py, python3-matplotlib. About 10 minutes.
"""
import argparse
import csv
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from bench_common import (DEFAULT_VIBRO, ROOT, fmt, milestone_error, pyplot, run_vibro,  # noqa: E402
                          save_figure, stick_intervals, sticking_fraction, write_csv)
import scipy_peer  # noqa: E402
import siconos_peer  # noqa: E402
from problem import Problem  # noqa: E402

SCENES = [
    ("Fig. 8 (1-DOF, r = 0.75)", "fig08_preload.toml"),
    ("Fig. 5 (1-DOF, r = 0.75)", "fig05_coexistence.toml"),
    ("Fig. 11 (1-DOF clearance, r = 0)", "fig11_clearance.toml"),
    ("Fig. 4 (1-DOF, r = 0, q = 2)", "fig04_subharmonic.toml"),
    ("2-DOF chain (r = 0.5)", "chain2.toml"),
    ("2-DOF chain, 2 % damping", "chain2_damped.toml"),
    ("3-DOF chain (r = 0)", "chain3.toml"),
]
LAST = 5  # periods over which the sticking fraction is measured
REPEAT = 10  # vibro processes per setting whose CPU is averaged (a run is a few ms)
LONGER = 101  # the longer runs that measure vibro's work per period, in multiples of --periods
WALL = 20.0  # seconds after which a peer run that has not finished is stopped ("gave up")


def settings(p, quick):
    """(engine, setting label, callable returning a dict of results)."""
    out = [("vibro exact", "defaults", ("vibro", ['run.engine="exact"']))]
    for rtol in ([1e-6, 1e-10] if not quick else [1e-6]):
        out.append(("vibro CVODE", f"Adams rtol {rtol:g}",
                    ("vibro", ['run.engine="cvode"', 'run.method="adams"', f"run.rtol={rtol:g}",
                               f"run.atol={rtol * 1e-2:g}"])))
    for rtol in ([1e-6, 1e-9, 1e-12] if not quick else [1e-9]):
        out.append(("SciPy restart", f"DOP853 rtol {rtol:g}, plastic below 1e-6",
                    ("scipy", dict(rtol=rtol, plastic_below=1e-6, wall_limit=WALL))))
    if p.r > 0 and not quick:
        out.append(("SciPy naive", "DOP853 rtol 1e-9, impact by impact",
                    ("scipy", dict(rtol=1e-9, plastic_below=0.0, wall_limit=WALL))))
    for steps in ([100, 1000, 10000] if not quick else [1000]):
        out.append(("Siconos Moreau–Jean", f"theta 0.5, h = T/{steps}", ("mj", dict(steps_per_period=steps))))
    ed = [(None, 16), (1e-6, 16), (1e-8, 16), (1e-10, 16), (1e-8, 256)] if not quick else [(1e-8, 16)]
    for rtol, td in ed:
        tol = f"rtol = atol = {rtol:g}" if rtol else "default tolerances (rtol 10ε, atol 100ε)"
        out.append(("Siconos event-driven", f"LSODAR {tol}, TOL_ED 1e-6, h = T/{td}",
                    ("ed", dict(rtol=rtol, tol_ed=1e-6, td_steps=td, wall_limit=WALL))))
    return out


def end_state_vibro(run, t_end):
    t, X, V = run.section
    k = int(np.argmin(np.abs(t - t_end)))
    if abs(t[k] - t_end) > 1e-9 * max(1.0, t_end):
        return None
    return X[k], V[k]


def measure(p, ref, kind, arg, vibro):
    """Runs one setting; returns (milestones list, sp, end state, cpu, status, impacts)."""
    t0, t1 = p.t_end - LAST * p.T, p.t_end
    if kind == "vibro":
        r = run_vibro(vibro, p.scene, p.periods, arg)
        if not r.ok:
            return [], float("nan"), None, (r.cpu, float("nan")), f"exit {r.returncode}: {r.stderr.strip()[:120]}", None
        sp = sticking_fraction(r.stick_intervals(), t0, t1)
        counts = r.summary["counts"] if r.summary else {}
        return (r.milestones(12), sp, end_state_vibro(r, p.t_end), vibro_cpu(vibro, p, arg),
                r.summary["status"], counts.get("impacts"))
    if kind == "scipy":
        res = scipy_peer.run(p, **arg)
    elif kind == "mj":
        res = siconos_peer.moreau_jean(p, last_periods=LAST, **arg)
    else:
        res = siconos_peer.event_driven(p, **arg)
    ok = res.status == "ok"
    if kind == "mj":
        sp = res.sp_steps if ok else float("nan")
    else:
        sp = sticking_fraction(stick_intervals(res.times, res.kinds), t0, t1) if ok else float("nan")
    return res.times[:12], sp, res.end, (res.cpu, float("nan")), res.status, res.impacts if kind != "mj" else None


def vibro_cpu(vibro, p, sets):
    """(CPU of one whole `vibro simulate` process, its start-up): means over REPEAT processes of
    p.periods periods and of LONGER·p.periods, in turn (A B A B ...) so that both see the same
    machine. They write no HDF5 file (the events stay in memory, as the peers' do)."""
    whole, longer = [], []
    for _ in range(REPEAT):
        whole.append(run_vibro(vibro, p.scene, p.periods, sets, read=False, out=False).cpu)
        longer.append(run_vibro(vibro, p.scene, LONGER * p.periods, sets, read=False, out=False).cpu)
    cpu = float(np.mean(whole))
    work = max(0.0, (float(np.mean(longer)) - cpu) / (LONGER - 1))
    return cpu, cpu - work


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vibro", default=DEFAULT_VIBRO)
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "peers"))
    ap.add_argument("--periods", type=int, default=20)
    ap.add_argument("--scenes", default=None, help="comma-separated scene files (default: all of SCENES)")
    ap.add_argument("--quick", action="store_true", help="one setting per engine (a smoke run)")
    ap.add_argument("--replot", action="store_true", help="only redraw PREFIX.png from PREFIX.csv")
    args = ap.parse_args()
    scenes = SCENES if not args.scenes else [(s, s) for s in args.scenes.split(",")]
    if args.replot:
        with open(args.out + ".csv", newline="") as fh:
            rows = list(csv.DictReader(fh))
        plot(rows, list(dict.fromkeys(r["scene"] for r in rows)), args.out + ".png")
        return
    rows = []
    for label, scene in scenes:
        p = Problem(args.vibro, scene, label, periods=args.periods)
        ref = run_vibro(args.vibro, scene, p.periods, ['run.engine="exact"', "run.chatter_switch=1e-9"])
        if not ref.ok:
            print(f"{label}: the reference run failed: {ref.stderr}", file=sys.stderr)
            continue
        ref_ms = ref.milestones(12)
        ref_sp = sticking_fraction(ref.stick_intervals(), p.t_end - LAST * p.T, p.t_end)
        ref_end = end_state_vibro(ref, p.t_end)
        base_cpu = base_work = None
        print(f"== {label} ({scene}, {p.n} mode(s), {p.periods} periods, reference SP {ref_sp:.6f})", flush=True)
        for engine, setting, (kind, arg) in settings(p, args.quick):
            ms, sp, end, (cpu, startup), status, impacts = measure(p, ref, kind, arg, args.vibro)
            if base_cpu is None:
                base_cpu, base_work = cpu, cpu - startup
            err = milestone_error(ms, ref_ms, p.T)
            sp_err = abs(sp - ref_sp) if not math.isnan(sp) else float("nan")
            st_err = float("nan")
            if end is not None and ref_end is not None:
                st_err = float(max(np.max(np.abs(end[0] - ref_end[0])), np.max(np.abs(end[1] - ref_end[1]))))
            rows.append({"scene": label, "scene_file": scene, "engine": engine, "setting": setting,
                         "cpu_s": fmt(cpu, ".5f"), "startup_s": fmt(startup, ".5f"),
                         "cpu_ratio": fmt(cpu / base_cpu, ".3g"), "cpu_ratio_work": fmt(cpu / base_work, ".3g"),
                         "event_error": fmt(err, ".2e"), "n_milestones": min(len(ms), len(ref_ms)),
                         "sp": fmt(sp, ".6f"), "sp_error": fmt(sp_err, ".2e"), "state_error": fmt(st_err, ".2e"),
                         "impacts": "" if impacts is None else impacts, "status": status})
            print(f"  {engine:22s} {setting:62s} cpu {cpu:8.4f} s (x{cpu / base_cpu:8.3g}, work x{cpu / base_work:8.3g})"
                  f"  event {err:8.1e}"
                  f"  SP {sp_err:8.1e}  state {st_err:8.1e}  {status}", flush=True)
    write_csv(rows, args.out + ".csv")
    print(args.out + ".csv")
    plot(rows, [s[0] for s in scenes], args.out + ".png")


STYLE = {"vibro exact": ("*", "k"), "vibro CVODE": ("o", "tab:blue"), "SciPy restart": ("s", "tab:orange"),
         "SciPy naive": ("X", "tab:red"), "Siconos Moreau–Jean": ("^", "tab:green"),
         "Siconos event-driven": ("v", "tab:purple")}


def plot(rows, labels, path):
    plt = pyplot()
    cols = 4
    nrows = math.ceil((len(labels) + 1) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.2 * cols, 3.8 * nrows), squeeze=False)
    for ax, label in zip(axes.flat, labels):
        for engine, (marker, color) in STYLE.items():
            for filled in (True, False):
                pts = [(float(r["cpu_s"]), max(float(r["event_error"]), 1e-17)) for r in rows
                       if r["scene"] == label and r["engine"] == engine and (r["status"] == "ok") == filled
                       and r["event_error"] not in ("", "nan") and int(r["n_milestones"]) >= 2]
                if pts:
                    ax.loglog([x for x, _ in pts], [y for _, y in pts], marker, ms=8, color=color,
                              mfc=color if filled else "none", linestyle="none")
        # vibro's exact engine once more at its work alone (start-up excluded, as for the peers).
        work = [(float(r["cpu_s"]) - float(r["startup_s"]), max(float(r["event_error"]), 1e-17)) for r in rows
                if r["scene"] == label and r["engine"] == "vibro exact" and r.get("startup_s") not in (None, "", "nan")
                and float(r["cpu_s"]) > float(r["startup_s"])]
        if work:
            ax.loglog([x for x, _ in work], [y for _, y in work], "*", ms=9, color="k", mfc="none",
                      linestyle="none")
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("CPU time per run [s]")
        ax.set_ylabel("stick/release time error / T")
        ax.grid(True, which="both", alpha=0.3)
    leg = axes.flat[len(labels)]
    for engine, (marker, color) in STYLE.items():
        leg.plot([], [], marker, color=color, ms=8, linestyle="none", label=engine)
    leg.plot([], [], "*", color="k", mfc="none", ms=9, linestyle="none",
             label="vibro exact, work alone\n(start-up excluded)")
    leg.plot([], [], "o", color="gray", mfc="none", ms=8, linestyle="none",
             label="hollow: failed or gave up\n(error over the events reached;\nnot drawn if none after t = 0)")
    leg.legend(loc="center", fontsize=9)
    leg.axis("off")
    for ax in list(axes.flat)[len(labels) + 1:]:
        ax.axis("off")
    fig.suptitle("vibro and its peers: error of the first 12 stick/release times against vibro's exact "
                 "engine vs CPU time (one run)", fontsize=10)
    save_figure(fig, path)


if __name__ == "__main__":
    main()
