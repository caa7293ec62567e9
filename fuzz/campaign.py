#!/usr/bin/python3
"""A fuzz campaign through the real `vibro` binary (docs/reliability.md).

Runs the binary thousands of times, one process at a time, on generated inputs:

- mutated scenes: values replaced by corner tokens, lines dropped or repeated, bytes flipped, the
  file cut short;
- CLI misuse: every command with unknown, missing, repeated and out-of-range options;
- numerical extremes: every numeric scene key at the edges of its range, both engines;
- signals: SIGINT or SIGTERM (once or twice) at a random moment during every command;
- corrupt files: bit flips, runs of 0xff and truncations of interrupted runs, studies, sweeps,
  branches and orbits, given to `info`, `plot` and `--resume`.

Each run is judged against what vibro promises:

- no crash: the process ends by exit(), not by a signal it was not sent;
- no hang: a run past its time limit gets SIGTERM and must be gone within LIVENESS seconds of its own
  time (below);
- exit codes 0, 2, 3 and 130 only (4 for `check`/`validate`/`score`, whose methods, claims or runs may disagree,
  and for `prove`: not proven);
- exit 2 creates and changes nothing in the run's directory or the files it was given, and
  its message says where the problem is;
- a signal: exit 130 (or the run had already finished), the --out file readable, with status
  "interrupted";
- a result reported `ok` keeps to the physics: no section point, sample or event below the stop
  beyond tolerance, time increasing, every sticking fraction in [0, 1].

usage: campaign.py VIBRO SCENES_DIR [--runs N] [--seed S] [--minutes M] [--report FILE.json] [--only CATEGORY]
A run that hangs past SIGTERM is reported with the stacks of its threads (gdb, when installed).

How long a stop takes is judged by the program's own time, not by the wall clock (StopClock): its
CPU time after the signal (every thread, and the children it waited for) plus the time during which
none of its threads nor any of its child processes could run (sleeping by its own choice). Time
spent waiting for a CPU on a loaded machine counts in neither, so a stop costing 0.3 s of work that
a load of 19 on 2 cores stretches to 3 s of wall time is on time, and a stop that computes or sleeps
for 2 s is late on a quiet machine and a loaded one alike. The wall clock is only an outer bound
(HANG_WALL, for a program that no clock above can see progressing).
Exits 1 when there are findings; the report lists each with its command line.
"""
import argparse
import hashlib
import json
import os
import random
import shutil
import signal
import resource
import subprocess
import sys
import tempfile
import threading
import time

import h5py
import numpy as np

LIVENESS = 1.0    # seconds of its own time (StopClock) from a stop request to the exit that vibro promises
HANG = 5.0        # past this much of its own time after a stop request the run is a hang
HANG_WALL = 60.0  # past this wall time after a stop request the run is a hang, whatever the clocks say
STARTUP = 0.05  # a signal this soon may come while the loader maps vibro's libraries (10-30 ms loaded)
CORNERS = ["nan", "inf", "-inf", "1e999", "-1e999", "0", "-0.0", "-1", "1", "5e-324", "-5e-324", "1e-310",
           "2.2250738585072014e-308", "1e308", "1.7976931348623157e308", "-1e308", "1e100", "1e-100",
           "4294967297", "9223372036854775807", "-9223372036854775808", "18446744073709551617", "0.5",
           "2", "1e16", "3.0e-17", "true", "\"x\"", "[]", "[1e300]", "[nan]", "[0.0, 0.0]", "{}", "'''",
           "[[", "\"\\u0000\"", "0x7fffffff", "1_000", "+inf", "-nan"]
NUMERIC_KEYS = ["excitation.amplitude", "excitation.frequency", "stop.position", "stop.restitution",
                "initial.time", "run.periods", "run.samples_per_period", "run.max_period", "run.rtol",
                "run.atol", "run.period_tolerance", "run.chatter_switch", "run.chatter_tolerance",
                "run.max_steps", "structure.damping_ratios", "initial.displacement", "initial.velocity"]
EXTREMES = ["1e-100", "1e100", "-1e100", "1e-50", "1e50", "1e-12", "1e12", "0", "0.999999999",
            "1.000000001", "1e-9", "1e9", "-1e-9"]
VECTOR_KEYS = {"structure.damping_ratios", "initial.displacement", "initial.velocity"}
STRINGS = {"run.engine": ["exact", "cvode", "lsoda", ""], "run.chatter": ["accumulation", "threshold", "none", "x"],
           "run.precision": ["double", "quad", "half"], "run.method": ["bdf", "adams", "rk"]}


def default_stop_signals():
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


# ---- The stop clock: a process's own time after a signal -------------------------------------

TICK = 1.0 / os.sysconf("SC_CLK_TCK")
SAMPLE = 0.01  # seconds between two looks at the process's threads


def _stat_fields(path):
    """The fields of a /proc/.../stat line after the command name (which may hold spaces and
    parentheses): [state, ppid, ...]; None once the process is gone."""
    try:
        with open(path, "rb") as f:
            line = f.read().decode(errors="replace")
    except OSError:
        return None
    return line[line.rfind(")") + 2:].split()


def process_cpu(pid):
    """CPU seconds of a process: every thread's, and those of the children it waited for
    (utime + stime + cutime + cstime of /proc/PID/stat); None once it is gone."""
    f = _stat_fields(f"/proc/{pid}/stat")
    if f is None or len(f) < 15:
        return None
    return sum(int(x) for x in f[11:15]) * TICK


def _thread_states(pid):
    try:
        tids = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return []
    out = []
    for tid in tids:
        f = _stat_fields(f"/proc/{pid}/task/{tid}/stat")
        if f:
            out.append(f[0])
    return out


def _descendants(pid):
    """The processes below `pid` (a scan of /proc: done only while pid's own threads all sleep)."""
    parent = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            f = _stat_fields(f"/proc/{name}/stat")
            if f and len(f) > 1:
                parent[int(name)] = int(f[1])
    below, todo = [], [pid]
    while todo:
        p = todo.pop()
        kids = [c for c, pp in parent.items() if pp == p]
        below += kids
        todo += kids
    return below


def runnable(pid):
    """Whether the process, or any process below it, has a thread that is running, waiting for a
    CPU (R) or in an uninterruptible wait, disk I/O mostly (D): then the time passing is not the
    process's own sleep. None once the process is gone (a zombie counts as gone)."""
    states = _thread_states(pid)
    if not states or all(s in "ZX" for s in states):
        return None
    if any(s in "RD" for s in states):
        return True
    return any(s in "RD" for c in _descendants(pid) for s in _thread_states(c))


class StopClock:
    """A process's own time from a stop request to its exit (see the module's docstring): CPU time
    (from the process's /proc stat, or exactly from the caller's rusage once it is reaped) plus the
    wall time during which nothing of it was runnable, sampled every SAMPLE s by a thread."""

    def __init__(self, pid):
        self.pid = pid
        self.wall0 = time.monotonic()
        self.cpu0 = process_cpu(pid)
        # The processes below it at the signal: their CPU so far is not the stop's, but reaches the
        # process's own (cutime) when it waits for them after the signal.
        if self.cpu0 is not None:
            self.cpu0 += sum(x for x in (process_cpu(c) for c in _descendants(pid)) if x is not None)
        self.cpu_last = self.cpu0
        self.idle = 0.0
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True)
        self._thread.start()

    def _sample(self):
        last = time.monotonic()
        while not self._done.wait(SAMPLE):
            now = time.monotonic()
            state = runnable(self.pid)
            if state is None:
                break
            cpu = process_cpu(self.pid)
            if cpu is not None:
                self.cpu_last = cpu
            if state is False:
                self.idle += now - last
            last = now

    def wall(self):
        return time.monotonic() - self.wall0

    def cpu(self):
        if self.cpu0 is None or self.cpu_last is None:
            return 0.0
        # No more than every CPU for the whole wall time (plus two clock ticks of rounding).
        return min(max(0.0, self.cpu_last - self.cpu0), self.wall() * (os.cpu_count() or 1) + 2 * TICK)

    def own(self):
        """The process's own time since the stop request, so far."""
        return self.cpu() + self.idle

    def finish(self, cpu_total=None):
        """Stops the sampling once the process is gone; `cpu_total`: its whole CPU time from its
        rusage (exact, where the sampled value may miss the last 10 ms or, under load, more)."""
        self._done.set()
        self._thread.join()
        if cpu_total is not None and self.cpu0 is not None:
            self.cpu_last = max(cpu_total, self.cpu_last or 0.0)
        return self.own()

    def describe(self):
        return f"{self.own():.2f} s of its own ({self.cpu():.2f} s CPU, {self.idle:.2f} s asleep), {self.wall():.2f} s wall"


def children_cpu():
    """CPU seconds of every child this process has reaped so far."""
    u = resource.getrusage(resource.RUSAGE_CHILDREN)
    return u.ru_utime + u.ru_stime


def wait_stopping(p, clock):
    """Waits for `p` after a stop request, reading its pipes; (stdout, stderr, hung). Hung: past
    HANG s of its own time or HANG_WALL s of wall time, still there (it is left running: the caller
    takes its stacks and kills it)."""
    while True:
        try:
            out, err = p.communicate(timeout=0.1)
            return out, err, False
        except subprocess.TimeoutExpired:
            if clock.own() > HANG or clock.wall() > HANG_WALL:
                return None, None, True


def compliant_scene(text):
    """Whether a scene's text gives a stop a stiffness (a compliant stop, docs/compliant.md)."""
    if isinstance(text, bytes):
        text = text.decode(errors="replace")
    if not text:
        return False
    try:
        import tomllib
        doc = tomllib.loads(text)
    except Exception:  # noqa: BLE001 (unparsable here: judged as rigid)
        return False
    tables = [doc.get("stop")] + list(doc.get("contact") or [])
    return any(isinstance(t, dict) and "stiffness" in t for t in tables)


def backtrace(pid):
    """The stacks of every thread of a hung process (gdb, when installed), for the report."""
    if not shutil.which("gdb"):
        return "(no gdb)"
    try:
        r = subprocess.run(["gdb", "-p", str(pid), "-batch", "-ex", "thread apply all bt 25"],
                           capture_output=True, text=True, timeout=60)
        return "\n".join(l for l in r.stdout.splitlines() if l.startswith(("#", "Thread")))[:6000]
    except (subprocess.TimeoutExpired, OSError) as e:
        return f"(gdb failed: {e})"


_digests = {}  # path → (stat key, digest)


def digest(path):
    """SHA-256 of the file, recomputed only when its inode, size, mtime or ctime changed: every run
    snapshots the whole work directory twice, which grows to gigabytes over a campaign (hashing it
    all made the runs slower and slower)."""
    st = os.stat(path)
    key = (st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)
    cached = _digests.get(path)
    if cached and cached[0] == key:
        return cached[1]
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    _digests[path] = (key, h.hexdigest())
    return _digests[path][1]


def snapshot(paths):
    """Name → digest of every file in the directories and files given."""
    out = {}
    for p in paths:
        if os.path.isdir(p):
            for name in os.listdir(p):
                q = os.path.join(p, name)
                if os.path.isfile(q):
                    out[q] = digest(q)
        elif os.path.isfile(p):
            out[p] = digest(p)
    return out


class Campaign:
    def __init__(self, vibro, scenes, seed, deadline, work):
        self.vibro, self.scenes, self.rng, self.deadline, self.work = vibro, scenes, random.Random(seed), deadline, work
        self.runs = 0
        self.inputs = set()
        self.findings = []
        self.exits = {}
        self.located = [0, 0]  # exit-2 messages that say where, of all exit-2 messages
        self.slow_stops = []   # stop requests honoured in more than LIVENESS s of the program's own time
        self.stop_walls = []   # (wall, own) seconds of every stop, for the report
        self.categories = {}
        self.physics_checked = 0
        self.scene_texts = {name: open(os.path.join(scenes, name)).read()
                            for name in sorted(os.listdir(scenes)) if name.endswith(".toml")}
        self.counter = 0
        self.before_main = 0  # runs ended by a signal sent before the program could install handlers

    def time_left(self):
        return time.monotonic() < self.deadline

    def fresh(self, suffix):
        self.counter += 1
        return os.path.join(self.work, f"f{self.counter}{suffix}")

    def write_scene(self, text):
        path = self.fresh(".toml")
        with open(path, "w", errors="surrogateescape") as f:
            f.write(text)
        return path

    def find(self, kind, argv, detail):
        self.findings.append({"kind": kind, "command": " ".join(repr(a) if " " in a or not a else a for a in argv),
                              "detail": detail[:8000] if "stacks:" in detail else detail[-1500:]})
        shown = detail[:2500] if "stacks:" in detail else detail[-400:]
        print(f"FINDING {kind}: {' '.join(argv)[:300]}\n    {shown}", flush=True)

    # One run of the binary, judged. `signals`: [(delay, signal), ...] sent in order; a delay may be
    # a predicate on the program's pid instead (liveness_test.py: a state the program shows, polled).
    def run(self, category, argv, signals=(), limit=20.0, watch=(), out=None, key=None, content=None):
        self.runs += 1
        self.categories[category] = self.categories.get(category, 0) + 1
        self.inputs.add((tuple(a if not a.startswith(self.work) else "<tmp>" for a in argv), key, content))
        scratch = self.fresh(".d")
        os.mkdir(scratch)
        before = snapshot([scratch, *watch])
        full = [self.vibro, *argv]
        # Default dispositions for the stop signals, whatever this script inherited: started in the
        # background by a shell, SIGINT is ignored, and a SIGINT sent while vibro's libraries are
        # still being loaded (before its handlers exist) would be silently lost, not a hang.
        cpu_before = children_cpu()
        p = subprocess.Popen(full, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=scratch,
                             preexec_fn=default_stop_signals)
        sent, clock, first_after = [], None, None
        start = time.monotonic()
        for delay, sig in signals:
            try:
                if callable(delay):
                    while p.poll() is None and not delay(p.pid):
                        time.sleep(SAMPLE)
                    if p.poll() is None:
                        raise subprocess.TimeoutExpired(full, 0)
                else:
                    p.wait(timeout=max(0.0, start + delay - time.monotonic()))
                break
            except subprocess.TimeoutExpired:
                p.send_signal(sig)
                sent.append(sig)
                if clock is None:
                    clock = StopClock(p.pid)
                    first_after = clock.wall0 - start
        hung = False
        if clock is None:
            try:
                out_, err = p.communicate(timeout=limit)
            except subprocess.TimeoutExpired:  # past its limit: a stop request must end it
                p.send_signal(signal.SIGTERM)
                sent.append(signal.SIGTERM)
                clock = StopClock(p.pid)
        if clock is not None:
            out_, err, hung = wait_stopping(p, clock)
            if hung:
                stacks = backtrace(p.pid)  # (gdb: a child of this process, so no rusage below)
                p.kill()
                out_, err = p.communicate()
                took = clock.finish()
            else:
                # The child's whole CPU time, exactly: it is the only child reaped since cpu_before.
                took = clock.finish(children_cpu() - cpu_before)
                self.stop_walls.append((clock.wall(), took))
        else:
            took = None
        rc = p.returncode
        err = err.decode(errors="replace")
        out_ = out_.decode(errors="replace")
        self.last_stdout = out_  # for the judges of surfaces.py (validate's and score's JSON)
        self.exits[rc] = self.exits.get(rc, 0) + 1
        tag = f"[{category}]"
        if hung:
            self.find("hang ignoring SIGTERM", full,
                      f"{tag} still running after SIGTERM, {clock.describe()} (signals {signals}, sent {sent}); "
                      f"stacks:\n{stacks}")
        elif rc < 0 and -rc in sent and first_after is not None and first_after < STARTUP:
            self.before_main += 1  # the signal came while the program was being loaded
        elif rc < 0:
            self.find("crash" if -rc not in (signal.SIGINT, signal.SIGTERM) else "died of the stop signal", full,
                      f"{tag} killed by signal {-rc}; stderr: {err}")
        else:
            allowed = {0, 2, 3, 130} | ({4} if argv and argv[0] in ("check", "validate", "score", "prove") else set())
            if rc not in allowed:
                self.find(f"exit {rc}", full, f"{tag} {err}")
            if took is not None and took > LIVENESS and rc == 130:
                self.slow_stops.append(took)
                self.find("slow stop", full, f"{tag} exit 130 after {clock.describe()} from the signal; {err[-300:]}")
            if sent and rc not in (130, 2) and took is not None and took > LIVENESS:
                # A run may finish as the signal comes (exit 0 or 3 at once); one that runs on
                # past the liveness bound and then reports no interruption ignored it.
                self.find("stop request ignored", full, f"{tag} exit {rc} after {clock.describe()} from a signal; {err}")
            if rc == 2:
                self.located[1] += 1
                if self.is_located(err, argv):
                    self.located[0] += 1
                else:
                    self.find("exit 2 message without a location", full, f"{tag} {err}")
                after = snapshot([scratch, *watch])
                if after != before:
                    changed = sorted(set(after.items()) ^ set(before.items()))
                    self.find("exit 2 created or changed files", full, f"{tag} {changed[:4]} {err}")
            if rc == 130 and "nothing was written" in err:
                # Stopped before anything was computed (during the test read of a file given):
                # like exit 2, nothing may have been created or changed.
                after = snapshot([scratch, *watch])
                if after != before:
                    changed = sorted(set(after.items()) ^ set(before.items()))
                    self.find("exit 130 said nothing was written, but files changed", full,
                              f"{tag} {changed[:4]} {err}")
            elif out and os.path.exists(out) and rc in (0, 3, 130):
                self.check_file(full, out, rc, tag, err)
            if rc == 0 and "--json" in argv:
                self.check_json(full, out_, tag)
        shutil.rmtree(scratch, ignore_errors=True)
        return rc, err

    @staticmethod
    def is_located(err, argv):
        """A refusal names its source: a file (path:line or the path), an option, a key or the
        --set that carries it."""
        text = err.lower()
        if any(a in err for a in argv if a.startswith("/") or a.endswith((".toml", ".h5"))):
            return True
        # A file given by any name (a path without a slash, or an empty one shown as '').
        if any(a and (err.startswith(a + ":") or ("\n" + a + ":") in err) for a in argv) or "'':" in err:
            return True
        if "--" in err or "line " in text or "run.periods" in err:
            return True
        for key in ("structure.", "excitation.", "stop.", "initial.", "run.", "scene", "option", "argument",
                    "subcommand", "command", "expected", "unknown", "required"):
            if key in text:
                return True
        return False

    def check_file(self, full, path, rc, tag, err=""):
        try:
            with h5py.File(path, "r") as f:
                status = f.attrs.get("status")
                status = status.decode() if isinstance(status, bytes) else status
                want = {0: "ok", 3: ("numerical-failure", "undetermined"), 130: "interrupted"}[rc]
                if rc == 3 and "(--time-limit" in err:  # stopped as on Ctrl-C, then exit 3 (docs/cli.md)
                    want = ("interrupted", "numerical-failure", "undetermined")
                if (status not in want) if isinstance(want, tuple) else status != want:
                    self.find("file status disagrees with the exit code", full, f"{tag} exit {rc}, status {status}")
                if status == "ok":
                    self.check_physics(full, f, tag)
        except OSError as e:
            self.find("--out file unreadable", full, f"{tag} exit {rc}: {e}")

    def check_physics(self, full, f, tag):
        if "model" not in f:
            return
        self.physics_checked += 1
        stop = float(f["model"].attrs["stop"])
        if compliant_scene(f.attrs.get("scene")):
            stop = -np.inf  # a compliant stop is entered: the gap is negative in contact (docs/compliant.md)
        problems = []
        tol = 1e-6 * (1 + abs(stop))
        for group in ("section", "samples"):
            if group in f and "x_B" in f[group] and f[group]["x_B"].shape[0]:
                x = f[group]["x_B"][:]
                scale = 1e-6 * (1 + abs(stop) + np.abs(x).max()) if np.isfinite(x).all() else tol
                engine = f.attrs.get("engine")
                engine = engine.decode() if isinstance(engine, bytes) else engine
                if engine == "cvode":
                    rtol, atol = float(f.attrs.get("rtol", 1e-9)), float(f.attrs.get("atol", 1e-12))
                    scale += 10 * rtol * (1 + abs(stop) + np.abs(x).max()) + 10 * atol
                if not np.isfinite(x).all():
                    problems.append(f"non-finite /{group}/x_B")
                elif x.min() < stop - scale:
                    problems.append(f"/{group}/x_B reaches {x.min():.6g} below the stop {stop} (tol {scale:.2g})")
                t = f[group]["t"][:]
                if len(t) > 1 and not (np.diff(t) > 0).all():
                    problems.append(f"/{group}/t not increasing")
        if "events" in f and "t" in f["events"] and f["events"]["t"].shape[0] > 1:
            t = f["events"]["t"][:]
            if not (np.diff(t) >= 0).all():
                problems.append("/events/t decreasing")
        if "attractor" in f:
            sp = f["attractor"].attrs.get("sticking_fraction")
            if sp is not None and not (0 <= float(sp) <= 1):
                problems.append(f"sticking fraction {sp}")
        for group in ("branch", "sweep"):
            if group in f and "sticking_fraction" in f[group]:
                sp = f[group]["sticking_fraction"][:]
                sp = sp[np.isfinite(sp)]
                if len(sp) and not ((sp >= 0) & (sp <= 1)).all():
                    problems.append(f"/{group}/sticking_fraction outside [0, 1]: {sp.min()}..{sp.max()}")
        if "basin" in f and "cells" in f["basin"] and "sticking_fraction" in f["basin"]["cells"]:
            sp = f["basin"]["cells"]["sticking_fraction"][:]
            sp = sp[np.isfinite(sp)]
            if len(sp) and not ((sp >= 0) & (sp <= 1)).all():
                problems.append("/basin/cells/sticking_fraction outside [0, 1]")
        if problems:
            self.find("ok result violating the physics", full, f"{tag} {'; '.join(problems)}")

    def check_json(self, full, text, tag):
        try:
            doc = json.loads(text.strip().splitlines()[-1]) if text.strip() else None
        except (json.JSONDecodeError, IndexError):
            return
        bad = []

        def walk(o):
            if isinstance(o, dict):
                for k, v in o.items():
                    if k == "sticking_fraction" and isinstance(v, (int, float)) and not (0 <= v <= 1):
                        bad.append(v)
                    walk(v)
            elif isinstance(o, list):
                for v in o:
                    walk(v)
        walk(doc)
        if bad:
            self.find("ok result violating the physics", full, f"{tag} sticking fractions {bad[:5]} in --json")

    # ---- generators ----
    def mutate_scene(self, text):
        r = self.rng
        lines = text.split("\n")
        for _ in range(r.randint(1, 4)):
            op = r.randrange(8)
            assignments = [i for i, l in enumerate(lines) if "=" in l and not l.lstrip().startswith("#")]
            if op <= 2 and assignments:  # a value replaced by a corner token
                i = r.choice(assignments)
                k = lines[i].split("=")[0]
                v = r.choice(CORNERS)
                if r.random() < 0.3:
                    v = "[" + ", ".join(r.choice(CORNERS) for _ in range(r.randint(0, 4))) + "]"
                lines[i] = f"{k}= {v}"
            elif op == 3 and lines:
                del lines[r.randrange(len(lines))]
            elif op == 4 and lines:
                i = r.randrange(len(lines))
                lines[i:i] = [lines[i]] * r.randint(1, 3)
            elif op == 5:  # a key of the schema in a random place
                key = r.choice(NUMERIC_KEYS + list(STRINGS))
                lines.insert(r.randrange(len(lines) + 1), f"{key.split('.')[-1]} = {r.choice(CORNERS)}")
            elif op == 6:
                data = bytearray("\n".join(lines).encode())
                for _ in range(r.randint(1, 6)):
                    if data:
                        data[r.randrange(len(data))] ^= 1 << r.randrange(8)
                lines = data.decode(errors="replace").split("\n")
            else:
                lines.insert(r.randrange(len(lines) + 1), r.choice(
                    ["[structure]", "[[run]]", "[run", "x = {a = 1, a = 2}", "a.b.c.d = 1", "= 1",
                     "[initial]\ndisplacement = [2.0]", "structure.modes = 4294967297",
                     "title = '''", "[excitation]\namplitude = -1"]))
        out = "\n".join(lines)
        if r.random() < 0.1:
            out = out[: r.randrange(len(out) + 1)]
        return out

    def scene(self):
        return os.path.join(self.scenes, self.rng.choice(sorted(self.scene_texts)))

    def short_sets(self):
        return ["--set", f"run.periods={self.rng.choice([1, 3, 10, 40])}"]

    def gen_mutated_scene(self):
        name = self.rng.choice(sorted(self.scene_texts))
        text = self.mutate_scene(self.scene_texts[name])
        path = self.write_scene(text)
        out = self.fresh(".h5")
        cmd = self.rng.choice(["simulate", "simulate", "model", "orbit"])
        argv = [cmd, path] + (self.short_sets() if cmd == "simulate" else [])
        if cmd != "model":
            argv += ["--out", out]
        self.run("mutated-scene", argv, limit=20, watch=[path, self.work], out=out,
                 content=hashlib.sha1(text.encode(errors="replace")).hexdigest())

    def gen_set_extreme(self):
        r = self.rng
        scene = self.scene()
        sets = []
        for _ in range(r.randint(1, 3)):
            key = r.choice(NUMERIC_KEYS + list(STRINGS))
            if key in STRINGS:
                v = f'"{r.choice(STRINGS[key])}"'
            else:
                v = r.choice(EXTREMES + CORNERS[:22])
                if key in VECTOR_KEYS:
                    v = f"[{v}]" if r.random() < 0.7 else f"[{v}, {r.choice(EXTREMES)}]"
            sets += ["--set", f"{key}={v}"]
        if not any("run.periods" in s for s in sets):
            sets += self.short_sets()
        if r.random() < 0.4:
            sets += ["--set", 'run.engine="cvode"']
        if r.random() < 0.15:
            sets += ["--set", "run.samples_per_period=32"]
        out = self.fresh(".h5")
        cmd = r.choice(["simulate"] * 5 + ["orbit", "model", "check"])
        argv = [cmd, scene, *sets]
        if cmd in ("simulate", "orbit"):
            argv += ["--out", out]
        if cmd == "check":
            argv = [cmd, scene, *sets]
        self.run("numerical-extremes", argv, limit=25, watch=[self.work], out=out, key=tuple(sets))

    def option_value(self):
        r = self.rng
        choice = r.random()
        if choice < 0.5:
            return r.choice(CORNERS)
        if choice < 0.7:
            return f"{r.choice(CORNERS)},{r.choice(CORNERS)}"
        if choice < 0.8:
            return ""
        return r.choice(["-1e300,1e300", "0,1e308", "1e-300,2e-300", "5e-324,1", "1,1", "2,1", "0.1,0.2",
                         "x_B", "v_B", "X1", "V9", "X0", "1,2,3", "excitation.amplitude", "foo.bar",
                         "excitation.frequency", "stop.position", "run.periods", "2147483648",
                         "-2147483649"])

    COMMAND_OPTIONS = {
        "simulate": ["--out", "--resume", "--json", "--events", "--force"],
        "orbit": ["--period", "--guess", "--kind", "--impacts", "--transient", "--out", "--json"],
        "continue": ["--param", "--to", "--step", "--max-points", "--period", "--out", "--from", "--point"],
        "partition": ["--params", "--range1", "--range2", "--steps1", "--sticking-fraction", "--out"],
        "attractors": ["--x", "--y", "--x-range", "--y-range", "--samples", "--seed", "--threads", "--full-periods"],
        "basin": ["--x", "--y", "--x-range", "--y-range", "--grid", "--threads", "--out", "--resume"],
        "sweep": ["--param", "--from", "--to", "--steps", "--record", "--one-way", "--out"],
        "info": ["--json"],
        "plot": ["--out", "--format", "--dpi", "--time-window", "--overlay"],
        "check": ["--json"],
        "model": ["--json"],
        "validate": ["--json"],
        "score": ["--json"],
    }

    def gen_cli_misuse(self):
        r = self.rng
        cmd = r.choice(list(self.COMMAND_OPTIONS) + ["", "nonsense", "--help-me"])
        argv = [cmd] if cmd else []
        if cmd in self.COMMAND_OPTIONS and r.random() < 0.9:
            argv.append(r.choice([self.scene(), self.scene(), "/dev/zero", "/nonexistent.toml", self.work, ""]))
        opts = self.COMMAND_OPTIONS.get(cmd, ["--x"])
        for _ in range(r.randint(0, 4)):
            o = r.choice(opts + ["--set", "--bogus", "-x", "--"])
            argv.append(o)
            if o == "--set":
                argv.append(f"{r.choice(NUMERIC_KEYS)}={r.choice(CORNERS)}")
            elif o in ("--out", "--overlay"):
                argv.append(self.fresh(".h5") if r.random() < 0.8 else self.work)
            elif o not in ("--json", "--resume", "--one-way", "--full-periods", "--force", "--events") and r.random() < 0.9:
                argv.append(self.option_value())
        # Commands that would run long get a small problem (the misuse is the point).
        if cmd == "simulate":
            argv += self.short_sets()
        if cmd == "basin":
            argv += ["--grid", "3,3"]
        if cmd == "attractors":
            argv += ["--samples", "4"]
        if cmd == "sweep":
            argv += ["--steps", "2"]
        if cmd in ("continue",):
            argv += ["--max-points", "5"]
        self.run("cli-misuse", argv, limit=20, watch=[self.work], out=None)

    LONG = None

    def long_commands(self):
        s = self.scenes
        fig5, chain3, default = (os.path.join(s, n) for n in ("fig05_coexistence.toml", "chain3.toml", "default.toml"))
        return {
            "simulate": (["simulate", default, "--set", "run.periods=100000000"], True),
            "simulate-cvode": (["simulate", default, "--set", "run.periods=100000000", "--set", 'run.engine="cvode"'], True),
            "simulate-quad": (["simulate", default, "--set", "run.periods=100000000", "--set", 'run.precision="quad"'], True),
            "simulate-chain2": (["simulate", os.path.join(s, "chain2.toml"), "--set", "run.periods=100000000",
                                 "--set", "run.samples_per_period=64"], True),
            "orbit": (["orbit", chain3, "--period", "3"], True),
            "check": (["check", chain3], False),
            "continue": (["continue", chain3, "--param", "excitation.frequency", "--to", "0.3", "--step", "1e-4",
                          "--max-points", "100000"], True),
            "partition": (["partition", chain3, "--params", "excitation.amplitude,excitation.frequency", "--range1",
                           "0.9,1.1", "--range2", "0.3,0.8", "--steps1", "4", "--sticking-fraction", "0.3,0.5"], True),
            "attractors": (["attractors", fig5, "--samples", "100000", "--threads", "1"], False),
            "basin": (["basin", fig5, "--grid", "300,300", "--threads", "1"], True),
            "sweep": (["sweep", fig5, "--param", "excitation.frequency", "--from", "1", "--to", "3", "--steps",
                       "1000000"], True),
            "attractors-huge-range": (["attractors", fig5, "--y-range", "-1e100,1e100", "--samples", "1000",
                                       "--threads", "1"], False),
            "validate": (["validate", default], False),
        }

    def gen_signal(self):
        r = self.rng
        name, (args, has_out) = r.choice(list(self.long_commands().items()))
        out = self.fresh(".h5")
        argv = list(args) + (["--out", out] if has_out else [])
        sig = r.choice([signal.SIGTERM, signal.SIGINT])
        delay = r.choice([0.0, 0.01, 0.05]) if r.random() < 0.2 else r.uniform(0.05, 1.5)
        signals = [(delay, sig)]
        if r.random() < 0.25:
            signals.append((delay + r.choice([0.0, 0.001, 0.01, 0.1]), r.choice([signal.SIGTERM, signal.SIGINT])))
        rc, _ = self.run("signals", argv, signals=signals, limit=30, out=out, key=(name, round(delay, 2), len(signals)))
        if has_out and rc == 130 and os.path.exists(out) and r.random() < 0.3:
            self.seeds.append((name, args, out))

    seeds = []

    def corrupt(self, src):
        r = self.rng
        data = bytearray(open(src, "rb").read())
        op = r.randrange(4)
        if op == 0:
            for _ in range(r.randint(1, 16)):
                data[r.randrange(len(data))] ^= 1 << r.randrange(8)
        elif op == 1:
            k = r.randrange(len(data))
            data[k:k + r.randint(1, 64)] = b"\xff" * len(data[k:k + r.randint(1, 64)])
        elif op == 2:
            data = data[: r.randrange(len(data))]
        else:
            for _ in range(r.randint(1, 4)):
                k = r.randrange(len(data))
                data[k] = r.randrange(256)
        path = self.fresh(".h5")
        with open(path, "wb") as f:
            f.write(data)
        return path, hashlib.sha1(bytes(data)).hexdigest()

    def gen_corrupt(self):
        r = self.rng
        if not self.seeds:
            return False
        name, args, src = r.choice(self.seeds)
        path, h = self.corrupt(src)
        what = r.random()
        if what < 0.4:
            argv = ["info", path] + (["--json"] if r.random() < 0.5 else [])
            limit = 20
        elif what < 0.5:
            argv = ["plot", path, "--out", os.path.join(self.work, f"plot{self.counter}")]
            limit = 60
        else:
            if not any(a in ("simulate", "basin") for a in args[:1]):
                argv = ["info", path]
            else:
                argv = list(args) + ["--out", path, "--resume"]
            limit = 8  # a resumed long run is stopped by its limit (SIGTERM) and must keep the file
        self.run("corrupt-files", argv, limit=limit, watch=[path], out=path if "--resume" in argv else None,
                 content=h)
        return True

    def gen_reproducers(self):
        """The reproducers of issue 15: each either refused or stopped by SIGTERM."""
        s = self.scenes
        fig5, default = os.path.join(s, "fig05_coexistence.toml"), os.path.join(s, "default.toml")
        cases = [
            ["attractors", fig5, "--y-range", "-1e300,1e300"],
            ["attractors", fig5, "--y-range", "-1e100,1e100", "--samples", "50"],
            ["orbit", default, "--guess", "inf,1"],
            ["simulate", default, "--set", "excitation.frequency=5e-324"],
            ["simulate", default, "--set", "excitation.frequency=1.797e308"],
            ["sweep", default, "--param", "excitation.frequency", "--from", "1e308", "--to", "1.7e308"],
            ["sweep", default, "--param", "excitation.amplitude", "--from", "1e308", "--to", "1.7e308"],
            ["sweep", default, "--param", "stop.position", "--from", "1e308", "--to", "1.7e308"],
            ["basin", fig5, "--set", "excitation.amplitude=5e-324", "--grid", "20,20"],
            ["simulate", default, "--set", "excitation.amplitude=1e-310", "--set", "initial.displacement=[2.0]"],
            ["simulate", default, "--set", 'run.engine="cvode"', "--set", "initial.displacement=[1.0]", "--set",
             "initial.velocity=[1e300]"],
            ["simulate", default, "--set", 'run.engine="cvode"', "--set", "initial.displacement=[1.0]", "--set",
             "initial.velocity=[5e-324]"],
        ]
        for argv in cases:
            out = self.fresh(".h5")
            self.run("reproducers", argv + ["--out", out] if argv[0] in ("simulate", "basin", "sweep", "orbit") else argv,
                     signals=[(2.0, signal.SIGTERM)], limit=10, watch=[self.work], out=out)

    def main(self, runs):
        self.gen_reproducers()
        # Seeds for the corrupt-file runs: interrupted runs and studies, and finished files.
        for name, (args, has_out) in self.long_commands().items():
            if has_out:
                out = self.fresh(".h5")
                rc, _ = self.run("signals", list(args) + ["--out", out], signals=[(0.6, signal.SIGTERM)], out=out)
                if os.path.exists(out):
                    self.seeds.append((name, args, out))
        weights = [("mutated-scene", 0.30, self.gen_mutated_scene), ("numerical-extremes", 0.22, self.gen_set_extreme),
                   ("cli-misuse", 0.20, self.gen_cli_misuse), ("signals", 0.13, self.gen_signal),
                   ("corrupt-files", 0.15, self.gen_corrupt)]
        if self.only:
            weights = [(name, 1.0, gen) for name, _, gen in weights if name == self.only]
        while self.runs < runs and self.time_left():
            x = self.rng.random()
            for name, w, gen in weights:
                if x < w:
                    gen()
                    break
                x -= w
            if self.runs % 200 == 0:
                print(f"{self.runs} runs, {len(self.inputs)} distinct inputs, {len(self.findings)} findings",
                      flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("vibro")
    ap.add_argument("scenes")
    ap.add_argument("--runs", type=int, default=4800)
    ap.add_argument("--seed", type=int, default=15)
    ap.add_argument("--minutes", type=float, default=40)
    ap.add_argument("--report", default="")
    ap.add_argument("--only", default="", choices=["", "mutated-scene", "numerical-extremes", "cli-misuse",
                                                   "signals", "corrupt-files"],
                    help="generate runs of this category only (after the reproducers and seeds)")
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="vibro_campaign_")
    c = Campaign(os.path.abspath(a.vibro), os.path.abspath(a.scenes), a.seed, time.monotonic() + 60 * a.minutes, work)
    c.only = a.only
    t0 = time.monotonic()
    try:
        c.main(a.runs)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return write_report(c, t0, a.report, {"signals_before_the_program_loaded": c.before_main})


def write_report(c, t0, path, extra):
    """Prints the campaign's report (and writes it to `path`); 1 when there are findings."""
    report = {
        "runs": c.runs, "distinct_inputs": len(c.inputs), "minutes": round((time.monotonic() - t0) / 60, 1),
        "runs_by_category": c.categories, "exit_codes": {str(k): v for k, v in sorted(c.exits.items(), key=lambda kv: str(kv[0]))},
        "exit2_located": f"{c.located[0]} of {c.located[1]}", "ok_files_checked_for_physics": c.physics_checked,
        "stops_timed": len(c.stop_walls),
        "stops_slower_than_1s": len(c.slow_stops),
        "slowest_stop_s": round(max(c.slow_stops), 2) if c.slow_stops else None,
        "slowest_stop_own_s": round(max(o for _, o in c.stop_walls), 2) if c.stop_walls else None,
        "slowest_stop_wall_s": round(max(w for w, _ in c.stop_walls), 2) if c.stop_walls else None,
        **extra,
        "findings": c.findings,
    }
    text = json.dumps(report, indent=1)
    print(text)
    if path:
        with open(path, "w") as f:
            f.write(text)
    return 1 if c.findings else 0


if __name__ == "__main__":
    sys.exit(main())
