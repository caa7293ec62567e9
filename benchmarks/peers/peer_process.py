#!/usr/bin/python3
"""One run of one engine in a process of its own, as its user runs it (benchmarks/peers/run_all.py).

    peer_process.py SPEC.json

SPEC: {"engine": "scipy" | "mj" | "ed" | "vibro", "args": {...}, "problem": Problem.to_dict()
(the peers), "scene", "sets", "periods", "python_dir", "repeat" (vibro)}. The process imports what
its engine needs (NumPy and SciPy, Siconos, or vibro's Python module), runs the engine and prints
one JSON line: the milestones, the end state, the status and `call_cpu`, the CPU seconds of the
call alone (model set-up included, interpreter start-up and imports excluded). run_all.py measures
the whole process (interpreter start-up and imports included) from outside (rusage of its child).
vibro's call (`vibro.simulate` on a scene loaded beforehand) is repeated `repeat` times and
call_cpu is the median (a call is well under a millisecond on some scenes).
"""
import json
import os
import resource
import sys
import time


def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def run_vibro_call(spec):
    sys.path.insert(0, spec["python_dir"])
    import vibro  # noqa: PLC0415
    sets = {"run.periods": spec["periods"], "run.samples_per_period": 0}
    for s in spec["sets"]:
        k, v = s.split("=", 1)
        sets[k] = json.loads(v)
    scene = vibro.load_scene(spec["scene"], sets)
    times, result = [], None
    for _ in range(spec.get("repeat", 1)):
        c0 = cpu()
        result = vibro.simulate(scene, progress=False)
        times.append(cpu() - c0)
    ev = result.events
    keep = [(float(t), int(k), int(c)) for t, k, c in zip(ev["t"], ev["kind"], ev["contact"]) if k in (3, 4)]
    end = None
    sec = result.section
    if len(sec) and abs(float(sec["t"][-1]) - spec["t_end"]) <= 1e-9 * max(1.0, spec["t_end"]):
        end = [sec["X"][-1].tolist(), sec["V"][-1].tolist()]
    times.sort()
    status = result.summary["status"]
    return {"times": [t for t, _, _ in keep], "kinds": [k for _, k, _ in keep], "contacts": [c for _, _, c in keep],
            "end": end, "status": status, "impacts": result.summary["counts"].get("impacts"),
            "call_cpu": times[len(times) // 2], "call_cpu_min": times[0], "call_cpu_max": times[-1]}


def run_peer(spec):
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from problem import Problem  # noqa: PLC0415
    engine = spec["engine"]
    if engine == "scipy":
        import scipy_peer as peer  # noqa: PLC0415
        fn = peer.run
    else:
        import siconos_peer as peer  # noqa: PLC0415
        fn = peer.moreau_jean if engine == "mj" else peer.event_driven
    c0 = cpu()
    p = Problem.from_dict(spec["problem"])
    res = fn(p, **spec["args"])
    out = res.to_dict()
    out["call_cpu"] = cpu() - c0
    return out


def main():
    with open(sys.argv[1]) as fh:
        spec = json.load(fh)
    w0 = time.time()
    out = run_vibro_call(spec) if spec["engine"] == "vibro" else run_peer(spec)
    out["wall"] = time.time() - w0
    sys.stdout.write(json.dumps(out) + "\n")


if __name__ == "__main__":
    main()
