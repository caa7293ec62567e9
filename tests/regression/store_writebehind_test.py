#!/usr/bin/python3
"""The store's write-behind (docs/output.md, "Writing"): a run long enough for the writer thread to
write many flushes of whole chunks while the simulation goes on (20 000 periods of Fig. 8,
720 000 events, 128 KiB chunks) keeps in its file exactly the events and sections that the same
run returns in memory through the Python module (no file): every column, bit for bit.

Usage: store_writebehind_test.py VIBRO SCENES_DIR PYTHON_DIR
"""
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

vibro_cli, scenes, python_dir = sys.argv[1:4]
sys.path.insert(0, python_dir)
import vibro  # noqa: E402

failures = 0


def check(what, ok):
    global failures
    print(("ok   " if ok else "FAIL ") + what)
    failures += 0 if ok else 1


scene_path = os.path.join(scenes, "fig08_preload.toml")
with tempfile.TemporaryDirectory() as tmp:
    out = os.path.join(tmp, "run.h5")
    p = subprocess.run([vibro_cli, "simulate", scene_path, "--set", "run.periods=20000", "--out", out],
                       capture_output=True, text=True)
    check("vibro simulate --out exits 0", p.returncode == 0)
    r = vibro.simulate(vibro.load_scene(scene_path, set=["run.periods=20000"]))  # in memory, no file
    with h5py.File(out, "r") as f:
        ev = f["events"]
        check("the file has 720 001 events", ev["t"].shape[0] == 720001)
        check("the events' chunks hold 16 384 rows", ev["t"].chunks == (16384,))
        check("as many events as in memory", ev["t"].shape[0] == len(r.events))
        if ev["t"].shape[0] == len(r.events):
            for name in ("t", "x_B", "v_before", "v_after"):
                check(f"/events/{name} is the in-memory run's, bit for bit",
                      np.array_equal(ev[name][()].view(np.uint64), np.ascontiguousarray(r.events[name]).view(np.uint64)))
            check("/events/kind is the in-memory run's", np.array_equal(ev["kind"][()], r.events["kind"]))
            sec = f["section"]
            check("/section/t is the in-memory run's, bit for bit",
                  np.array_equal(sec["t"][()].view(np.uint64), np.ascontiguousarray(r.section["t"]).view(np.uint64)))
sys.exit(1 if failures else 0)
