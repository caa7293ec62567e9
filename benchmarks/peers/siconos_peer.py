#!/usr/bin/python3
"""The scenes with Siconos (Debian python3-siconos 4.4): Moreau–Jean time-stepping (and, on
request, the event-driven scheme EventDriven + LsodarOSI), against vibro.

The model is the modal system of problem.py written as a LagrangianLinearTIDS with the modal
masses (M = diag(1/T_B), K = diag(ω²/T_B), C = diag(2ζω/T_B)) and one Interaction per contact:
LagrangianLinearTIR with y_j = c_jᵀX − e_j ≥ 0 and a NewtonImpactNSL with the contact's
restitution. The force (T_A/T_B) f sin ωt is a Siconos plugin, compiled C
(benchmarks/peers/forcing_plugin.c, built once by build_plugin and attached with
setComputeFExtFunction, its parameters in the system's z vector), as Siconos' own examples do: no
Python is called while Siconos integrates, only between steps to read the impulses.

Moreau–Jean (θ = 0.5, LCP at velocity level, fixed step h = T/steps): no events; a contact is
"on" in the steps where its LCP impulse λ is positive. Stick/release milestones of each contact
are the changes of this state that last at least 3 steps (a chattering impact is one "on" step),
dated at the first step of the change; the milestones of all contacts are merged in time order.

Event-driven (LSODAR with root finding, an impact LCP and an acceleration-level LCP; one contact
only): the contact sticks when the post-impact velocity is below the simulation's TOL_ED and
leaves when the acceleration-level contact force λ₂ vanishes. Milestones are the changes of index
set 2 (the "sticking" set). Two measures are needed to get it running at all on this model:
  * LsodarOSI.computeRhs(t_event) before processEvents: without it EventDriven 4.4 throws in
    updateIndexSetsWithDoubleCondition at the first sticking entry of any system with a
    stiffness (it works for the bouncing ball under gravity, which has none; --diagnose);
  * setMaxNstep(1e5): sticking phases need many LSODAR steps per call.
LsodarOSI.setTol(itol, rtol, atol) of 4.4 sets atol = rtol (its atol argument is ignored);
TOL_ED is a static member of EventDriven, so it is set before every run.

Standalone: benchmarks/peers/siconos_peer.py [--vibro build/vibro] [--scenes a.toml,b.toml]
            benchmarks/peers/siconos_peer.py --diagnose   (the event-driven scheme's failures)
(benchmarks/peers/run_all.py runs it beside vibro and SciPy and writes the table.)
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np
import siconos.kernel as sk

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from bench_common import DEFAULT_VIBRO, ROOT, cpu_self, milestone_error, run_vibro  # noqa: E402
from problem import PeerResult, Problem  # noqa: E402

PLUGIN_SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "forcing_plugin.c")
PLUGIN_DIR = os.path.join(ROOT, "build", "peers")


def build_plugin(directory=PLUGIN_DIR):
    """Compiles forcing_plugin.c into DIRECTORY/forcing_plugin.so (when missing or older than the
    source); returns the path without the extension, as Siconos takes it."""
    os.makedirs(directory, exist_ok=True)
    so = os.path.join(directory, "forcing_plugin.so")
    if not os.path.exists(so) or os.path.getmtime(so) < os.path.getmtime(PLUGIN_SOURCE):
        subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-o", so, PLUGIN_SOURCE, "-lm"], check=True)
    return so[:-3]


class _CaptureStdout:
    """Captures what the C++ side prints on file descriptor 1 (LSODAR's failure messages)."""

    def __enter__(self):
        sys.stdout.flush()
        self.file = tempfile.TemporaryFile(mode="w+b")
        self.saved = os.dup(1)
        os.dup2(self.file.fileno(), 1)
        return self

    def __exit__(self, *exc):
        sys.stdout.flush()
        os.dup2(self.saved, 1)
        os.close(self.saved)
        self.file.seek(0)
        self.text = self.file.read().decode(errors="replace")
        self.file.close()
        return False


def _system(p, plugin):
    M, K, C, force_vec = p.lagrangian()
    ds = sk.LagrangianLinearTIDS(p.X0.copy(), p.V0.copy(), M, K, C)
    ds.setzPtr(np.concatenate(([p.f, p.omega], force_vec)))
    ds.setComputeFExtFunction(plugin, "forcing")
    inters = [sk.Interaction(sk.NewtonImpactNSL(float(p.r[j])),
                             sk.LagrangianLinearTIR(p.C[j].reshape(1, p.n), np.array([-p.e[j]])))
              for j in range(p.m)]
    nsds = sk.NonSmoothDynamicalSystem(0.0, p.t_end)
    nsds.insertDynamicalSystem(ds)
    for inter in inters:
        nsds.link(inter, ds)
    return ds, inters, nsds


def moreau_jean(p, steps_per_period, plugin=None, last_periods=5, min_run=3):
    res = PeerResult()
    c0 = cpu_self()
    ds, inters, nsds = _system(p, plugin or build_plugin())
    h = p.T / steps_per_period
    s = sk.TimeStepping(nsds, sk.TimeDiscretisation(0.0, h), sk.MoreauJeanOSI(0.5), sk.LCP())
    m = p.m
    state, run_start, run_len = [False] * m, [0.0] * m, [0] * m  # debounced state, run of the other value
    on_steps = total = 0
    t_last = p.t_end - last_periods * p.T
    milestones = []
    t = 0.0
    try:
        while s.hasNextEvent():
            s.computeOneStep()
            t = s.nextTime()
            for j, inter in enumerate(inters):
                on = inter.lambda_(1)[0] > 0
                if j == 0 and t > t_last + 0.5 * h:
                    total += 1
                    on_steps += on
                if on != state[j]:
                    if run_len[j] == 0:
                        run_start[j] = t - h
                    run_len[j] += 1
                    if run_len[j] == min_run:
                        milestones.append((run_start[j], 3 if on else 4, j))
                        state[j], run_len[j] = on, 0
                else:
                    run_len[j] = 0
            s.nextStep()
        res.end = (np.array(ds.q()).copy(), np.array(ds.velocity()).copy())
    except Exception as e:  # noqa: BLE001 (SWIG raises a bare std::exception)
        res.status = f"exception at t = {t:.6g}: {e}"
    for tm, kind, j in sorted(milestones):
        (res.stick if kind == 3 else res.release)(tm, j)
    res.t_reached = t
    res.sp_steps = on_steps / max(total, 1)
    res.cpu = cpu_self() - c0
    return res


def event_driven(p, rtol=None, tol_ed=1e-6, td_steps=16, max_steps=100000, wall_limit=60.0,
                 fix_free_acceleration=True, plugin=None):
    """rtol None keeps LsodarOSI's default tolerances (rtol 10ε, atol 100ε). One contact only."""
    if p.m != 1:
        raise ValueError("the event-driven peer takes one contact")
    res = PeerResult()
    c0, w0 = cpu_self(), time.time()
    ds, _, nsds = _system(p, plugin or build_plugin())
    s = sk.EventDriven(nsds, sk.TimeDiscretisation(0.0, p.T / td_steps))
    osi = sk.LsodarOSI()
    s.insertIntegrator(osi)
    s.insertNonSmoothProblem(sk.LCP(), sk.SICONOS_OSNSP_ED_IMPACT)
    s.insertNonSmoothProblem(sk.LCP(), sk.SICONOS_OSNSP_ED_SMOOTH_ACC)
    s.setToleranceED(tol_ed if tol_ed else 1000 * 10 * np.finfo(float).eps)
    s.initialize()
    if rtol:
        osi.setTol(1, rtol, rtol)
    if max_steps:
        osi.setMaxNstep(max_steps)
    topo = nsds.topology()
    em = s.eventsManager()
    stuck_prev = False
    t = 0.0
    where = ""
    with _CaptureStdout() as out:
        try:
            while s.hasNextEvent():
                if time.time() - w0 > wall_limit:
                    res.status = f"gave up after {wall_limit:.0f} s (t = {t:.6g})"
                    break
                where = "integration (LSODAR)"
                s.advanceToEvent()
                v_before = float(np.sum(ds.velocity()))  # ẋ_B at the event, before processing
                if fix_free_acceleration:
                    osi.computeRhs(em.nextTime())
                where = "event processing"
                s.processEvents()
                t = s.startingTime()
                if v_before < 0 and float(np.sum(ds.velocity())) > v_before:
                    res.impacts += 1
                stuck = topo.indexSetsSize() > 2 and topo.indexSetSize(2) > 0
                if stuck != stuck_prev:
                    (res.stick if stuck else res.release)(t)
                    stuck_prev = stuck
            else:
                res.end = (np.array(ds.q()).copy(), np.array(ds.velocity()).copy())
        except Exception:  # noqa: BLE001 (SWIG raises a bare std::exception without its message)
            res.status = f"failed at t = {t:.6g} in {where}"
    m = re.search(r"Istate = (-?\d+)", out.text)
    if res.status.startswith("failed"):
        if m:
            res.status += f" (LSODAR istate {m.group(1)}: excess work)" if m.group(1) == "-1" else \
                f" (LSODAR istate {m.group(1)})"
        elif "TOL_ED" in out.text:
            g = re.search(r"y = (\S+) < -_TOL_ED", out.text)
            res.status += f" (gap {g.group(1) if g else '?'} below -TOL_ED)"
        elif where == "event processing":
            res.status += " (EventDriven::updateIndexSetsWithDoubleCondition)"
    res.t_reached = t
    res.cpu = cpu_self() - c0
    return res


def spring_ball(restitution, stiffness, workaround):
    """A ball under gravity (g = 9.81) dropped from 1 onto the ground at 0, with a spring of the
    given stiffness to the ground, event-driven for 2 s; returns 'ok' or where it failed."""
    ds = sk.LagrangianLinearTIDS(np.array([1.0]), np.array([0.0]), np.eye(1), stiffness * np.eye(1),
                                 np.zeros((1, 1)))
    ds.setFExtPtr(np.array([-9.81]))
    inter = sk.Interaction(sk.NewtonImpactNSL(restitution), sk.LagrangianLinearTIR(np.eye(1)))
    nsds = sk.NonSmoothDynamicalSystem(0.0, 2.0)
    nsds.insertDynamicalSystem(ds)
    nsds.link(inter, ds)
    s = sk.EventDriven(nsds, sk.TimeDiscretisation(0.0, 0.1))
    osi = sk.LsodarOSI()
    s.insertIntegrator(osi)
    s.insertNonSmoothProblem(sk.LCP(), sk.SICONOS_OSNSP_ED_IMPACT)
    s.insertNonSmoothProblem(sk.LCP(), sk.SICONOS_OSNSP_ED_SMOOTH_ACC)
    s.setToleranceED(1000 * 10 * np.finfo(float).eps)
    s.initialize()
    try:
        with _CaptureStdout():
            while s.hasNextEvent():
                s.advanceToEvent()
                if workaround:
                    osi.computeRhs(s.eventsManager().nextTime())
                s.processEvents()
        return f"ok (t = 2, x = {ds.q()[0]:.2g})"
    except Exception:  # noqa: BLE001
        return f"fails in processEvents after t = {s.startingTime():.3g}"


def diagnose(vibro):
    """The evidence behind the README's statements on the event-driven scheme."""
    print("1. Ball dropped on the ground, event-driven (default tolerances):")
    for k in (0.0, 0.1):
        for r in (0.0, 0.5):
            for fix in (False, True):
                print(f"   spring k = {k:3g}, r = {r:3g}, computeRhs(t_event) before processEvents: "
                      f"{'yes' if fix else 'no ':3s} -> {spring_ball(r, k, fix)}")
    print("2. Releases (R = 0) found by the event-driven scheme (rtol 1e-8, h = T/16) and by vibro:")
    ref8 = run_vibro(vibro, "fig08_preload.toml", 2, ['run.engine="exact"', "run.chatter_switch=1e-9"])
    print("   (vibro's first sticks on Fig. 8: " + ", ".join(f"{t:.5f}" for t, k in zip(*ref8.events) if k == 3) + ")")
    for scene in ("fig08_preload.toml", "fig11_clearance.toml"):
        p = Problem.from_vibro(vibro, scene, periods=6)
        ref = run_vibro(vibro, scene, p.periods, ['run.engine="exact"', "run.chatter_switch=1e-9"])
        res = event_driven(p, 1e-8, td_steps=16)
        h = p.T / 16
        ed = [t for t, k in zip(res.times, res.kinds) if k == 4][:5]
        vb = [t for t, k in zip(*ref.events) if k == 4][:5]
        print(f"   {scene}: vibro  " + " ".join(f"{t:9.5f}" for t in vb))
        print(f"   {' ' * len(scene)}  Siconos " + " ".join(f"{t:9.5f}" for t in ed) + "   (" + res.status + ")")
        print(f"   {' ' * len(scene)}  t / h   " + " ".join(f"{t / h:9.4f}" for t in ed))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vibro", default=DEFAULT_VIBRO)
    ap.add_argument("--scenes", default="fig08_preload.toml,fig05_coexistence.toml,fig11_clearance.toml")
    ap.add_argument("--periods", type=int, default=20)
    ap.add_argument("--diagnose", action="store_true",
                    help="only the evidence for the event-driven scheme's failures (see README)")
    args = ap.parse_args()
    if args.diagnose:
        diagnose(args.vibro)
        return
    print(f"{'scene':24s} {'scheme':14s} {'CPU [s]':>8s} {'error/T':>9s}  status")
    for scene in args.scenes.split(","):
        p = Problem.from_vibro(args.vibro, scene, periods=args.periods)
        ref = run_vibro(args.vibro, scene, p.periods, ['run.engine="exact"', "run.chatter_switch=1e-9"])
        print(f"{scene:24s} {'vibro exact':14s} {ref.cpu:8.3f} {0.0:9.1e}  (whole process)")
        for steps in (100, 1000, 10000):
            res = moreau_jean(p, steps)
            err = milestone_error(res.times[:12], ref.milestones(12), p.T)
            print(f"{scene:24s} {'MJ T/' + str(steps):14s} {res.cpu:8.3f} {err:9.1e}  {res.status}", flush=True)
        for rtol in ((None, 1e-6, 1e-8, 1e-10) if p.m == 1 else ()):
            res = event_driven(p, rtol)
            err = milestone_error(res.times[:12], ref.milestones(12), p.T)
            print(f"{scene:24s} {'ED ' + (f'{rtol:g}' if rtol else 'default'):14s} {res.cpu:8.3f} {err:9.1e}  "
                  f"{res.status}", flush=True)


if __name__ == "__main__":
    main()
