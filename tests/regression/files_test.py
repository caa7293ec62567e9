#!/usr/bin/python3
"""Files vibro writes and reads back, through the real `vibro` binary (docs/reliability.md):

- one writer per file: a second `simulate --out` (with or without --force), a `--resume` of a
  run still running and two `--resume` at once are refused (exit 2, "FILE is in use by process
  N") and the first run is unharmed;
- a disk that fills up during a run (an LD_PRELOAD shim that makes writes to *.h5 fail with
  ENOSPC past a budget; a 3 MiB tmpfs too when this test may mount one): exit 3, one line naming
  the reason and the file, every dataset of the file still readable, and the run resumable;
- damaged and malformed files given to `continue --from`, `--resume` and `info`: exit 2, one line
  naming the file and the dataset.

Waits are for observable states (a file that opens, a status), with generous liveness bounds.

usage: files_test.py VIBRO FULL_DISK_SHIM SCENES_DIR
"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

vibro, shim, scenes = sys.argv[1], sys.argv[2], sys.argv[3]
default = os.path.join(scenes, "default.toml")
fig5 = os.path.join(scenes, "fig05_coexistence.toml")
tmp = tempfile.mkdtemp(prefix="vibro_files_")
LONG = ["--set", "run.periods=100000000"]


def run(*args, env=None, timeout=300):
    return subprocess.run([vibro, *args], capture_output=True, text=True, timeout=timeout, env=env)


def start(*args):
    return subprocess.Popen([vibro, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def attrs(path):
    with h5py.File(path, "r") as f:
        return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}


def wait_for_status(path, wanted, proc, limit=120.0):
    """Waits until `path` opens with h5py and its status is `wanted` (a run under way)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < limit and proc.poll() is None:
        try:
            if attrs(path).get("status") == wanted:
                return True
        except (OSError, KeyError):
            pass  # not there yet, or a flush in progress: retry
        time.sleep(0.05)
    return False


def stop(proc):
    proc.send_signal(signal.SIGTERM)
    try:
        _, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
    return proc.returncode, err


def read_all(path):
    """Reads every dataset and attribute; returns "" or the first failure."""
    try:
        with h5py.File(path, "r") as f:
            dict(f.attrs)

            def visit(name, obj):
                dict(obj.attrs)
                if isinstance(obj, h5py.Dataset):
                    obj[()]
            f.visititems(visit)
        return ""
    except Exception as e:  # noqa: BLE001  (any failure is the finding)
        return repr(e)


def one_line(text):
    return len([l for l in text.strip().splitlines() if l.strip()]) == 1


# ---- one writer per file ----
out = os.path.join(tmp, "same.h5")
first = start("simulate", default, *LONG, "--out", out)
check("lock: the first run starts", wait_for_status(out, "running", first), "no running file")
for name, extra in (("second simulate", []), ("second simulate --force", ["--force"]),
                    ("--resume of a running run", ["--resume"])):
    r = run("simulate", default, *LONG, "--out", out, *extra)
    check(f"lock: {name}: exit 2", r.returncode == 2, f"exit {r.returncode}: {r.stderr[-300:]}")
    check(f"lock: {name}: names the file and the first run's process",
          f"{out} is in use by process {first.pid}" in r.stderr, r.stderr[-300:])
rc, err = stop(first)
check("lock: the first run ends as it would have (exit 130)", rc == 130, f"{rc} {err[-300:]}")
check("lock: the first run's file is whole", read_all(out) == "" and attrs(out)["status"] == "interrupted",
      read_all(out))

# Two resumes at once: the second is refused, the first goes on and its file is whole.
resumed = start("simulate", default, *LONG, "--out", out, "--resume")
check("lock: a resume starts", wait_for_status(out, "running", resumed), "no running file")
r = run("simulate", default, *LONG, "--out", out, "--resume")
check("lock: a second --resume at once: exit 2 naming the first",
      r.returncode == 2 and f"in use by process {resumed.pid}" in r.stderr, f"{r.returncode} {r.stderr[-300:]}")
rc, err = stop(resumed)
check("lock: the first resume ends as it would have (exit 130, file whole)",
      rc == 130 and read_all(out) == "" and attrs(out)["status"] == "interrupted", f"{rc} {err[-300:]}")

# A basin study still running: its --resume is refused.
bout = os.path.join(tmp, "basin.h5")
basin_args = ["basin", fig5, "--grid", "600,600", "--threads", "1", "--out", bout]
study = start(*basin_args)
check("lock: a basin starts", wait_for_status(bout, "running", study), "no running file")
r = run(*basin_args, "--resume")
check("lock: basin --resume of a running basin: exit 2",
      r.returncode == 2 and f"in use by process {study.pid}" in r.stderr, f"{r.returncode} {r.stderr[-300:]}")
rc, err = stop(study)
check("lock: the running basin is unharmed", rc == 130 and read_all(bout) == "", f"{rc} {err[-300:]}")

# The lock dies with its process: after SIGKILL the file can be resumed at once.
killed = start("simulate", default, *LONG, "--out", out, "--force")
check("lock: a run to kill starts", wait_for_status(out, "running", killed), "no running file")
t0 = time.monotonic()
while time.monotonic() - t0 < 60:  # until a checkpoint is on disk
    try:
        with h5py.File(out, "r") as f:
            if f["/checkpoint"].attrs.get("period") is not None:
                break
    except (OSError, KeyError):
        pass
    time.sleep(0.05)
killed.kill()
killed.communicate()
resumed = start("simulate", default, *LONG, "--out", out, "--resume")
check("lock: no stale lock after SIGKILL (the resume runs)", wait_for_status(out, "running", resumed),
      resumed.stderr.read() if resumed.poll() is not None else "")
stop(resumed)


# ---- a disk that fills up during a run ----
def full_disk_env(budget):
    env = dict(os.environ)
    env["LD_PRELOAD"] = shim
    env["VIBRO_TEST_DISK_BYTES"] = str(budget)
    return env


def filled(name, args, path, budget, resume=None):
    """Runs `args` writing `path` on a disk of `budget` bytes: exit 3, one line, file readable."""
    if os.path.exists(path):
        os.remove(path)
    r = run(*args, env=full_disk_env(budget))
    check(f"full disk: {name}: exit 3", r.returncode == 3, f"exit {r.returncode}: {r.stderr[-400:]}")
    check(f"full disk: {name}: one line naming the reason and the file",
          one_line(r.stderr) and f"no space left on device writing {path}" in r.stderr, r.stderr[-400:])
    if not os.path.exists(path):
        check(f"full disk: {name}: the file is there", False, "no file")
        return
    check(f"full disk: {name}: every dataset of the file readable", read_all(path) == "", read_all(path))
    if resume:
        r = run(*resume)
        check(f"full disk: {name}: resumable once there is room", r.returncode == 0, r.stderr[-400:])
        check(f"full disk: {name}: the resumed file is whole", read_all(path) == "" and
              attrs(path)["status"] == "ok", read_all(path))


sim = ["simulate", default, "--set", "run.periods=60000", "--out", os.path.join(tmp, "full.h5")]
for budget in (3_000_000, 6_000_000):
    filled(f"simulate ({budget} bytes)", sim, sim[-1], budget, resume=sim + ["--resume"])
filled("basin", ["basin", fig5, "--grid", "300,300", "--threads", "2", "--out", os.path.join(tmp, "fullb.h5")],
       os.path.join(tmp, "fullb.h5"), 1_500_000)
filled("sweep", ["sweep", fig5, "--param", "excitation.frequency", "--from", "1", "--to", "3", "--steps", "300",
                 "--record", "200", "--out", os.path.join(tmp, "fulls.h5")], os.path.join(tmp, "fulls.h5"),
       1_100_000)

# A real full file system, where this test may mount one (root; skipped elsewhere).
mnt = os.path.join(tmp, "tmpfs")
os.makedirs(mnt)
if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=3m", "tmpfs", mnt], capture_output=True).returncode == 0:
    try:
        path = os.path.join(mnt, "run.h5")
        r = run("simulate", default, "--set", "run.periods=200000", "--out", path)
        check("tmpfs 3 MiB: simulate exit 3 with one line", r.returncode == 3 and one_line(r.stderr) and
              "no space left on device" in r.stderr, f"{r.returncode} {r.stderr[-400:]}")
        check("tmpfs 3 MiB: every dataset readable", read_all(path) == "", read_all(path))
        os.remove(path)
        path = os.path.join(mnt, "basin.h5")
        r = run("basin", fig5, "--grid", "400,400", "--threads", "2", "--out", path)
        check("tmpfs 3 MiB: basin exit 3", r.returncode == 3 and "no space left on device" in r.stderr,
              f"{r.returncode} {r.stderr[-400:]}")
        check("tmpfs 3 MiB: basin file readable", read_all(path) == "", read_all(path))
    finally:
        subprocess.run(["umount", mnt])
else:
    print("tmpfs: cannot mount here; the shim's cases stand for it")

shutil.rmtree(tmp, ignore_errors=True)
finish()
