#!/usr/bin/python3
"""Stop requests while a library call never returns, or while vibro waits for a child process
(docs/reliability.md, "Stop requests").

An LD_PRELOAD shim (tests/support/hang_shim.cpp) makes the N-th H5Fflush or H5Dread block for ever,
as HDF5's filter pipeline was seen to on a damaged file.

1. The grace period. An H5Fflush of vibro's own blocks. vibro cannot poll its stop flag there; after
SIGTERM it must leave on its own once the grace period is over (4 s; 28 s when the call is part of
the final write, which is given more time): exit 130, a message saying why, and the --out file as
it was at its last completed flush (readable, status "running").

Without the grace period the process would hang until killed; the test then fails at its liveness
bound.

2. Waiting for a child. The contained test read of a file given to `info` (and every other reader)
runs in a child process, and `vibro plot` draws in one: a stop request must end the wait within a
second (LIVENESS_CHILD), kill the child, exit 130 and write nothing. The campaign found `info` of a
damaged file finishing 1.7 s after SIGTERM with exit 0: the test read took seconds, and the wait for
it did not poll the stop flag.

usage: grace_test.py VIBRO SHIM SCENES_DIR
"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

vibro, shim, scenes = sys.argv[1], sys.argv[2], sys.argv[3]
tmp = tempfile.mkdtemp(prefix="vibro_grace_")
markers = tempfile.mkdtemp(prefix="vibro_grace_markers_")  # apart from the files watched
GRACE = 4.0        # vibro's grace period (src/cli/stop_signals.cpp)
FINAL_GRACE = 28.0  # during a final write: the grace period and six extensions of it
LIVENESS = 10.0  # seconds from the signal to the exit, at most (a loaded machine)
LIVENESS_CHILD = 1.5  # a stop during a child's wait: vibro promises a second


def marker_written(marker):
    """The shim writes the stuck process's id and a newline just after creating the marker."""
    try:
        with open(marker) as f:
            return f.read().endswith("\n")
    except FileNotFoundError:
        return False


def children(pid):
    """The process ids of pid's children."""
    try:
        return [int(c) for t in os.listdir(f"/proc/{pid}/task")
                for c in open(f"/proc/{pid}/task/{t}/children").read().split()]
    except (FileNotFoundError, ProcessLookupError):
        return []


def start_stuck(name, args, hang):
    """Starts vibro with the shim (`hang`: its VIBRO_TEST_HANG_* setting) and waits until the call
    that never returns has begun. Returns the process and the id of the process that is stuck in
    the call, or None (checked) when the call never began."""
    marker = os.path.join(markers, "".join(c if c.isalnum() else "_" for c in name) + ".marker")
    assert not os.path.exists(marker), name  # one marker per case
    env = dict(os.environ, LD_PRELOAD=shim, VIBRO_TEST_HANG_MARKER=marker, **hang)
    p = subprocess.Popen([vibro, *args], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                         text=True, cwd=tmp)
    deadline = time.monotonic() + 300  # a loaded machine
    while not marker_written(marker) and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    began = marker_written(marker)
    check(f"{name}: the call that never returns began", began, f"exit {p.poll()}")
    if not began:
        p.kill()
        p.communicate()
        return None
    with open(marker) as f:
        return p, int(f.read().split()[0])


def hang_then_stop(name, args, flush, out, grace=GRACE):
    started = start_stuck(name, args, {"VIBRO_TEST_HANG_FLUSH": str(flush)})
    if started is None:
        return
    p, _ = started
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
hang_then_stop("simulate", ["simulate", default, "--time-limit", "0", "--set", "run.periods=100000000", "--out", out],
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


def stop_child_wait(name, args, hang, files_before):
    started = start_stuck(name, args, hang)
    if started is None:
        return
    p, child = started
    time.sleep(0.2)
    check(f"{name}: the stuck call is in a child", child != p.pid, f"pid {child}")
    t0 = time.monotonic()
    p.send_signal(signal.SIGTERM)
    try:
        _, err = p.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        for pid in (p.pid, child):  # the stuck child holds the pipes too
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        _, err = p.communicate()
    elapsed = time.monotonic() - t0
    check(f"{name}: exit 130", p.returncode == 130, f"exit {p.returncode} {err[-300:]}")
    check(f"{name}: within {LIVENESS_CHILD} s of SIGTERM ({elapsed:.2f} s)", elapsed <= LIVENESS_CHILD,
          f"{elapsed:.2f} s")
    check(f"{name}: says so", "interrupted by a stop request" in err, err[-300:])
    try:
        os.kill(child, 0)
        gone = False
    except ProcessLookupError:
        gone = True
    check(f"{name}: the child is gone", gone, f"pid {child} still exists")
    check(f"{name}: nothing written", sorted(os.listdir(tmp)) == files_before,
          sorted(set(os.listdir(tmp)) ^ set(files_before)))


# A finished run to read (made without the shim).
done = os.path.join(tmp, "done.h5")
subprocess.run([vibro, "simulate", default, "--set", "run.periods=20", "--out", done],
               capture_output=True, timeout=120, check=True)
before = sorted(os.listdir(tmp))
# `info`: the first H5Dread of the test read (in the child) never returns.
stop_child_wait("info, its test read", ["info", done], {"VIBRO_TEST_HANG_READ": "1"}, before)
# `plot`: the plotting process is a Python child (h5py calls HDF5 through its own binding, which
# the shim does not reach): SIGTERM while it draws; its pictures are removed.
p = subprocess.Popen([vibro, "plot", done, "--out", os.path.join(tmp, "pic")],
                     stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
deadline = time.monotonic() + 300  # until the Python child runs (drawing takes about 3 s)
while not children(p.pid) and p.poll() is None and time.monotonic() < deadline:
    time.sleep(0.01)
t0 = time.monotonic()
p.send_signal(signal.SIGTERM)
_, err = p.communicate(timeout=30)
elapsed = time.monotonic() - t0
check("plot: exit 130 on SIGTERM while drawing", p.returncode == 130, f"exit {p.returncode} {err[-300:]}")
check(f"plot: within {LIVENESS_CHILD} s ({elapsed:.2f} s)", elapsed <= LIVENESS_CHILD, f"{elapsed:.2f} s")
check("plot: no picture left", not [f for f in os.listdir(tmp) if f.startswith("pic")],
      [f for f in os.listdir(tmp) if f.startswith("pic")])

# 3. Files from the campaign whose damaged variable-length lengths made the test read ask HDF5 for
# up to 23 GB (78 s, the machine's memory; the wait for it outlived SIGTERM). The test read's
# address space is limited: refused at once, exit 2, the file unchanged.
corrupt = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corrupt")
for name in ("vlen_length_23gb.h5", "vlen_length_slow.h5"):
    path = os.path.join(tmp, name)
    shutil.copy(os.path.join(corrupt, name), path)
    with open(path, "rb") as f:
        data = f.read()
    t0 = time.monotonic()
    r = subprocess.run([vibro, "info", path], capture_output=True, text=True, timeout=300)
    elapsed = time.monotonic() - t0
    check(f"{name}: exit 2", r.returncode == 2, f"exit {r.returncode} {r.stderr[-300:]}")
    check(f"{name}: refused within 5 s ({elapsed:.2f} s)", elapsed < 5, f"{elapsed:.2f} s")
    check(f"{name}: names the file", path in r.stderr, r.stderr[-300:])
    with open(path, "rb") as f:
        check(f"{name}: unchanged", f.read() == data)
finish()
