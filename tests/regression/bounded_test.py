#!/usr/bin/python3
"""Bounded memory and time for every input (issue 38): a 1-DOF two-sided clearance of 1e-9 with
r = 1 and starting velocity 1 has about 10⁹ impacts per time unit.

- by default (--time-limit one day) `simulate` ends within seconds with exit 3 and one line naming
  the rate, with or without --out (the file stays readable);
- with --time-limit 0 the run goes on in bounded memory: under `ulimit -v` at the process's start
  plus 256 MB for the events and 200 MB to spare it keeps running while it holds more events than
  the limit could store (interrupted: exit 130 and its counts);
- under a limit the events cannot fit in, the refused allocation is exit 3 with one line, never
  exit 1, and an --out file stays readable.
"""
import os
import re
import resource
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

vibro = sys.argv[1]
tmp = tempfile.mkdtemp(prefix="vibro_bounded_")
scene = os.path.join(tmp, "tiny_gap.toml")
with open(scene, "w") as f:
    f.write("""title = "two-sided clearance of 1e-9, r = 1"
[structure]
mass = [[1.0]]
stiffness = [[1.0]]
forcing_dof = 0
[[contact]]
dof = 0
side = "below"
position = -0.5e-9
restitution = 1.0
[[contact]]
dof = 0
side = "above"
position = 0.5e-9
restitution = 1.0
[excitation]
amplitude = 5.0
frequency = 0.8
[initial]
displacement = [0.0]
velocity = [1.0]
[run]
periods = 20
""")
MB = 1 << 20


def status(pid):
    fields = {}
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                k, _, v = line.partition(":")
                fields[k] = v.strip()
    except OSError:
        return {}
    return {k: int(v.split()[0]) * 1024 for k, v in fields.items() if v.endswith("kB")}


# Every library the executable needs (ldd): the baseline is taken once all are mapped. Taken when
# libvibro alone was mapped, it was 11 MB instead of 70 MB now and then, and every limit below
# "base + N MB" was 60 MB tighter than it says.
needed = [os.path.realpath(l.split("=>")[1].split("(")[0].strip())
          for l in subprocess.run(["ldd", vibro], capture_output=True, text=True).stdout.splitlines()
          if "=>" in l and "/" in l.split("=>")[1]]


def loaded(pid):
    try:
        with open(f"/proc/{pid}/maps") as f:
            maps = f.read()
        return "libvibro" in maps and all(n in maps for n in needed)
    except OSError:
        return False


def baseline():
    """The address space of a running `vibro simulate` of the scene, its libraries loaded."""
    p = subprocess.Popen([vibro, "simulate", scene, "--time-limit", "0"], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    size = None
    while p.poll() is None and size is None:
        if loaded(p.pid):
            size = status(p.pid).get("VmSize")
    p.kill()
    p.wait()
    return size


def cpu_seconds(pid):
    """The CPU time (user + system) of process `pid` so far, or None once it has ended."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return None


def limited(limit):
    return lambda: resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def one_line(err):
    lines = [l for l in err.splitlines() if l.strip()]
    return len(lines) == 1, lines


base = baseline()
check("baseline measured", base is not None and base > 0, base)

# ---- the default limit: exit 3 and one line, at once ----
limit = base + 256 * MB + 200 * MB
for out in (None, os.path.join(tmp, "rate.h5")):
    args = [vibro, "simulate", scene] + (["--out", out] if out else [])
    t0 = time.monotonic()
    p = subprocess.run(args, capture_output=True, text=True, timeout=600, preexec_fn=limited(limit))
    took = time.monotonic() - t0
    what = "--out" if out else "no --out"
    check(f"rate ({what}): exit 3", p.returncode == 3, (p.returncode, p.stderr[-500:]))
    single, lines = one_line(p.stderr)
    check(f"rate ({what}): one line", single, lines)
    check(f"rate ({what}): names 10⁹ impacts per time unit and the limit",
          re.match(r"^vibro: 1\.0·10⁹ impacts per time unit: .*--time-limit", p.stderr or "") is not None, p.stderr)
    check(f"rate ({what}): well within a minute of work", took < 120, took)
    if out:
        i = subprocess.run([vibro, "info", out], capture_output=True, text=True, timeout=120)
        check("rate: the --out file stays readable (info exit 0)", i.returncode == 0, (i.returncode, i.stderr))

# ---- no time limit: bounded memory, the run goes on ----
p = subprocess.Popen([vibro, "simulate", scene, "--time-limit", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                     text=True, preexec_fn=limited(limit))
rss0 = None
filled = None  # the process's CPU time when the events held reached 240 MB
peak = 0
while p.poll() is None:
    s = status(p.pid)
    rss = s.get("VmRSS")
    now = cpu_seconds(p.pid)
    if rss is None or now is None:
        continue
    rss0 = rss if rss0 is None else rss0
    peak = max(peak, rss)
    if filled is None and rss - rss0 >= 240 * MB:
        filled = now
    # Past 3 times the CPU time it took to fill 240 MB: more events than the limit can hold
    # (checked below from the counts). CPU time, not wall time: under a load of 15 the wall-time
    # rule stopped the run at 4.6 M impacts, short of the 4.8 M the check needs. 2.5 times fell
    # 3 % short once an event carried a compliant phase's peak_time and penetration_max (240 MB
    # fill with fewer events).
    if filled is not None and now >= 3.0 * filled:
        break
    time.sleep(0.05)
running = p.poll() is None
p.send_signal(signal.SIGINT)
out, err = p.communicate(timeout=600)
check("no limit: still running once past the room of the limit", running, (p.returncode, err[-500:]))
check("no limit: interrupted, exit 130", p.returncode == 130, (p.returncode, err[-500:]))
m = re.search(r"^events +(\d+) impacts", out, re.M)
check("no limit: the counts are printed", m is not None, out[:500])
if m:
    impacts = int(m.group(1))
    # An event takes at least 100 bytes in memory: these could not all be held under the limit.
    check("no limit: more events than the limit could hold", impacts * 100 > limit - base, (impacts, limit - base))
check("no limit: resident memory within the 256 MB bound", peak - (rss0 or 0) < 256 * MB + 64 * MB,
      (peak - (rss0 or 0)) / MB)

# ---- a limit the events cannot fit in: the refused allocation is exit 3, one line ----
small = base + 100 * MB
for out in (None, os.path.join(tmp, "memory.h5")):
    args = [vibro, "simulate", scene, "--time-limit", "0"] + (["--out", out] if out else [])
    p = subprocess.run(args, capture_output=True, text=True, timeout=600, preexec_fn=limited(small))
    what = "--out" if out else "no --out"
    check(f"memory ({what}): exit 3, not 1", p.returncode == 3, (p.returncode, p.stderr[-500:]))
    # With --out the disk's free space may refuse the run first (the file would need 10¹¹ bytes).
    said = "out of memory" in p.stderr or (out is not None and "its disk has" in p.stderr)
    check(f"memory ({what}): out of memory (or the disk) said", said, p.stderr[-500:])
    check(f"memory ({what}): no internal error", "internal error" not in p.stderr, p.stderr[-500:])
    if out:
        i = subprocess.run([vibro, "info", out], capture_output=True, text=True, timeout=120)
        check("memory: the --out file stays readable (info exit 0)", i.returncode == 0, (i.returncode, i.stderr))

# ---- limits that leave HDF5 itself short (its writes, its exit(-1), its clean-up at exit) ----
# Under a few MB over the baseline the file's own writes fail for want of memory: HDF5 1.10 then
# returned "could not write", ended the process with exit(-1), or crashed closing the failed file
# at exit (SIGSEGV, about 1 run in 100 over these limits before the fix).
outcomes = {}
for k in range(60):
    tight = base + (3 + k) * MB
    out = os.path.join(tmp, f"tight{k % 2}.h5")
    if os.path.exists(out):
        os.remove(out)
    p = subprocess.run([vibro, "simulate", scene, "--time-limit", "0", "--out", out], capture_output=True, text=True,
                       timeout=600, preexec_fn=limited(tight))
    outcomes[p.returncode] = outcomes.get(p.returncode, 0) + 1
    single, lines = one_line(p.stderr)
    check(f"tight limit base + {3 + k} MB: exit 3 with one line", p.returncode == 3 and single,
          (p.returncode, p.stderr[-500:]))
    check(f"tight limit base + {3 + k} MB: out of memory said", "out of memory" in p.stderr, p.stderr[-300:])
    if os.path.exists(out):
        i = subprocess.run([vibro, "info", out], capture_output=True, text=True, timeout=120)
        check(f"tight limit base + {3 + k} MB: the file left is readable or refused as unfinished",
              i.returncode in (0, 2) and "corrupt" not in i.stderr, (i.returncode, i.stderr[-300:]))
print("tight limits, exit codes:", outcomes)

finish()
