#!/usr/bin/python3
"""Out of memory inside worker threads (issue 38): the commands that compute on several threads
(basin and attractors on TBB; sweep; simulate's write-behind thread) run under `ulimit -v` limits from barely enough to start up to comfortable, end with exit 0
or exit 3 and one line, never exit 1, a
traceback of another kind, or death by a signal (std::terminate on an exception escaping a
thread); an --out file left is readable or absent.

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
        check(f"{tag}: exit 0, 2 or 3", r.returncode in (0, 2, 3), f"exit {r.returncode}: {r.stderr[-400:]}")
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

finish()
