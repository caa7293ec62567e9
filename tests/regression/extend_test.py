#!/usr/bin/python3
"""`vibro simulate --extend N` through the real binary: a finished run extended (twice), with the
exact engine and with CVODE, and an interrupted run extended, each equal to an uninterrupted run of
the total length in every dataset and attribute of the file, to the bit (h5py); refused extensions
(another scene, no --out, no file, a failed run) exit 2 and leave the file as it was.
"""
import hashlib
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
fig8 = os.path.join(scenes, "fig08_preload.toml")

# Attributes that say how and when a file was written, not what the run computed: the time of
# creation and the invocation (an extension records its own command line).
INVOCATION = {"/": {"created", "command_line", "options"}}


def run(*args, timeout=900):
    return subprocess.run([vibro, *args], capture_output=True, text=True, timeout=timeout)


def digest(path):
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()


def contents(path):
    """Every dataset (dtype, shape, bytes) and every attribute of every group, by path."""
    datasets, attrs = {}, {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            key = "/" + name
            if isinstance(obj, h5py.Dataset):
                a = obj[()]
                datasets[key] = (str(obj.dtype), obj.shape, np.ascontiguousarray(a).tobytes())
            attrs[key] = {k: v for k, v in obj.attrs.items()}
        attrs["/"] = {k: v for k, v in f.attrs.items()}
        f.visititems(visit)
    return datasets, attrs


def same_value(a, b):
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    if isinstance(a, float) or isinstance(a, np.floating):
        return np.asarray(a).tobytes() == np.asarray(b).tobytes()
    return type(a) is type(b) and a == b


def same_as(reference, path, label, skip=()):
    """The file at `path` equals `reference` in every dataset and attribute, to the bit, apart from
    the invocation attributes and the root attributes in `skip`."""
    rd, ra = contents(reference)
    pd, pa = contents(path)
    check(f"{label}: same datasets", sorted(rd) == sorted(pd), (sorted(set(rd) ^ set(pd))))
    for name in sorted(set(rd) & set(pd)):
        x, y = rd[name], pd[name]
        check(f"{label}: {name} identical to the bit", x == y,
              f"dtype/shape {x[:2]} vs {y[:2]}" if x[:2] != y[:2] else "same shape, different bits")
    check(f"{label}: same groups", sorted(ra) == sorted(pa), sorted(set(ra) ^ set(pa)))
    for group in sorted(set(ra) & set(pa)):
        ignore = INVOCATION.get(group, set()) | (set(skip) if group == "/" else set())
        ka, kb = set(ra[group]) - ignore, set(pa[group]) - ignore
        check(f"{label}: attributes of {group}", ka == kb, sorted(ka ^ kb))
        for k in sorted(ka & kb):
            check(f"{label}: attribute {group}:{k} identical", same_value(ra[group][k], pa[group][k]),
                  f"{ra[group][k]!r} vs {pa[group][k]!r}")


def carried_root_attrs(path):
    """Root attributes an extension cannot reproduce yet: the chattering counters unless the
    checkpoint carries them, and the CVODE work counters (the work of the last invocation)."""
    with h5py.File(path, "r") as f:
        skip = {k for k in f.attrs if k.startswith("cvode_") and k != "cvode_method"}
        if "chatter_accumulations_predicted" not in f["checkpoint"].attrs:
            skip |= {k for k in f.attrs if k.startswith("chatter_")}
    return skip


with tempfile.TemporaryDirectory() as d:
    # --- A finished run extended, twice, exact engine (chattering with accumulation points) -------
    for engine, first, more, again in (("exact", 200, 300, 250), ("cvode", 60, 90, 0)):
        sets = ["--set", f'run.engine="{engine}"']
        ref = os.path.join(d, f"{engine}_ref.h5")
        p = run("simulate", fig8, *sets, "--set", f"run.periods={first + more}", "--out", ref, "--json")
        check(f"{engine}: reference of {first + more} periods", p.returncode == 0, p.stderr)
        ref_json = json.loads(p.stdout) if p.returncode == 0 else {}
        path = os.path.join(d, f"{engine}.h5")
        p = run("simulate", fig8, *sets, "--set", f"run.periods={first}", "--out", path)
        check(f"{engine}: first {first} periods", p.returncode == 0, p.stderr)
        # The scene file says 200 periods: --extend ignores run.periods of the given scene.
        p = run("simulate", fig8, *sets, "--out", path, "--extend", str(more), "--json")
        check(f"{engine}: --extend {more} exit 0", p.returncode == 0, p.stderr)
        if p.returncode == 0:
            got = json.loads(p.stdout)
            for key in ("status", "t_end", "counts", "attractor"):
                check(f"{engine}: extended JSON {key} as the uninterrupted run's", got.get(key) == ref_json.get(key),
                      (got.get(key), ref_json.get(key)))
            with h5py.File(path, "r") as f:
                check(f"{engine}: the stored run.periods is the total",
                      f.attrs["periods"] == first + more and f"periods = {first + more}" in f.attrs["scene"],
                      (f.attrs["periods"], f.attrs["scene"]))
                check(f"{engine}: command line recorded", "--extend" in f.attrs["command_line"], f.attrs["command_line"])
            same_as(ref, path, f"{engine} +{more}", carried_root_attrs(path))
        if again:
            ref2 = os.path.join(d, f"{engine}_ref2.h5")
            total = first + more + again
            p = run("simulate", fig8, *sets, "--set", f"run.periods={total}", "--out", ref2)
            check(f"{engine}: reference of {total} periods", p.returncode == 0, p.stderr)
            p = run("simulate", fig8, *sets, "--out", path, "--extend", str(again))
            check(f"{engine}: second --extend exit 0", p.returncode == 0 and "extended by" in p.stdout, p.stderr)
            same_as(ref2, path, f"{engine} +{more} +{again}", carried_root_attrs(path))

    # --- An interrupted run extended --------------------------------------------------------------
    long_sets = ["--set", "run.samples_per_period=4"]
    first, more = 150000, 2000
    ref = os.path.join(d, "long_ref.h5")
    p = run("simulate", fig8, *long_sets, "--set", f"run.periods={first + more}", "--out", ref)
    check("reference long run", p.returncode == 0, p.stderr)

    def interrupt(args, path, past_period):
        """Runs vibro with `args`, sends SIGINT once the file's checkpoint is past `past_period`
        (a flush of the new run reached the disk) and returns the exit code and stderr."""
        proc = subprocess.Popen([vibro, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        deadline = time.time() + 300
        while time.time() < deadline and proc.poll() is None:
            time.sleep(0.2)
            try:
                with h5py.File(path, "r") as f:
                    if f.attrs["status"] == "running" and f["checkpoint"].attrs["period"] > past_period:
                        break
            except Exception:  # noqa: BLE001 (not created yet, or a flush in progress)
                pass
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=300)
        return proc.returncode, err

    path = os.path.join(d, "interrupted.h5")
    code, err = interrupt(["simulate", fig8, *long_sets, "--set", f"run.periods={first}", "--out", path], path, 0)
    check("interrupted: exit 130", code == 130, (code, err))
    with h5py.File(path, "r") as f:
        check("interrupted: status", f.attrs["status"] == "interrupted", f.attrs["status"])
        stopped = int(f["checkpoint"].attrs["period"])
    check("interrupted before its end", 0 < stopped < first, stopped)
    p = run("simulate", fig8, *long_sets, "--out", path, "--extend", str(more))
    check("interrupted: --extend exit 0", p.returncode == 0, p.stderr)
    if p.returncode == 0:
        same_as(ref, path, "interrupted +2000", carried_root_attrs(path))

    # --- An extension interrupted, then resumed with the total named ------------------------------
    path = os.path.join(d, "extension_interrupted.h5")
    p = run("simulate", fig8, *long_sets, "--set", f"run.periods={more}", "--out", path)
    check("short run", p.returncode == 0, p.stderr)
    code, err = interrupt(["simulate", fig8, *long_sets, "--out", path, "--extend", str(first)], path, more)
    check("extension interrupted: exit 130", code == 130, (code, err))
    with h5py.File(path, "r") as f:
        stopped = int(f["checkpoint"].attrs["period"])
        check("extension interrupted: status and total", f.attrs["status"] == "interrupted" and
              f.attrs["periods"] == first + more, (f.attrs["status"], f.attrs["periods"]))
    check("extension interrupted before its end", more < stopped < first + more, stopped)
    p = run("simulate", fig8, *long_sets, "--out", path, "--resume")
    check("plain --resume names the total", p.returncode == 2 and f"--set run.periods={first + more}" in p.stderr,
          p.stderr)
    p = run("simulate", fig8, *long_sets, "--set", f"run.periods={first + more}", "--out", path, "--resume")
    check("extension resumed: exit 0", p.returncode == 0, p.stderr)
    if p.returncode == 0:
        same_as(ref, path, "extension interrupted, resumed", carried_root_attrs(path))

    # --- Refusals: exit 2, the file as it was -------------------------------------------------------
    done = os.path.join(d, "exact.h5")
    before = digest(done)
    p = run("simulate", fig8, "--set", "excitation.amplitude=1.3", "--out", done, "--extend", "10")
    check("another scene: exit 2", p.returncode == 2 and "different scene" in p.stderr, p.stderr)
    p = run("simulate", fig8, "--extend", "10")
    check("no --out: exit 2", p.returncode == 2 and "--out" in p.stderr, p.stderr)
    p = run("simulate", fig8, "--out", os.path.join(d, "none.h5"), "--extend", "10")
    check("no such file: exit 2", p.returncode == 2 and "no such file" in p.stderr, p.stderr)
    check("no such file: nothing created", not os.path.exists(os.path.join(d, "none.h5")))
    p = run("simulate", fig8, "--out", done, "--extend", "0")
    check("--extend 0: exit 2", p.returncode == 2, p.stderr)
    p = run("simulate", fig8, "--out", done, "--resume", "--extend", "10")
    check("--resume with --extend: exit 2", p.returncode == 2 and "--resume and --extend: give one" in p.stderr,
          p.stderr)
    exact = ["--set", 'run.engine="exact"']
    p = run("simulate", fig8, *exact, "--set", "run.periods=750", "--out", done, "--resume")
    check("--resume of a finished run points to --extend",
          p.returncode == 2 and "nothing to resume" in p.stderr and "--extend" in p.stderr, p.stderr)
    p = run("simulate", fig8, *exact, "--set", "run.periods=900", "--out", done, "--resume")
    check("--resume with more periods points to --extend",
          p.returncode == 2 and "only run.periods differs" in p.stderr and "--set run.periods=750" in p.stderr
          and "--extend" in p.stderr, p.stderr)
    p = run("simulate", fig8, "--out", done, "--extend", "10")
    check("an override missing: exit 2", p.returncode == 2 and "different scene" in p.stderr, p.stderr)
    check("refused extensions leave the file as it was", digest(done) == before)
    # A run that ended in a numerical failure: run.chatter = "none" on a chattering scene.
    failed = os.path.join(d, "failed.h5")
    p = run("simulate", fig8, "--set", 'run.chatter="none"', "--out", failed)
    check("a failed run (exit 3)", p.returncode == 3, (p.returncode, p.stderr))
    before = digest(failed)
    p = run("simulate", fig8, "--set", 'run.chatter="none"', "--out", failed, "--extend", "10")
    check("a failed run: --extend exit 2", p.returncode == 2 and "numerical-failure" in p.stderr, p.stderr)
    check("a failed run: file as it was", digest(failed) == before)

finish()
