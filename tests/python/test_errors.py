"""Bad input raises ValueError carrying file:line:col, the key and the violated constraint; a
computation interrupted by SIGINT raises KeyboardInterrupt and leaves a readable file."""
import os
import re
import signal
import subprocess
import sys
import textwrap
import time

import h5py
import pytest

import vibro
from conftest import SCENES

BAD = """\
[structure]
frequencies = [1.0]
forcing     = [1.0]
contact     = [1.0]

[stop]
position    = 1.0
restitution = 1.5

[excitation]
amplitude = 1.2
frequency = 2.8
"""


def test_bad_file_is_located_value_error(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(BAD)
    with pytest.raises(ValueError) as e:
        vibro.load_scene(path)
    msg = str(e.value)
    assert re.search(re.escape(str(path)) + r":8:\d+: stop\.restitution", msg), msg
    assert "1.5" in msg


def test_bad_text_is_located_value_error():
    with pytest.raises(ValueError, match=r"mine\.toml:8:\d+: stop\.restitution"):
        vibro.Scene.from_toml(BAD, source="mine.toml")
    with pytest.raises(ValueError, match=r"mine\.toml:\d+:\d+: .*restitutoin"):
        vibro.Scene.from_toml(BAD.replace("restitution = 1.5", "restitutoin = 0.5"), source="mine.toml")


def test_bad_override_and_options_are_value_errors():
    path = os.path.join(SCENES, "fig08_preload.toml")
    with pytest.raises(ValueError, match="stop.restitution"):
        vibro.load_scene(path, set={"stop.restitution": -1.0})
    scene = vibro.load_scene(path)
    with pytest.raises(ValueError, match="kind"):
        vibro.orbit(scene, kind="chaotic")
    with pytest.raises(ValueError, match="grid"):
        vibro.basin(scene, grid=(0, 4))
    with pytest.raises(ValueError, match="not a numeric key"):
        vibro.continue_(scene, "excitation.nothing", 2.0)


def test_bad_out_is_value_error_and_nothing_computed(tmp_path):
    scene = vibro.load_scene(os.path.join(SCENES, "fig08_preload.toml"))
    with pytest.raises(ValueError):
        vibro.simulate(scene, out=tmp_path / "missing-dir" / "run.h5")


CHILD = textwrap.dedent("""
    import sys
    import vibro
    scene = vibro.load_scene(sys.argv[1], set={"run.periods": 100000000, "run.engine": "exact"})
    try:
        vibro.simulate(scene, out=sys.argv[2])
    except KeyboardInterrupt as e:
        print("KeyboardInterrupt:", e)
        sys.exit(130)
    print("finished")
""")


def test_sigint_gives_keyboard_interrupt_and_readable_file(tmp_path):
    out = tmp_path / "long.h5"
    child = subprocess.Popen([sys.executable, "-c", CHILD, os.path.join(SCENES, "fig08_preload.toml"), str(out)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    # Wait until the run has started (its file exists) and flushed once (1 s flush interval).
    deadline = time.monotonic() + 60
    while not out.exists() and time.monotonic() < deadline and child.poll() is None:
        time.sleep(0.05)
    assert out.exists(), child.communicate()
    time.sleep(1.5)
    child.send_signal(signal.SIGINT)
    stdout, stderr = child.communicate(timeout=120)
    assert child.returncode == 130, (stdout, stderr)
    assert stdout.startswith("KeyboardInterrupt:") and str(out) in stdout
    with h5py.File(out, "r") as f:
        assert f.attrs["status"] in ("interrupted", b"interrupted")
        n = f["events/t"].shape[0]
        assert n > 0
        t = f["events/t"][:]
        assert (t[1:] >= t[:-1]).all()
    info = vibro.info(out)
    assert info["status"] == "interrupted" and info["rows"]["events"] == n


def test_read_of_a_file_that_is_not_hdf5_is_a_value_error():
    # The surfaces campaign: h5py's OSError reached the caller; read() now refuses as `vibro info`
    # does, naming the file.
    with pytest.raises(ValueError, match="/dev/zero"):
        vibro.read("/dev/zero")
