"""Two Python threads writing one output file: the second writer is refused with a ValueError naming
the file ("... is in use by process N": one writer per file, docs/reliability.md), the first run is
unharmed and the interpreter exits cleanly. It used to give a misleading "exists and is not a vibro
output file" and "HDF5: infinite loop closing library" at exit."""
import os
import subprocess
import sys
import textwrap

import h5py

from conftest import SCENES

CHILD = textwrap.dedent("""
    import os, signal, sys, threading, time
    import vibro
    out = sys.argv[1]
    scene = vibro.load_scene(sys.argv[2], set={"run.periods": 10000000})
    second = {}

    def second_writer():
        # Once the first run holds the file (its header is written), try to write it too.
        deadline = time.monotonic() + 300
        while not (os.path.exists(out) and os.path.getsize(out) > 0) and time.monotonic() < deadline:
            time.sleep(0.01)
        try:
            vibro.simulate(vibro.load_scene(sys.argv[2], set={"run.periods": 5}), out=out)
            second["outcome"] = "ok"
        except Exception as e:
            second["outcome"] = f"{type(e).__name__}: {e}"
        os.kill(os.getpid(), signal.SIGINT)  # ends the first run (it keeps what it computed)

    threading.Thread(target=second_writer).start()
    try:
        vibro.simulate(scene, out=out)
        print("first: finished")
    except KeyboardInterrupt:
        print("first: interrupted")
    print("second:", second.get("outcome"), flush=True)
""")


def test_second_writer_in_another_thread_is_refused(tmp_path):
    out = tmp_path / "same.h5"
    p = subprocess.run([sys.executable, "-c", CHILD, str(out), os.path.join(SCENES, "default.toml")],
                       capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert "first: interrupted" in lines, p.stdout
    second = next(line for line in lines if line.startswith("second:"))
    assert second.startswith("second: ValueError: ") and str(out) in second and "in use" in second, second
    assert "infinite loop" not in p.stderr and "HDF5" not in p.stderr, p.stderr
    # The first run's file is whole: its own status and rows, readable.
    with h5py.File(out, "r") as f:
        assert f.attrs["status"] in (b"interrupted", "interrupted")
        assert len(f["events"]["t"]) > 0
