#!/usr/bin/python3
"""Hardening through the real `vibro` binary (docs/reliability.md):

- stop requests: SIGTERM (and SIGINT) to every long command at several moments: exit 130, the
  --out file valid with status "interrupted" and what was computed (a continuation branch kept is
  the start of the uninterrupted branch); two signals in a row while the final write runs;
- bad input exits 2, creates nothing and changes nothing: deep TOML keys and nesting, wrapped
  integer indices, non-finite and out-of-range option values, extra TOML in --set, /dev/zero as a
  scene, huge grids, corrupt files given to --resume (extra columns in /section/X, a flipped count
  in a basin file, random bit flips);
- `continue` says the same thing in its exit code and in its file.

Signals are sent at moments the process shows: after its line "vibro: ready for stop requests"
(VIBRO_SIGNAL_READY=1: the handlers are in place), and for the later moments after the --out file
exists or holds rows, then a delay counted in the process's own CPU time; never at a fixed wall
time from the start, which a loaded machine stretches. The time limits below are liveness bounds (a command that ignores a stop request would
hang until killed), not speed measurements, with margins for a load of 8 on 2 cores.

usage: hardening_test.py VIBRO SCENES_DIR
"""
import hashlib
import json
import os
import random
import select
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

vibro, scenes = sys.argv[1], sys.argv[2]
default = os.path.join(scenes, "default.toml")
fig5 = os.path.join(scenes, "fig05_coexistence.toml")
chain3 = os.path.join(scenes, "chain3.toml")
tmp = tempfile.mkdtemp(prefix="vibro_hardening_")
LIVENESS = 15.0  # seconds from the signal to the exit, at most (a second of work, on a loaded machine)
SHOWN = 300.0  # seconds to wait for the state a signal waits for (the ready line, a file, rows)


def run(*args, timeout=120):
    return subprocess.run([vibro, *args], capture_output=True, text=True, timeout=timeout)


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def status(path):
    with h5py.File(path, "r") as f:
        s = f.attrs["status"]
        return s.decode() if isinstance(s, bytes) else s


def file_exists(path):
    return lambda: os.path.exists(path)


def rows_at_least(path, dataset, n):
    """True once the file (written without a lock, so read while it grows) holds n rows."""
    def shown():
        try:
            with h5py.File(path, "r") as f:
                return dataset in f and f[dataset].shape[0] >= n
        except Exception:  # not created yet, or met a flush in progress: look again
            return False
    return shown


def cpu_seconds(pid):
    """CPU time (user + system, all threads) the process has used so far."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def wait_ready(p):
    """Reads stderr up to vibro's ready line (the stop handlers are installed); returns what it
    read, or None when the process ended or SHOWN s passed first."""
    fd, seen, deadline = p.stderr.fileno(), b"", time.monotonic() + SHOWN
    while b"vibro: ready for stop requests\n" not in seen:
        left = deadline - time.monotonic()
        if left <= 0 or not select.select([fd], [], [], left)[0]:
            return None
        chunk = os.read(fd, 4096)
        if not chunk:
            return None
        seen += chunk
    return seen


def interrupt(args, delay, sig=signal.SIGTERM, repeat=1, gap=0.0, after=None):
    """Starts vibro, waits for its ready line and then (when given) for the condition `after`,
    sends `sig` once the process has used `delay` more seconds of CPU (`repeat` times, `gap` s
    apart); returns (exit code, seconds from the first signal to the exit, stderr). The exit
    code is None when the process ended before the moment came or did not end within 120 s of
    the signal."""
    env = dict(os.environ, VIBRO_SIGNAL_READY="1")
    p = subprocess.Popen([vibro, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    head = wait_ready(p)
    deadline = time.monotonic() + SHOWN
    while head is not None and after is not None and not after():
        if p.poll() is not None or time.monotonic() > deadline:
            head = None
            break
        time.sleep(0.02)
    # Then `delay` s of the process's own CPU time, which a loaded machine does not shorten.
    try:
        until = cpu_seconds(p.pid) + delay if head is not None else 0.0
        while head is not None and delay > 0 and cpu_seconds(p.pid) < until:
            if p.poll() is not None or time.monotonic() > deadline:
                break
            time.sleep(0.01)
    except OSError:  # the process is gone
        pass
    if head is None:
        p.kill()
        _, err = p.communicate()
        return None, 0.0, f"the moment to signal never came (exit {p.returncode}): " + err.decode(errors="replace")
    t0 = time.monotonic()
    for i in range(repeat):
        if p.poll() is None:
            p.send_signal(sig)
        if i + 1 < repeat:
            time.sleep(gap)
    try:
        _, err = p.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        p.kill()
        _, err = p.communicate()
        return None, 120.0, err.decode(errors="replace")
    return p.returncode, time.monotonic() - t0, (head + err).decode(errors="replace")


# ---- stop requests, every long command, several moments ----
long_commands = {
    "simulate": (["simulate", default, "--time-limit", "0", "--set", "run.periods=100000000"], "/section/t"),
    "simulate-cvode": (["simulate", default, "--time-limit", "0", "--set", "run.periods=100000000", "--set", 'run.engine="cvode"'],
                       "/section/t"),
    "continue": (["continue", chain3, "--param", "excitation.frequency", "--to", "0.3", "--step", "1e-4",
                  "--max-points", "100000"], "/branch/value"),
    "partition": (["partition", chain3, "--params", "excitation.amplitude,excitation.frequency", "--range1",
                   "0.9,1.1", "--range2", "0.3,0.8", "--steps1", "4", "--sticking-fraction", "0.3,0.5"],
                  "/partition/column_status"),
    "attractors": (["attractors", fig5, "--samples", "100000", "--threads", "2"], None),
    "basin": (["basin", fig5, "--grid", "400,400", "--threads", "2"], "/basin/cells/index"),
    "sweep": (["sweep", fig5, "--param", "excitation.frequency", "--from", "1", "--to", "3", "--steps",
               "1000000"], "/sweep/value"),
}
# Moments: just after the handlers are installed (the scene and the options are still being read),
# and 0.4 s and 1.5 s of CPU after the --out file appeared (after the ready line for attractors).
for name, (args, dataset) in long_commands.items():
    for delay, sig in ((0.0, signal.SIGTERM), (0.4, signal.SIGTERM), (1.5, signal.SIGTERM), (0.4, signal.SIGINT)):
        if True:
            out = os.path.join(tmp, f"{name}.h5")
            if os.path.exists(out):
                os.remove(out)
            full = args + (["--out", out] if dataset else [])
            rc, took, err = interrupt(full, delay, sig, after=file_exists(out) if dataset and delay > 0 else None)
            tag = f"{name} {signal.Signals(sig).name} {delay} s of CPU after " + (
                "the --out file appeared" if dataset and delay > 0 else "the ready line")
            check(f"{tag}: exit 130", rc == 130, f"exit {rc}, stderr {err[-500:]}")
            check(f"{tag}: stops within {LIVENESS} s", took < LIVENESS, f"{took:.2f} s")
            if dataset and os.path.exists(out):
                check(f"{tag}: file status interrupted", status(out) == "interrupted", status(out))
                with h5py.File(out, "r") as f:
                    check(f"{tag}: {dataset} kept", dataset in f, list(f.keys()))
            elif dataset and delay > 0:
                check(f"{tag}: --out written", False, "no file")

# The branch kept by an interrupted continuation is the start of the uninterrupted branch.
out = os.path.join(tmp, "branch.h5")
rc, _, err = interrupt(long_commands["continue"][0] + ["--out", out], 1.5, after=file_exists(out))
with h5py.File(out, "r") as f:
    kept = f["/branch/value"][:]
    kept_sp = f["/branch/sticking_fraction"][:]
check("continue: interrupted branch has points", rc == 130 and len(kept) > 2, f"{rc} {len(kept)}")
if len(kept) > 2:
    full = os.path.join(tmp, "branch_full.h5")
    n = len(kept)
    r = run("continue", chain3, "--param", "excitation.frequency", "--to", "0.3", "--step", "1e-4",
            "--max-points", str(n), "--out", full)
    with h5py.File(full, "r") as f:
        ref, ref_sp = f["/branch/value"][:], f["/branch/sticking_fraction"][:]
    check("continue: kept branch = first points of the uninterrupted branch",
          len(ref) == n and np.array_equal(ref, kept) and np.array_equal(ref_sp, kept_sp),
          f"{len(ref)} vs {n}")

# Two signals in a row (the second lands in the final write): the file stays whole.
for gap in (0.0, 0.002, 0.02, 0.1):
    out = os.path.join(tmp, "double.h5")
    if os.path.exists(out):
        os.remove(out)
    rc, took, err = interrupt(["simulate", default, "--time-limit", "0", "--set", "run.periods=100000000", "--out", out], 0.5,
                              signal.SIGINT, repeat=2, gap=gap, after=file_exists(out))
    check(f"two SIGINTs {gap} s apart: exit 130", rc == 130, f"{rc} {err[-300:]}")
    with h5py.File(out, "r") as f:
        rows = f["/section/t"].shape[0]
        check(f"two SIGINTs {gap} s apart: file complete", status(out) == "interrupted" and rows > 0 and
              "checkpoint" in f and f["/checkpoint"].attrs.get("period") is not None, f"{status(out)} {rows}")
    r = run("info", out)
    check(f"two SIGINTs {gap} s apart: vibro info reads the file", r.returncode == 0, r.stderr[-300:])

# ---- continue: exit code and file status agree ----
out = os.path.join(tmp, "noorbit.h5")
r = run("continue", os.path.join(scenes, "chain10_stiff.toml"), "--param", "excitation.amplitude", "--to",
        "0.01", "--out", out)
expected = {0: "ok", 3: "numerical-failure", 130: "interrupted"}
check("continue: exit code matches the file status", expected.get(r.returncode) == status(out),
      f"exit {r.returncode}, status {status(out)}")


# ---- bad input: exit 2, located message, nothing created ----
def refused(name, args, out=None, located=None):
    if out and os.path.exists(out):
        os.remove(out)
    r = run(*args)
    check(f"{name}: exit 2", r.returncode == 2, f"exit {r.returncode}: {r.stderr[-400:]}")
    check(f"{name}: no Python/C++ crash text", "internal error" not in r.stderr and "terminate" not in r.stderr,
          r.stderr[-400:])
    if located:
        check(f"{name}: message names {located}", located in r.stderr, r.stderr[-400:])
    if out:
        check(f"{name}: nothing created", not os.path.exists(out), out)


def scene_file(name, text):
    path = os.path.join(tmp, name)
    with open(path, "w") as f:
        f.write(text)
    return path


base = open(default).read()
deep_dotted = scene_file("deep_dotted.toml", base + "\n" + ".".join(["a"] * 50000) + " = 1\n")
deep_header = scene_file("deep_header.toml", base + "\n[" + ".".join(["t"] * 50000) + "]\n")
deep_array = scene_file("deep_array.toml", base + "\nx = " + "[" * 100000 + "\n")
deep_inline = scene_file("deep_inline.toml", base + "\nx = " + "{a = " * 100000 + "\n")
deep_quoted = scene_file("deep_quoted.toml", base + "\n" + ".".join(['"q"'] * 50000) + " = 1\n")
out = os.path.join(tmp, "never.h5")
for path in (deep_dotted, deep_header, deep_array, deep_inline, deep_quoted):
    refused(os.path.basename(path), ["simulate", path, "--out", out], out, located=path + ":")
refused("deep --set value", ["model", default, "--set", "structure.frequencies=" + "[" * 100000], located="--set")
refused("deep --set key", ["model", default, "--set", ".".join(["a"] * 50000) + "=1"], located="unknown key")
refused("/dev/zero as a scene", ["simulate", "/dev/zero", "--out", out], out, located="/dev/zero")
refused("extra TOML in --set", ["simulate", default, "--set", "excitation.amplitude=2.5\nrun.periods=1", "--out",
                                out], out, located="one TOML value")
for key in ("structure.contact_dof", "structure.forcing_dof", "structure.modes"):
    refused(f"{key} = 2^32 + 1", ["simulate", os.path.join(scenes, "chain2.toml"), "--set", f"{key}=4294967297",
                                  "--out", out], out, located=key)
refused("run.periods = 2^63 - 1", ["model", default, "--set", "run.periods=9223372036854775807"], located="run.periods")
refused("run.samples_per_period = 2^31", ["model", default, "--set", "run.samples_per_period=2147483648"],
        located="run.samples_per_period")
refused("excitation.amplitude = 1e-310", ["model", default, "--set", "excitation.amplitude=1e-310"],
        located="excitation.amplitude")
for w in ("5e-324", "1.797e308"):
    refused(f"excitation.frequency = {w}", ["model", default, "--set", f"excitation.frequency={w}"],
            located="excitation.frequency")
refused("initial.velocity = 1e300", ["model", default, "--set", "initial.displacement=[1.0]", "--set",
                                     "initial.velocity=[1e300]"], located="initial.velocity")

nonfinite = {
    "sweep --to inf": ["sweep", default, "--param", "excitation.amplitude", "--from", "1", "--to", "inf"],
    "sweep --from nan": ["sweep", default, "--param", "excitation.amplitude", "--from", "nan", "--to", "2"],
    "sweep --to 1e999": ["sweep", default, "--param", "excitation.amplitude", "--from", "1", "--to", "1e999"],
    "continue --to nan": ["continue", default, "--param", "excitation.amplitude", "--to", "nan"],
    "continue --step inf": ["continue", default, "--param", "excitation.amplitude", "--to", "2", "--step", "inf"],
    "basin --x-range nan,1": ["basin", fig5, "--x-range", "nan,1", "--grid", "4,4"],
    "attractors --y-range -inf,1": ["attractors", fig5, "--y-range", "-inf,1", "--samples", "4"],
    "partition --range1 0,inf": ["partition", chain3, "--params", "excitation.amplitude,excitation.frequency",
                                 "--range1", "0,inf", "--range2", "0.3,0.8", "--sticking-fraction", "0.5"],
    "partition --sticking-fraction nan": ["partition", chain3, "--params",
                                          "excitation.amplitude,excitation.frequency", "--range1", "0.9,1",
                                          "--range2", "0.3,0.8", "--sticking-fraction", "nan"],
    "orbit --guess inf,1": ["orbit", default, "--guess", "inf,1"],
    "orbit --guess 1,nan": ["orbit", default, "--guess", "1,nan"],
    "basin --grid 2^31,2": ["basin", fig5, "--grid", "2147483648,2"],
    "basin --grid 65536,65536": ["basin", fig5, "--grid", "65536,65536"],
    "continue --max-points 2^32+1": ["continue", default, "--param", "excitation.amplitude", "--to", "2",
                                     "--max-points", "4294967297"],
    "orbit --period -1": ["orbit", default, "--period", "-1"],
    "sweep --steps 0": ["sweep", default, "--param", "excitation.amplitude", "--from", "1", "--to", "2",
                        "--steps", "0"],
    "attractors --threads -3": ["attractors", fig5, "--threads", "-3"],
}
for name, args in nonfinite.items():
    has_out = args[0] not in ("attractors",)
    refused(name, args + (["--out", out] if has_out else []), out if has_out else None)

# ---- issue 15's reproducers: refused naming the option or key (nothing created), or stopped ----
reproducers = {
    "attractors --y-range -1e300,1e300": (["attractors", fig5, "--y-range", "-1e300,1e300"], "--y-range", False),
    "basin --x-range 0,1e101": (["basin", fig5, "--x-range", "0,1e101", "--grid", "4,4"], "--x-range", True),
    "sweep --from 1e308 --to 1.7e308": (["sweep", default, "--param", "excitation.frequency", "--from", "1e308",
                                         "--to", "1.7e308"], "--from", True),
    "sweep stop.position --to 1.7e308": (["sweep", default, "--param", "stop.position", "--from", "1", "--to",
                                          "1.7e308"], "--to", True),
    "basin excitation.amplitude=5e-324": (["basin", fig5, "--set", "excitation.amplitude=5e-324", "--grid", "4,4"],
                                          "excitation.amplitude", True),
    "simulate excitation.amplitude=1e-310, x = 2": (["simulate", default, "--set", "excitation.amplitude=1e-310",
                                                     "--set", "initial.displacement=[2.0]", "--set",
                                                     "initial.velocity=[0.0]"], "excitation.amplitude", True),
    "simulate excitation.frequency=5e-324": (["simulate", default, "--set", "excitation.frequency=5e-324"],
                                             "excitation.frequency", True),
    "simulate excitation.frequency=1.797e308": (["simulate", default, "--set", "excitation.frequency=1.797e308"],
                                                "excitation.frequency", True),
    "orbit --guess inf,1": (["orbit", default, "--guess", "inf,1"], "--guess", True),
}
for name, (args, where, has_out) in reproducers.items():
    refused(name, args + (["--out", out] if has_out else []), out if has_out else None, located=where)

# Stop requests reach runs started deep inside another computation: the orbit solves of a
# partition's continuations (a root search in a sticking phase at f ~ 1e99 ran 7 s after SIGTERM),
# and a sweep's run of many periods.
deep = {
    "partition at f ~ 1e99": ["partition", chain3, "--params", "excitation.amplitude,excitation.frequency",
                               "--range1", "1e99,1e100", "--range2", "0.3,0.8", "--sticking-fraction", "0.5"],
    "sweep of long runs": ["sweep", default, "--set", "run.periods=100000000", "--param", "excitation.amplitude",
                           "--from", "1.1", "--to", "1.2", "--steps", "2"],
    # One CVODE step that never completes (error tests failing forever at atol = 2.2e-308 in a
    # chattering sequence of the stiff chain): ran 11 minutes after SIGTERM before the right-hand
    # side polled the stop flag.
    "CVODE step at atol 2.2e-308": ["simulate", os.path.join(scenes, "chain10_stiff.toml"), "--set",
                                    'run.engine="cvode"', "--set", "run.atol=2.2e-308", "--set",
                                    "run.periods=100000"],
}
for name, args in deep.items():
    out = os.path.join(tmp, "deep.h5")
    if os.path.exists(out):
        os.remove(out)
    rc, took, err = interrupt(args + ["--out", out], 1.5, after=file_exists(out))
    check(f"{name}: SIGTERM → exit 130", rc == 130, f"exit {rc} {err[-300:]}")
    check(f"{name}: stops within {LIVENESS} s", took < LIVENESS, f"{took:.2f} s")
    check(f"{name}: file status interrupted", os.path.exists(out) and status(out) == "interrupted")

# Without a signal the same run ends by itself: the step's work limit makes the jump fail, and the
# sequence is reported undetermined with the reason (exit 3), never sticking.
out = os.path.join(tmp, "atol.h5")
r = run("simulate", os.path.join(scenes, "chain10_stiff.toml"), "--set", 'run.engine="cvode"', "--set",
        "run.atol=2.2e-308", "--set", "run.periods=50", "--out", out, timeout=120)
check("CVODE atol 2.2e-308: exit 3 naming the work limit",
      r.returncode == 3 and "right-hand-side evaluations in one step" in r.stderr, f"{r.returncode} {r.stderr[-300:]}")

# ---- physics invariants: a run that breaks one is a numerical failure, never ok ----
# f = 1e100 on Fig. 8's scene: the double flight's rounding (1e84) puts the body far below the stop
# at the end of the first flight; it used to be reported ok.
out = os.path.join(tmp, "below.h5")
r = run("simulate", default, "--set", "excitation.amplitude=1e100", "--set", "run.periods=3", "--out", out)
check("f = 1e100: exit 3", r.returncode == 3, f"{r.returncode} {r.stderr[-300:]}")
check("f = 1e100: status numerical-failure naming the cause",
      status(out) == "numerical-failure" and "state below the stop" in r.stderr, r.stderr[-300:])

# A sweep whose run fails ends there with the file's status, the exit code and the last point
# saying so (it used to exit 0 with status ok and a classification of the partial run).
out = os.path.join(tmp, "sweep_fail.h5")
r = run("sweep", default, "--set", 'run.chatter="none"', "--param", "excitation.amplitude", "--from", "1.1", "--to",
        "1.2", "--steps", "2", "--out", out, "--json")
check("failing sweep: exit 3", r.returncode == 3, f"{r.returncode} {r.stderr[-300:]}")
check("failing sweep: file status numerical-failure", status(out) == "numerical-failure", status(out))
with h5py.File(out, "r") as f:
    msg = f.attrs["message"]
    msg = msg.decode() if isinstance(msg, bytes) else msg
check("failing sweep: message names the value", "excitation.amplitude = 1.1" in msg, msg)
last = json.loads(r.stdout.strip().splitlines()[-1])["points"][-1] if r.stdout.strip() else {}
check("failing sweep: the last point has the run's status and no period",
      last.get("status") == "numerical-failure" and last.get("period") is None, str(last)[:300])

# ---- corrupt files given to --resume: exit 2, file untouched ----
run_file = os.path.join(tmp, "run.h5")
rc, _, _ = interrupt(["simulate", default, "--time-limit", "0", "--set", "run.periods=100000000", "--out", run_file], 0.5,
                    after=file_exists(run_file))
check("resume source: interrupted run", rc == 130 and status(run_file) == "interrupted", rc)
resume_args = ["simulate", default, "--time-limit", "0", "--set", "run.periods=100000000", "--resume", "--out"]

wide = os.path.join(tmp, "wide.h5")
shutil.copy(run_file, wide)
with h5py.File(wide, "a") as f:
    for name in ("X", "V"):
        data = f["/section"][name][:]
        del f["/section"][name]
        f["/section"].create_dataset(name, data=np.hstack([data, np.zeros((len(data), 3))]),
                                     maxshape=(None, data.shape[1] + 3), chunks=True)
before = digest(wide)
r = run(*resume_args, wide)
check("/section/X with extra columns: exit 2", r.returncode == 2, f"{r.returncode} {r.stderr[-300:]}")
check("/section/X with extra columns: message names the file", wide in r.stderr, r.stderr[-300:])
check("/section/X with extra columns: file untouched", digest(wide) == before)

short = os.path.join(tmp, "short.h5")
shutil.copy(run_file, short)
with h5py.File(short, "a") as f:
    f["/checkpoint"].attrs["sections"] = np.int64(10 ** 12)
before = digest(short)
r = run(*resume_args, short)
check("checkpoint beyond the tables: exit 2 and untouched", r.returncode == 2 and digest(short) == before,
      f"{r.returncode} {r.stderr[-300:]}")

basin_file = os.path.join(tmp, "basin.h5")
basin_args = ["basin", fig5, "--grid", "400,400", "--threads", "2", "--out", basin_file]  # ~8 s uninterrupted
if os.path.exists(basin_file):  # the long-command runs above used the name: wait for this run's cells
    os.remove(basin_file)
rc, _, _ = interrupt(basin_args, 0.0, after=rows_at_least(basin_file, "/basin/cells/index", 1))
with h5py.File(basin_file, "r") as f:
    cells = f["/basin/cells/index"].shape[0]
check("basin source: interrupted with cells kept", rc == 130 and cells > 0, f"{rc} {cells}")
flipped = os.path.join(tmp, "flipped.h5")
shutil.copy(basin_file, flipped)
with h5py.File(flipped, "a") as f:
    counts = f["/basin/cells/stick_phase_count"]
    if counts.shape[0]:
        counts[0] = 2 ** 30
    had_labels = "labels" in f["/basin"]
before = digest(flipped)
r = run(*basin_args[:-1], flipped, "--resume")
check("basin --resume, flipped count: exit 2", r.returncode == 2, f"{r.returncode} {r.stderr[-300:]}")
check("basin --resume, flipped count: file untouched (labels kept)", digest(flipped) == before and had_labels)

# Random bit flips in the raw bytes of a small interrupted study: any outcome but a crash; a
# refusal leaves the file as it was.
small = os.path.join(tmp, "small.h5")
basin_args = ["basin", fig5, "--grid", "40,40", "--threads", "2", "--out", small]
rc, _, _ = interrupt(basin_args, 0.15, after=file_exists(small))
rng = random.Random(15)
raw = open(small, "rb").read()
for i in range(20):
    data = bytearray(raw)
    for _ in range(rng.randint(1, 8)):
        k = rng.randrange(len(data))
        data[k] ^= 1 << rng.randrange(8)
    path = os.path.join(tmp, f"bits{i}.h5")
    with open(path, "wb") as f:
        f.write(data)
    before = digest(path)
    for args in (["info", path], [*basin_args[:-1], path, "--resume"]):
        try:
            r = run(*args, timeout=120)
            rc = r.returncode
        except subprocess.TimeoutExpired:
            rc = "timeout"
        # Exit 1 only with the message of a file whose damage showed when it was written.
        late = rc == 1 and "cannot write the study" in r.stderr
        check(f"bit flips {i} ({args[0]}): no crash", rc in (0, 2, 130) or late, f"exit {rc} {r.stderr[-300:]}")
        if rc == 2:
            check(f"bit flips {i} ({args[0]}): refused file untouched", digest(path) == before)

shutil.rmtree(tmp, ignore_errors=True)
finish()
