#!/usr/bin/python3
"""Basin studies through the real `vibro` binary: the file of a study is the same for 1 and 2
threads and (with --mpiexec) for `mpirun -np 2`; SIGINT and SIGKILL keep the finished cells and
`--resume` ends with the labels and table of an uninterrupted run; resumes of another scene or
grid are refused (exit 2); `vibro sweep --out` and its plot, with a continuation branch overlaid
(bad overlays exit 2).

usage: studies_test.py VIBRO SCENES_DIR [--mpiexec MPIEXEC]
"""
import json
import os
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
mpiexec = sys.argv[sys.argv.index("--mpiexec") + 1] if "--mpiexec" in sys.argv else None
fig5 = os.path.join(scenes, "fig05_coexistence.toml")


def run(*args, timeout=600, prefix=()):
    return subprocess.run([*prefix, vibro, *args], capture_output=True, text=True, timeout=timeout)


def start(*args):
    return subprocess.Popen([vibro, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def content(path):
    """Every dataset and attribute of a file, as comparable Python values, except those that say
    when and how it was invoked (`created`, `command_line`, `options`: --threads, mpirun)."""
    out = {}

    def value(v):
        a = np.asarray(v)
        if a.dtype.kind == "f":
            return ("f", a.shape, a.tobytes())  # bit for bit (NaN included)
        return ("o", a.shape, a.tolist())

    def visit(name, obj):
        for k, v in obj.attrs.items():
            if k not in ("created", "command_line", "options"):
                out[f"{name}@{k}"] = value(v)
        if isinstance(obj, h5py.Dataset):
            out[name] = (str(obj.dtype), value(obj[()]))

    with h5py.File(path, "r") as f:
        visit("/", f)
        f.visititems(visit)
    return out


def differences(a, b):
    keys = sorted(set(a) | set(b))
    return [k for k in keys if a.get(k) != b.get(k)]


def cells_by_index(path):
    """The cell table as {index: row}, whatever order the cells were written in."""
    with h5py.File(path, "r") as f:
        c = f["basin/cells"]
        cols = {k: c[k][()] for k in c if k != "phases"}
    rows = {}
    for r in range(len(cols["index"])):
        rows[int(cols["index"][r])] = tuple(np.asarray(v[r]).tobytes() for k, v in sorted(cols.items()))
    return rows


def wait_for_cells(path, proc, seconds):
    """Waits until the study has flushed some cells (the writer takes no lock)."""
    deadline = time.time() + seconds
    while time.time() < deadline and proc.poll() is None:
        time.sleep(0.2)
        try:
            with h5py.File(path, "r") as f:
                if f["basin/cells/index"].shape[0] > 0:
                    return True
        except Exception:
            pass
    return False


def grid_args(nxy="224,160", x_range="1,3"):
    return ["--grid", nxy, "--set", "run.periods=100", "--x-range", x_range, "--y-range", "-2,2"]


grid = grid_args()
with tempfile.TemporaryDirectory() as d:
    # --- The same file for 1 and 2 threads (and 2 MPI ranks) -------------------------------------
    ref = os.path.join(d, "ref.h5")
    p = run("basin", fig5, *grid, "--threads", "2", "--out", ref, "--json")
    check("basin exit 0", p.returncode == 0, p.stderr)
    ref_json = json.loads(p.stdout) if p.returncode == 0 else {}
    ref_content = content(ref)
    with h5py.File(ref, "r") as f:
        labels = f["basin/labels"][()]
        n_cells = labels.size
        check("labels cover the grid", labels.shape == (160, 224), labels.shape)
        check("every cell written", f["basin/cells/index"].shape[0] == n_cells)
        check("status ok", f.attrs["status"] == "ok", f.attrs["status"])
        a = {k: v[()] for k, v in f["attractors"].items()}  # one dataset per column
        kinds = list(f["attractors/kind"].asstr()[()])
        check("Fig. 5 attractors", "sticking-periodic" in kinds and "impact-periodic" in kinds, kinds)
        check("orbit columns", len(a["stable"]) == len(kinds) and a["floquet_multipliers"].shape[1] == 2
              and int(a["multiplier_count"].sum()) == a["floquet_multipliers"].shape[0], a)
        fractions = a["basin_fraction"].sum() + f["basin"].attrs["unresolved_fraction"]
        check("fractions add up", abs(fractions - 1) < 1e-12, fractions)
        check("labels match fractions", all(abs((labels == k).mean() - a["basin_fraction"][k]) < 1e-12
                                            for k in range(len(kinds))))
    check("json: orbit fields", all({"orbit_status", "floquet_multipliers", "stable", "merged_classes"} <= set(x)
                                    for x in ref_json.get("attractors", [{}])), ref_json)
    one = os.path.join(d, "one.h5")
    p = run("basin", fig5, *grid, "--threads", "1", "--out", one, "--json")
    check("basin --threads 1 exit 0", p.returncode == 0, p.stderr)
    check("threads 1 and 2: same JSON", p.stdout == json.dumps(ref_json, separators=(",", ":")) or
          json.loads(p.stdout) == ref_json)
    diff = differences(content(one), ref_content)
    check("threads 1 and 2: same file (all datasets and attributes but the invocation)", not diff, diff)
    if mpiexec:
        mpi = os.path.join(d, "mpi.h5")
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                   OMPI_MCA_rmaps_base_oversubscribe="1")
        p = subprocess.run([mpiexec, "-np", "2", "--oversubscribe", vibro, "basin", fig5, *grid,
                            "--threads", "1", "--out", mpi, "--json"],
                           capture_output=True, text=True, timeout=600, env=env)
        check("mpirun -np 2 exit 0", p.returncode == 0, p.stderr)
        check("mpirun: one JSON object on stdout", p.stdout.count("\n") == 1, p.stdout)
        if p.returncode == 0:
            check("mpirun: same JSON", json.loads(p.stdout) == ref_json)
            diff = differences(content(mpi), ref_content)
            check("mpirun -np 2: same file as one process", not diff, diff)

    # --- Interruption and resume -----------------------------------------------------------------
    # A grid nine times larger, so that one thread is still far from done at the store's first
    # flush however fast the machine (the small grid takes 1.6 s on a quiet machine, under one
    # flush interval), with its own uninterrupted reference.
    igrid = grid_args(nxy="672,480")
    iref = os.path.join(d, "iref.h5")
    p = run("basin", fig5, *igrid, "--threads", "2", "--out", iref, "--json")
    check("large basin exit 0", p.returncode == 0, p.stderr)
    iref_json = json.loads(p.stdout) if p.returncode == 0 else {}
    iref_content = content(iref)
    n_icells = 672 * 480
    for sig, code, label in ((signal.SIGINT, 130, "SIGINT"), (signal.SIGKILL, -9, "SIGKILL")):
        path = os.path.join(d, f"{label}.h5")
        proc = start("basin", fig5, *igrid, "--threads", "1", "--out", path)
        flushed = wait_for_cells(path, proc, 300)
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=120)
        check(f"{label}: cells flushed before the signal", flushed)
        check(f"{label}: exit {code}", proc.returncode == code, (proc.returncode, err))
        with h5py.File(path, "r") as f:
            done = f["basin/cells/index"].shape[0]
            check(f"{label}: some cells kept, not all", 0 < done < n_icells, done)
            if sig == signal.SIGINT:
                check("SIGINT: status interrupted", f.attrs["status"] == "interrupted", f.attrs["status"])
                check("SIGINT: message says how to continue", "--resume" in f.attrs["message"], f.attrs["message"])
                lab = f["basin/labels"][()]
                check("SIGINT: labels of the done cells, −3 elsewhere",
                      (lab != -3).sum() == done and (lab == -3).sum() == n_icells - done, (lab != -3).sum())
            else:
                check("SIGKILL: status running", f.attrs["status"] == "running", f.attrs["status"])
        p = run("basin", fig5, *igrid, "--threads", "2", "--out", path, "--resume", "--json")
        check(f"{label}: resume exit 0", p.returncode == 0, p.stderr)
        if p.returncode == 0:
            check(f"{label}: resumed JSON equals the uninterrupted one", json.loads(p.stdout) == iref_json)
            c = content(path)
            for key in [k for k in iref_content if k.startswith(("/attractors", "basin/labels", "basin@"))]:
                check(f"{label}: resumed {key}", c.get(key) == iref_content[key], key)
            check(f"{label}: resumed cell table equals the uninterrupted one (as a set)",
                  cells_by_index(path) == cells_by_index(iref))
            with h5py.File(path, "r") as f:
                check(f"{label}: resumed status ok", f.attrs["status"] == "ok", f.attrs["status"])

    # --- Resumes that must be refused (exit 2, the file untouched) --------------------------------
    stamp = os.path.getmtime(ref)
    p = run("basin", fig5, *grid, "--out", ref, "--resume")
    check("resume of a finished study: exit 2", p.returncode == 2 and "nothing to resume" in p.stderr, p.stderr)
    half = os.path.join(d, "half.h5")
    proc = start("basin", fig5, *igrid, "--threads", "1", "--out", half)
    wait_for_cells(half, proc, 300)
    proc.send_signal(signal.SIGINT)
    proc.communicate(timeout=120)
    p = run("basin", fig5, *grid_args(nxy="100,160"), "--out", half, "--resume")
    check("resume with another grid: exit 2 naming --grid", p.returncode == 2 and "--grid" in p.stderr, p.stderr)
    p = run("basin", fig5, *grid_args(nxy="672,480", x_range="1,2.5"), "--out", half, "--resume")
    check("resume with another range: exit 2 naming --x-range", p.returncode == 2 and "--x-range" in p.stderr, p.stderr)
    p = run("basin", fig5, *igrid, "--set", "excitation.amplitude=1.2", "--out", half, "--resume")
    check("resume with another scene: exit 2", p.returncode == 2 and "different scene" in p.stderr, p.stderr)
    p = run("basin", fig5, *igrid, "--full-periods", "--out", half, "--resume")
    check("resume with --full-periods changed: exit 2", p.returncode == 2 and "--full-periods" in p.stderr, p.stderr)
    p = run("basin", fig5, *igrid, "--resume")
    check("--resume without --out: exit 2", p.returncode == 2 and "--out" in p.stderr, p.stderr)
    with h5py.File(half, "r") as f:
        check("refused resumes leave the file as it was", f.attrs["status"] == "interrupted", f.attrs["status"])
    check("refused resume leaves a finished file alone", os.path.getmtime(ref) == stamp)

    # --- Sweep to HDF5, its plot, and a continuation branch overlaid -------------------------------
    # 1-DOF, r = 0, ω = 2.8: sticking ends at f_ff = 5.899628658289789 (docs/model.md §6.3, eq. 38).
    f_ff = 5.899628658289789
    sw = os.path.join(d, "sweep.h5")
    sweep_args = ["sweep", os.path.join(scenes, "fig08_preload.toml"), "--set", "stop.restitution=0.0",
                  "--set", "run.periods=30", "--param", "excitation.amplitude", "--from", "5.85", "--to", "5.95",
                  "--steps", "10", "--record", "8"]
    p = run(*sweep_args, "--out", sw, "--json")
    check("sweep --out exit 0", p.returncode == 0, p.stderr)
    pts = json.loads(p.stdout)["points"] if p.returncode == 0 else []
    with h5py.File(sw, "r") as f:
        s = f["sweep"]
        check("sweep: attributes", (s.attrs["param"], s.attrs["from"], s.attrs["to"], s.attrs["steps"], s.attrs["record"])
              == ("excitation.amplitude", 5.85, 5.95, 10, 8), dict(s.attrs))
        value, up = s["value"][()], s["upward"][()]
        check("sweep: 21 runs up then down", len(value) == 21 and up.dtype == np.uint8
              and list(up) == [1] * 11 + [0] * 10, up)
        check("sweep: same values, kinds and fractions as the JSON",
              list(value) == [q["value"] for q in pts] and list(s["kind"].asstr()[()]) == [q["kind"] for q in pts]
              and all((np.isnan(a) and b is None) or a == b
                      for a, b in zip(s["sticking_fraction"][()], [q["sticking_fraction"] for q in pts])))
        check("sweep: section points (N, record) as in the JSON",
              s["x_B"].shape == (21, 8) and s["v_B"].shape == (21, 8)
              and all(list(s["x_B"][i]) == pts[i]["x_B"] for i in range(21)), s["x_B"].shape)
        sticks = np.array([k == "sticking-periodic" for k in s["kind"].asstr()[()]])
        check("sweep: sticking exactly below f_ff, both ways", list(sticks) == list(value < f_ff),
              list(zip(value, sticks)))
        check("sweep: status ok", f.attrs["status"] == "ok")
    p = run("plot", sw, "--out", os.path.join(d, "plain"))
    plain = os.path.join(d, "plain_sweep.png")
    check("plot sweep", p.returncode == 0 and os.path.getsize(plain) > 5000, p.stderr)
    # A continuation file as `vibro continue --out` writes it (/branch, /bifurcations).
    branch = os.path.join(d, "branch.h5")
    with h5py.File(branch, "w") as f:
        b = f.create_group("branch")
        b.attrs["param"] = "excitation.amplitude"
        v = np.linspace(5.80, f_ff, 30)
        b["value"] = v
        b["sticking_fraction"] = 0.2 * (f_ff - v) / (f_ff - 5.8)
        b["stable"] = np.array([1] * 20 + [0] * 10, dtype=np.uint8)
        b["x_B"] = np.ones(30)
        g = f.create_group("bifurcations")
        g["value"] = np.array([f_ff])
        g.create_dataset("kind", data=["sticking-lost"], dtype=h5py.string_dtype())
    p = run("plot", sw, "--out", os.path.join(d, "over"), "--overlay", branch)
    over = os.path.join(d, "over_sweep.png")
    check("plot sweep --overlay", p.returncode == 0 and os.path.exists(over), p.stderr)
    if p.returncode == 0:
        with open(plain, "rb") as a, open(over, "rb") as b:
            check("the overlay is drawn", a.read() != b.read())
    with h5py.File(branch, "a") as f:
        f["branch"].attrs["param"] = "excitation.frequency"
    p = run("plot", sw, "--overlay", branch, "--out", os.path.join(d, "x"))
    check("overlay of another parameter: exit 2", p.returncode == 2 and "excitation.frequency" in p.stderr, p.stderr)
    p = run("plot", sw, "--overlay", ref, "--out", os.path.join(d, "x"))
    check("overlay without /branch: exit 2", p.returncode == 2 and "--overlay" in p.stderr, p.stderr)
    p = run("plot", ref, "--overlay", branch, "--out", os.path.join(d, "x"))
    check("overlay on a file without a sweep: exit 2", p.returncode == 2 and "no sweep" in p.stderr, p.stderr)

finish()
