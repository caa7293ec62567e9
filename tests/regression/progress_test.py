#!/usr/bin/python3
"""The progress of long commands on stderr (src/cli/progress.cpp, docs/cli.md): on a terminal (a
pty) a bar redrawn in place with the rate and the time left; to a pipe whole lines only (no \\r,
a final newline), at most one every 5 seconds, none for a short command, and a last line after an
interruption; nothing with --json.
"""
import os
import pty
import re
import select
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

vibro, scenes = sys.argv[1], sys.argv[2]
fig8 = os.path.join(scenes, "fig08_preload.toml")
endless = ["simulate", fig8, "--set", "run.periods=1000000000", "--set", "run.samples_per_period=0", "--time-limit",
           "0"]
LINE_SECONDS = 5.0

# --- stderr a pipe: whole lines ----------------------------------------------------------------------
start = time.time()
proc = subprocess.Popen([vibro, *endless], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
lines = []
while len(lines) < 2:  # two progress lines seen: at least one interval has passed
    line = proc.stderr.readline()
    if not line:
        break
    lines.append(line)
proc.send_signal(signal.SIGINT)
_, rest = proc.communicate(timeout=300)
elapsed = time.time() - start
err = b"".join(lines) + rest
text = err.decode()
check("pipe: interrupted (exit 130)", proc.returncode == 130, (proc.returncode, text[-500:]))
check("pipe: no carriage return", b"\r" not in err, repr(text[:300]))
check("pipe: no escape sequence", b"\x1b" not in err, repr(text[:300]))
check("pipe: ends with a newline", err.endswith(b"\n"), repr(text[-200:]))
progress = [l for l in text.splitlines() if l.startswith("simulate:")]
pattern = re.compile(r"^simulate: +(\d+)% \((\d+) / 1000000000\)(, [0-9.e+]+/s, .+ left| after [0-9.]+ s)$")
check("pipe: progress lines", len(progress) >= 3, text[-800:])
check("pipe: every progress line whole and well formed", all(pattern.match(l) for l in progress), progress)
done = [int(pattern.match(l).group(2)) for l in progress if pattern.match(l)]
check("pipe: counts never decrease", all(a <= b for a, b in zip(done, done[1:])), done)
check("pipe: the rate and time left", all(", " in l and "/s" in l and " left" in l for l in progress[:-1]), progress)
check("pipe: a last line after the interruption", progress[-1].endswith(" s") and " after " in progress[-1],
      progress[-1:])
# The first line comes after LINE_SECONDS and then at most one per LINE_SECONDS (the last one aside).
check("pipe: at most one line every 5 s", len(progress) - 1 <= elapsed / LINE_SECONDS, (len(progress), elapsed))
check("pipe: the interruption reported after the progress", "interrupted" in text.splitlines()[-1], text[-300:])

# A short command writes no progress; --json none either.
p = subprocess.run([vibro, "simulate", fig8], capture_output=True, text=True, timeout=300)
check("pipe: a short run writes nothing on stderr", p.returncode == 0 and p.stderr == "", repr(p.stderr))
proc = subprocess.Popen([vibro, *endless, "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
time.sleep(2 * LINE_SECONDS)
proc.send_signal(signal.SIGINT)
out, err = proc.communicate(timeout=300)
check("--json: no progress", b"simulate:" not in err and proc.returncode == 130, err[-300:])

# validate wrote "\r1 of 2 points" to any stderr: now whole lines only.
with tempfile.TemporaryDirectory() as d:
    branch = os.path.join(d, "claims.csv")
    with open(branch, "w") as f:
        f.write("value,time,displacement_1,velocity_1\n1.2,0.0,1.5,0.0\n1.3,0.0,1.5,0.0\n")
    p = subprocess.run([vibro, "validate", fig8, branch, "--param", "excitation.amplitude"],
                       capture_output=True, text=True, timeout=600)
    check("validate: ran", p.returncode in (0, 4), (p.returncode, p.stderr))
    check("validate: no carriage return on a pipe", "\r" not in p.stderr, repr(p.stderr))

# --- stderr a terminal: a bar with the rate and the time left ------------------------------------
master, slave = pty.openpty()
proc = subprocess.Popen([vibro, *endless], stdout=subprocess.PIPE, stderr=slave)
os.close(slave)
seen = b""
deadline = time.time() + 300
while time.time() < deadline and b" left" not in seen.split(b"\r")[-1]:
    ready, _, _ = select.select([master], [], [], 1.0)
    if ready:
        try:
            seen += os.read(master, 65536)
        except OSError:
            break
proc.send_signal(signal.SIGINT)
proc.communicate(timeout=300)
while True:
    ready, _, _ = select.select([master], [], [], 1.0)
    if not ready:
        break
    try:
        chunk = os.read(master, 65536)
    except OSError:
        break
    if not chunk:
        break
    seen += chunk
os.close(master)
text = seen.decode(errors="replace")
frames = [f for f in text.split("\r") if f.startswith("simulate [")]
check("terminal: redrawn in place", len(frames) >= 2, repr(text[:300]))
bar = re.compile(r"^simulate \[[# ]{30}\] +\d+% \(\d+ / 1000000000\), [0-9.e+]+/s, .+ left\x1b\[K")
check("terminal: bar with rate and time left", any(bar.match(f) for f in frames), frames[-3:])
check("terminal: the line ended after the run", "\x1b[K\r\n" in text or "\x1b[K\n" in text, repr(text[-200:]))

finish()
