#!/usr/bin/python3
"""Out of memory inside worker threads (issue 38): the commands that compute on several threads
(basin and attractors on TBB; sweep; simulate's write-behind thread) run under `ulimit -v` limits from barely enough to start up to comfortable, end with exit 0
or exit 3 and one line, never exit 1, a
traceback of another kind, or death by a signal (std::terminate on an exception escaping a
thread); an --out file left is readable or absent.

The same for vibro.basin and vibro.attractors in a Python interpreter under RLIMIT_AS: each call
returns or raises MemoryError promptly and the interpreter exits (docs/python.md, "Under a memory
limit").

usage: oom_workers_test.py VIBRO SCENES_DIR PYTHONPATH
"""
import os
import resource
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

vibro, scenes, pythonpath = (os.path.abspath(a) for a in sys.argv[1:4])
tmp = tempfile.mkdtemp(prefix="vibro_oom_")
fig5 = os.path.join(scenes, "fig05_coexistence.toml")
chain3 = os.path.join(scenes, "chain3.toml")
MB = 1024 * 1024


def limited(megabytes):
    def set_limit():
        resource.setrlimit(resource.RLIMIT_AS, (megabytes * MB, megabytes * MB))
    return set_limit


out = os.path.join(tmp, "out.h5")
commands = {
    "basin": ["basin", fig5, "--grid", "40,40", "--threads", "2", "--out", out, "--force"],
    "attractors": ["attractors", fig5, "--samples", "100", "--threads", "2"],
    "sweep": ["sweep", fig5, "--param", "excitation.frequency", "--from", "1", "--to", "3", "--steps", "10",
              "--out", out, "--force"],
    "simulate": ["simulate", fig5, "--set", "run.periods=3000", "--out", out, "--force"],
}
# ulimit -v in MB: the smallest lets the process barely start (the libraries alone map ~40 MB).
limits = [48, 56, 64, 100]
outcomes = {}
for name, args in commands.items():
    for mb in limits:
        if os.path.exists(out):
            os.remove(out)
        r = subprocess.run([vibro, *args, "--time-limit", "300"], capture_output=True, text=True, timeout=600,
                           preexec_fn=limited(mb))
        tag = f"vibro {name} under ulimit -v {mb} MB"
        outcomes.setdefault(name, []).append(r.returncode)
        # Never exit 2 either: running out of memory is a limit, not bad input (a bad_alloc creating
        # the --out file was "cannot write the study: std::bad_alloc", exit 2).
        check(f"{tag}: exit 0 or 3", r.returncode in (0, 3), f"exit {r.returncode}: {r.stderr[-400:]}")
        check(f"{tag}: no internal error", "internal error" not in r.stderr and "terminate" not in r.stderr,
              r.stderr[-400:])
        if r.returncode == 3:
            last = r.stderr.strip().splitlines()[-1] if r.stderr.strip() else ""
            check(f"{tag}: one line says why", last.startswith("vibro:"), r.stderr[-400:])
        if os.path.exists(out) and r.returncode in (0, 3):
            i = subprocess.run([vibro, "info", out], capture_output=True, text=True, timeout=120)
            check(f"{tag}: the --out file left is readable", i.returncode in (0, 2), i.stderr[-300:])
            check(f"{tag}: vibro info never exit 1", i.returncode != 1, i.stderr[-300:])
print("exit codes per command over", limits, "MB:", outcomes)
check("some limit ends a command with exit 3 (the test reaches out-of-memory)",
      any(3 in codes for codes in outcomes.values()), outcomes)

# The same from Python: vibro.basin / vibro.attractors on 2 threads, in an interpreter whose
# address space is limited either from its start (numpy and OpenBLAS start under the limit: an
# OpenBLAS thread refused its buffer spun for ever and the interpreter hung at exit joining it) or
# right after `import vibro` (a TBB worker's first throw needed thread-local storage that malloc
# could no longer give: glibc ended the process, "cannot allocate memory for thread-local data",
# exit 127). Each call returns or raises MemoryError, the interpreter exits normally, and a basin's
# `out` file left is readable. An interpreter that cannot even import numpy under the limit
# (before it prints "ready") is Python's limit, not vibro's, and is only counted.
child = r"""
import resource, sys
limit_after_import = sys.argv[2] == "after-import"
import vibro
if limit_after_import:
    mb = int(sys.argv[1]) << 20
    resource.setrlimit(resource.RLIMIT_AS, (mb, resource.RLIM_INFINITY))
print("ready", flush=True)
scene = vibro.load_scene(sys.argv[3])
try:
    if sys.argv[4] == "basin":
        vibro.basin(scene, grid=(40, 40), threads=2, out=sys.argv[5], force=True)
    else:
        vibro.attractors(scene, samples=100, threads=2)
    print("result ok", flush=True)
except MemoryError as e:
    print("result MemoryError", str(e).splitlines()[0] if str(e) else "", flush=True)
"""
py_limits = list(range(100, 424, 6))
py_outcomes = {}
env = dict(os.environ, PYTHONPATH=pythonpath + os.pathsep + os.environ.get("PYTHONPATH", ""))
env.pop("OPENBLAS_NUM_THREADS", None)  # vibro's own choice under a limit is what is tested
for mode in ("from-start", "after-import"):
    for name in ("basin", "attractors"):
        for mb in py_limits:
            if os.path.exists(out):
                os.remove(out)
            tag = f"python vibro.{name} on 2 threads, RLIMIT_AS {mb} MB {mode}"
            try:
                r = subprocess.run(["/usr/bin/python3", "-c", child, str(mb), mode, fig5, name, out],
                                   capture_output=True, text=True, timeout=300, env=env,
                                   preexec_fn=limited(mb) if mode == "from-start" else None)
            except subprocess.TimeoutExpired as e:
                check(f"{tag}: the interpreter ends (returns, raises MemoryError, exits)", False,
                      f"still running after 300 s; stdout {e.stdout!r}")
                break  # the next limits would hang the same way: the test fails now, not in hours
            lines = r.stdout.split("\n")
            ready = "ready" in lines
            result = [ln for ln in lines if ln.startswith("result ")]
            kind = result[-1].split()[1] if result else ("no-start" if not ready else f"exit {r.returncode}")
            py_outcomes.setdefault((mode, name), []).append(kind)
            if not ready:
                check(f"{tag}: an interpreter that cannot start exits with a Python error",
                      r.returncode == 1 and "Error" in r.stderr, f"exit {r.returncode}: {r.stderr[-300:]}")
                continue
            check(f"{tag}: the call returns or raises MemoryError, the interpreter exits 0",
                  r.returncode == 0 and bool(result), f"exit {r.returncode}: {r.stdout[-200:]} {r.stderr[-400:]}")
            check(f"{tag}: no thread-local-storage abort", "thread-local" not in r.stderr, r.stderr[-300:])
            if name == "basin" and os.path.exists(out):
                i = subprocess.run([vibro, "info", out], capture_output=True, text=True, timeout=120)
                check(f"{tag}: the out file left is readable", i.returncode in (0, 2), i.stderr[-300:])
print("python outcomes over", py_limits, "MB:", py_outcomes)
for key, kinds in py_outcomes.items():
    check(f"python {key}: some limit raises MemoryError and some lets the call finish",
          "MemoryError" in kinds and "ok" in kinds, kinds)

finish()
