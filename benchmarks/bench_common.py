#!/usr/bin/python3
"""Helpers shared by the benchmark scripts (work_precision.py, modal_truncation.py, peers/).

One place for: running `vibro simulate` on a scene with overrides and timing it (CPU time of the
child process, start-up included), reading its events and stroboscopic section from the HDF5
file, the stick/release milestones and their error against a reference, the sticking fraction
over the last periods from a stick/release list, CSV writing and figure saving.
Not part of the test suite; needs /usr/bin/python3 with Debian's h5py and matplotlib.
"""
import csv
import json
import math
import os
import resource
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES_DIR = os.path.join(ROOT, "data", "scenes")
DEFAULT_VIBRO = os.path.join(ROOT, "build", "vibro")
STICK, RELEASE = 3, 4  # HDF5 enum values of events/kind (docs/output.md)


def scene_path(scene):
    """A scene file name of data/scenes/ (or any path) as a path."""
    return scene if os.path.sep in scene else os.path.join(SCENES_DIR, scene)


def cpu_self():
    """User + system CPU time of this process (for peers running in-process)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


class VibroRun:
    """One `vibro simulate` run: summary (JSON), events, section, forcing period, CPU time."""

    def __init__(self, returncode, summary, cpu, stderr, events=None, section=None, period=None):
        self.returncode, self.summary, self.cpu, self.stderr = returncode, summary, cpu, stderr
        self.events = events or ([], [])  # (t, kind)
        self.section = section  # (t, X, V) arrays, one row per forcing period
        self.T = period

    @property
    def ok(self):
        return self.returncode == 0

    def milestones(self, n=12):
        """The first n stick and release times."""
        return milestones(*self.events, n=n)

    def stick_intervals(self):
        return stick_intervals(*self.events)


def run_vibro(vibro, scene, periods, sets=(), samples=0, read=True, model=False, out=None):
    """Runs `vibro simulate SCENE --json` with run.periods, run.samples_per_period and the
    overrides `sets` (list of "key=value"); returns a VibroRun. The CPU time is that of the child
    process (user + system), so it includes start-up (a few ms: docs/performance.md, "Start-up").
    With read=True the HDF5 file is written to a temporary directory and its events and section
    are read back; out=True writes it without reading it back."""
    with tempfile.TemporaryDirectory() as d:
        h5 = os.path.join(d, "run.h5")
        cmd = [vibro, "simulate", scene_path(scene), "--json",
               "--set", f"run.periods={periods}", "--set", f"run.samples_per_period={samples}"]
        if read if out is None else out:  # out=True: write the file without reading it back
            cmd += ["--out", h5]
        for s in sets:
            cmd += ["--set", s]
        before = _cpu_children()
        p = subprocess.run(cmd, capture_output=True, text=True)
        cpu = _cpu_children() - before
        try:
            summary = json.loads(p.stdout) if p.stdout.strip() else None
        except json.JSONDecodeError:
            summary = None
        run = VibroRun(p.returncode, summary, cpu, p.stderr)
        if read and os.path.exists(h5):
            import h5py  # noqa: PLC0415 (only the runs that read HDF5 need it)
            with h5py.File(h5, "r") as f:
                run.events = (f["events/t"][:].tolist(), f["events/kind"][:].tolist())
                run.section = (f["section/t"][:], f["section/X"][:], f["section/V"][:])
                run.T = float(f.attrs["forcing_period"])
    return run


def vibro_model(vibro, scene, sets=()):
    """`vibro model SCENE --json` as a dict (frequencies, forcing T_A, contact T_B, ...)."""
    cmd = [vibro, "model", scene_path(scene), "--json"]
    for s in sets:
        cmd += ["--set", s]
    return json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)


def scene_values(scene):
    """The scene's TOML as a dict (tomllib, Python ≥ 3.11)."""
    import tomllib  # noqa: PLC0415
    with open(scene_path(scene), "rb") as fh:
        return tomllib.load(fh)


def milestones(times, kinds, n=12):
    """The first n stick (3) and release (4) times of an event list."""
    return [t for t, k in zip(times, kinds) if k in (STICK, RELEASE)][:n]


def milestone_error(a, b, T):
    """Largest difference of two milestone lists over their common length, relative to T;
    a list shorter than the other counts as missing events (NaN when one is empty)."""
    n = min(len(a), len(b))
    if n == 0:
        return float("nan")
    return max(abs(x - y) for x, y in zip(a[:n], b[:n])) / T


def stick_intervals(times, kinds):
    """[(start, end)] of the sticking phases of a stick/release list (end None if still stuck)."""
    out, start = [], None
    for t, k in zip(times, kinds):
        if k == STICK and start is None:
            start = t
        elif k == RELEASE and start is not None:
            out.append((start, t))
            start = None
    if start is not None:
        out.append((start, None))
    return out


def sticking_fraction(intervals, t0, t1):
    """Share of [t0, t1] spent in the sticking intervals."""
    stuck = 0.0
    for a, b in intervals:
        b = t1 if b is None else b
        stuck += max(0.0, min(b, t1) - max(a, t0))
    return stuck / (t1 - t0)


def write_csv(rows, path):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fields = []
    for r in rows:
        fields += [k for k in r if k not in fields]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)


def pyplot():
    """matplotlib.pyplot with the Agg backend (no display needed)."""
    import matplotlib  # noqa: PLC0415
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415
    return plt


def save_figure(fig, path, dpi=100):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    print(path)


def fmt(x, spec=".2e"):
    """A float for a CSV cell ('' for None, 'nan' kept)."""
    if x is None:
        return ""
    if isinstance(x, float) and math.isnan(x):
        return "nan"
    return format(x, spec)
