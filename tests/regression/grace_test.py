#!/usr/bin/python3
"""The stop grace period (docs/reliability.md, "Stop requests"): a stop request that comes while a
library call never returns still ends the process.

An LD_PRELOAD shim (tests/support/hang_flush_shim.cpp) makes the N-th H5Fflush block for ever, as
HDF5's filter pipeline was seen to on a damaged file. vibro cannot poll its stop flag there; after
SIGTERM it must leave on its own once the grace period is over (4 s; 28 s when the call is part of
the final write, which is given more time): exit 130, a message saying why, and the --out file as
it was at its last completed flush (readable, status "running").

Without the grace period the process would hang until killed; the test then fails at its liveness
bound.

usage: grace_test.py VIBRO SHIM SCENES_DIR
"""
import os
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

vibro, shim, scenes = sys.argv[1], sys.argv[2], sys.argv[3]
tmp = tempfile.mkdtemp(prefix="vibro_grace_")
GRACE = 4.0        # vibro's grace period (src/cli/stop_signals.cpp)
FINAL_GRACE = 28.0  # during a final write: the grace period and six extensions of it
LIVENESS = 10.0  # seconds from the signal to the exit, at most (a loaded machine)


def hang_then_stop(name, args, flush, out, grace=GRACE):
    marker = os.path.join(tmp, f"{name}.marker")
    env = dict(os.environ, LD_PRELOAD=shim, VIBRO_TEST_HANG_FLUSH=str(flush),
               VIBRO_TEST_HANG_MARKER=marker)
    p = subprocess.Popen([vibro, *args], env=env, stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not os.path.exists(marker) and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    began = os.path.exists(marker)
    check(f"{name}: the shim's flush {flush} began", began, f"exit {p.poll()}")
    if not began:
        p.kill()
        p.communicate()
        return
    time.sleep(0.3)  # well inside the blocked call
    t0 = time.monotonic()
    p.send_signal(signal.SIGTERM)
    try:
        _, err = p.communicate(timeout=grace + LIVENESS)
    except subprocess.TimeoutExpired:
        p.kill()
        _, err = p.communicate()
        check(f"{name}: gone within {grace + LIVENESS} s of SIGTERM", False, "hung until killed")
        return
    elapsed = time.monotonic() - t0
    check(f"{name}: exit 130", p.returncode == 130, f"exit {p.returncode} {err[-300:]}")
    # It cannot have left by polling its flag (the flush never returns): only the grace period.
    check(f"{name}: left after the grace period ({elapsed:.1f} s)",
          grace - 0.5 <= elapsed <= grace + LIVENESS, f"{elapsed:.2f} s")
    check(f"{name}: says why", "could not be honoured in time" in err, err[-300:])
    info = subprocess.run([vibro, "info", out], capture_output=True, text=True, timeout=60)
    check(f"{name}: the file keeps its last flush (vibro info exit 0)", info.returncode == 0,
          info.stderr[-300:])
    check(f"{name}: status running", "status       running" in info.stdout, info.stdout[:400])


default = os.path.join(scenes, "default.toml")
out = os.path.join(tmp, "simulate.h5")
hang_then_stop("simulate", ["simulate", default, "--set", "run.periods=100000000", "--out", out],
               3, out)
# A basin's flushes: 1 at creation, 2 after each batch of cells (one batch here: 64 cells, under
# the first batch's 256 on any machine), 3 in the final write (the label map and the attractor
# table, under FinalWrite).
fig5 = os.path.join(scenes, "fig05_coexistence.toml")
out = os.path.join(tmp, "basin.h5")
hang_then_stop("basin, a batch of cells", ["basin", fig5, "--grid", "8,8", "--threads", "1",
                                            "--out", out], 2, out)
out = os.path.join(tmp, "basin_final.h5")
hang_then_stop("basin, its final write", ["basin", fig5, "--grid", "8,8", "--threads", "1",
                                           "--out", out], 3, out, FINAL_GRACE)
finish()
