#!/usr/bin/python3
"""HDF5 store through the real `vibro` binary: docs/output.md layout and types read with h5py,
SIGINT/SIGTERM/SIGKILL on a long run, resume equal to an uninterrupted run, unwritable
destinations (exit 2 before any computation), and `vibro plot` on a sticking and a chattering run.
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
default = os.path.join(scenes, "fig08_preload.toml")


def run(*args, timeout=600):
    return subprocess.run([vibro, *args], capture_output=True, text=True, timeout=timeout)


def start(*args):
    return subprocess.Popen([vibro, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_for_rows(path, proc, seconds):
    """Waits until the file has flushed some events (or the time is up)."""
    deadline = time.time() + seconds
    while time.time() < deadline and proc.poll() is None:
        time.sleep(0.2)
        try:  # the writer takes no file lock: a long run can be watched as it goes
            with h5py.File(path, "r") as f:
                if f["events/t"].shape[0] > 1000:
                    return
        except Exception:
            pass


with tempfile.TemporaryDirectory() as d:
    # --- Layout and types --------------------------------------------------------------------
    out = os.path.join(d, "fig8.h5")
    p = run("simulate", default, "--out", out, "--json")
    check("simulate --out exit 0", p.returncode == 0, p.stderr)
    summary = json.loads(p.stdout)
    with h5py.File(out, "r") as f:
        for key in ("vibro_version", "scene", "engine", "rtol", "atol", "chatter", "status",
                    "message", "created"):
            check(f"root attribute {key}", key in f.attrs, list(f.attrs))
        for key in ("vibro_version", "scene", "engine", "chatter", "status", "message", "created"):
            check(f"{key} is str", isinstance(f.attrs[key], str), type(f.attrs[key]))
        check("status ok", f.attrs["status"] == "ok", f.attrs["status"])
        check("created ISO 8601", len(f.attrs["created"]) == 20 and f.attrs["created"][10] == "T",
              f.attrs["created"])
        kinds = h5py.check_enum_dtype(f["events/kind"].dtype)
        check("events/kind enum", kinds == {"impact": 1, "accumulation": 2, "stick": 3,
                                            "release": 4, "grazing": 5}, kinds)
        n = f["events/t"].shape[0]
        for name in ("t", "x_B", "v_before", "v_after"):
            ds = f["events/" + name]
            check(f"events/{name}", ds.dtype == np.float64 and ds.shape == (n,), ds)
            check(f"events/{name} chunked, compressed, extendible",
                  ds.chunks is not None and ds.compression == "gzip" and ds.maxshape == (None,), ds)
        counts = summary["counts"]
        k = f["events/kind"][:]
        check("event counts match the JSON",
              (k == 1).sum() == counts["impacts"] and (k == 2).sum() == counts["accumulations"]
              and (k == 3).sum() == counts["sticks"] and (k == 4).sum() == counts["releases"], counts)
        t = f["events/t"][:]
        check("event times increase", np.all(np.diff(t) >= 0), "")
        m = f["samples/t"].shape[0]
        check("samples per period", m == 64 * 200, m)
        check("samples/X shape", f["samples/X"].shape == (m, 1) and f["samples/X"].dtype == np.float64, "")
        check("samples/V shape", f["samples/V"].shape == (m, 1), "")
        check("samples/mode int8", f["samples/mode"].dtype == np.int8, f["samples/mode"].dtype)
        check("samples/x_B", f["samples/x_B"].shape == (m,), "")
        check("samples never inside the stop", f["samples/x_B"][:].min() >= 1.0 - 1e-12, "")
        check("section one row per period", f["section/t"].shape == (201,) and
              f["section/X"].shape == (201, 1) and f["section/V"].shape == (201, 1), f["section/t"].shape)
        T = f.attrs["forcing_period"]
        check("section times", np.allclose(f["section/t"][:], np.arange(201) * T, rtol=0, atol=1e-9), "")
        a = f["attractor"].attrs
        check("attractor attrs", a["kind"] == summary["attractor"]["kind"] and
              a["period"] == summary["attractor"]["period"] and
              abs(a["sticking_fraction"] - summary["attractor"]["sticking_fraction"]) < 1e-15, dict(a))
        check("attractor stick_phases", np.allclose(a["stick_phases"], summary["attractor"]["stick_phases"]), "")
        check("scene as run parses", "restitution = 0.75" in f.attrs["scene"], f.attrs["scene"])
    p = run("info", out, "--json")
    check("info --json", p.returncode == 0 and json.loads(p.stdout)["rows"]["events"] == n, p.stdout)

    # --- Interruption, hard kill and resume -----------------------------------------------------
    # 60000 periods: ~3e6 events, a few seconds; interrupted after the first flush (~1 s).
    long_sets = ["--set", "run.periods=150000", "--set", "run.samples_per_period=4"]
    ref = os.path.join(d, "ref.h5")
    p = run("simulate", default, *long_sets, "--out", ref, "--json")
    check("reference long run", p.returncode == 0, p.stderr)
    ref_summary = json.loads(p.stdout)

    def same_as_reference(path, label):
        with h5py.File(ref, "r") as a, h5py.File(path, "r") as b:
            check(f"{label}: status ok", b.attrs["status"] == "ok", b.attrs["status"])
            for name in ("events/t", "events/kind", "events/x_B", "events/v_before", "events/v_after",
                         "events/period", "events/offset", "events/impulse", "events/energy_dissipated",
                         "events/stick_duration", "events/reaction_integral", "events/reaction_max", "samples/t", "samples/X", "samples/V",
                         "samples/mode", "section/t", "section/X", "section/V"):
                x, y = a[name][:], b[name][:]
                check(f"{label}: {name} identical to the bit", x.shape == y.shape and
                      np.array_equal(x.view(np.uint8), y.view(np.uint8)), f"{x.shape} vs {y.shape}")
            check(f"{label}: attractor", dict(a["attractor"].attrs).keys() == dict(b["attractor"].attrs).keys()
                  and a["attractor"].attrs["kind"] == b["attractor"].attrs["kind"], "")

    for sig, code, label in ((signal.SIGINT, 130, "SIGINT"), (signal.SIGTERM, 130, "SIGTERM")):
        path = os.path.join(d, f"{label}.h5")
        proc = start("simulate", default, *long_sets, "--out", path)
        wait_for_rows(path, proc, 300)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
        check(f"{label}: exit {code}", proc.returncode == code, (proc.returncode, err))
        with h5py.File(path, "r") as f:
            check(f"{label}: status interrupted", f.attrs["status"] == "interrupted", f.attrs["status"])
            check(f"{label}: message says how to continue", "--resume" in f.attrs["message"], f.attrs["message"])
            kept = f["events/t"].shape[0]
            check(f"{label}: events kept", 0 < kept < ref_summary["counts"]["impacts"] * 2, kept)
        p = run("simulate", default, *long_sets, "--out", path, "--resume", "--json")
        check(f"{label}: resume exit 0", p.returncode == 0, p.stderr)
        if p.returncode == 0:
            check(f"{label}: resumed counts", json.loads(p.stdout)["counts"] == ref_summary["counts"],
                  (p.stdout, ref_summary))
            same_as_reference(path, f"{label} resume")

    path = os.path.join(d, "killed.h5")
    proc = start("simulate", default, *long_sets, "--out", path)
    wait_for_rows(path, proc, 300)
    time.sleep(0.3)
    t_kill = time.time()
    proc.kill()
    proc.communicate(timeout=60)
    check("SIGKILL: killed", proc.returncode == -9, proc.returncode)
    try:
        with h5py.File(path, "r") as f:
            rows = f["events/t"].shape[0]
            check("SIGKILL: file opens as it is, status running", f.attrs["status"] == "running", f.attrs["status"])
            check("SIGKILL: events on disk", rows > 1000, rows)
            ev = f["events/t"][:]
            check("SIGKILL: events readable", np.all(np.isfinite(ev)), "")
    except Exception as e:  # noqa: BLE001
        check("SIGKILL: file opens with h5py", False, repr(e))
    p = run("simulate", default, *long_sets, "--out", path, "--resume")
    check("SIGKILL: resume exit 0", p.returncode == 0, p.stderr)
    if p.returncode == 0:
        same_as_reference(path, "SIGKILL resume")

    p = run("simulate", default, "--set", "excitation.amplitude=1.3", "--out", ref, "--resume")
    check("resume with another scene refused (exit 2)", p.returncode == 2 and "different scene" in p.stderr,
          p.stderr)

    # --- Unwritable destinations: exit 2 before any computation, nothing half-written -------------
    if os.geteuid() == 0:
        target = "/proc/vibro-store-test.h5"  # root ignores directory permissions, not /proc's
    else:
        ro = os.path.join(d, "ro")
        os.mkdir(ro)
        os.chmod(ro, 0o500)
        target = os.path.join(ro, "x.h5")
    t0 = time.time()
    p = run("simulate", default, "--set", "run.periods=1000000", "--out", target, timeout=60)
    check("read-only destination exit 2", p.returncode == 2 and "cannot write" in p.stderr, (p.returncode, p.stderr))
    check("read-only destination fails at once", time.time() - t0 < 5, time.time() - t0)
    check("read-only: no file", not os.path.exists(target), "")
    if True:
        p = run("simulate", default, "--out", os.path.join(d, "missing", "x.h5"))
        check("missing directory exit 2", p.returncode == 2 and "cannot write" in p.stderr, p.stderr)
    t0 = time.time()
    p = run("simulate", default, "--set", "run.periods=1000000", "--out", "/dev/full", timeout=60)
    check("full destination exit 2", p.returncode == 2 and "cannot write" in p.stderr, (p.returncode, p.stderr))
    check("full destination fails at once", time.time() - t0 < 5, time.time() - t0)
    p = run("simulate", default, "--set", "stop.restitution=3", "--out", os.path.join(d, "bad.h5"))
    check("bad scene writes nothing", p.returncode == 2 and not os.path.exists(os.path.join(d, "bad.h5")), p.stderr)
    p = run("info", os.path.join(scenes, "chain2.toml"))
    check("info on a non-HDF5 file exit 2", p.returncode == 2, p.stderr)

    # --- Plots of a sticking (r = 0) and a chattering (r = 0.75) run ------------------------------
    for scene, label in (("fig04_subharmonic.toml", "sticking"), ("fig05_coexistence.toml", "chattering"),
                         ("chain2.toml", "2-DOF")):
        h5 = os.path.join(d, label + ".h5")
        p = run("simulate", os.path.join(scenes, scene), "--set", "run.periods=30", "--out", h5)
        check(f"plot {label}: simulate", p.returncode == 0, p.stderr)
        prefix = os.path.join(d, label)
        p = run("plot", h5, "--out", prefix)
        check(f"plot {label}: exit 0", p.returncode == 0, p.stderr)
        for suffix in ("xB", "reaction", "phase", "section"):
            png = f"{prefix}_{suffix}.png"
            ok = os.path.exists(png) and os.path.getsize(png) > 5000
            if ok:
                with open(png, "rb") as fh:
                    ok = fh.read(8) == b"\x89PNG\r\n\x1a\n"
            check(f"plot {label}: {suffix} PNG", ok, png)

finish()
