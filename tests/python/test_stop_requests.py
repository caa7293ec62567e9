"""Ctrl-C during vibro.check() and vibro.orbit() raises KeyboardInterrupt at once (docs/python.md),
as it does during every other call: both used to finish their computation first (10 s and more).

Each case runs the call in a child Python, waits until the child is observably inside the call
(it has used CPU time after printing "ready", the last thing before the call), sends SIGINT and
measures the time until the child has raised and exited."""
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from conftest import SCENES

# Generous against a loaded machine; the calls below run for minutes when the stop is ignored.
LIMIT = 5.0


def _cpu_seconds(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _interrupt(call, tmp_path):
    code = textwrap.dedent(f"""
        import sys, vibro
        scene = vibro.load_scene({os.path.join(SCENES, "default.toml")!r}, set={{"run.periods": 200000}})
        print("ready", flush=True)
        try:
            {call}
        except KeyboardInterrupt as e:
            print("KeyboardInterrupt:", e, flush=True)
            sys.exit(130)
        print("finished", flush=True)
    """)
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             cwd=tmp_path)
    try:
        assert child.stdout.readline().strip() == "ready", child.stderr.read()
        start_cpu = _cpu_seconds(child.pid)
        deadline = time.monotonic() + 300
        while _cpu_seconds(child.pid) < start_cpu + 0.5:  # inside the call, computing
            assert child.poll() is None and time.monotonic() < deadline, "the call ended before it was interrupted"
            time.sleep(0.02)
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        try:
            out, err = child.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            pytest.fail("SIGINT was ignored for 120 s")
        elapsed = time.monotonic() - sent
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    return child.returncode, out, err, elapsed


@pytest.mark.parametrize("call, what", [
    ("vibro.check(scene)", "cross-check"),
    ("vibro.orbit(scene, transient=100000)", "orbit search"),
    ("vibro.orbit(scene, transient=100000, out='orbit.h5')", "orbit search"),
])
def test_ctrl_c_stops_at_once(call, what, tmp_path):
    code, out, err, elapsed = _interrupt(call, tmp_path)
    assert code == 130, (out, err)
    assert f"KeyboardInterrupt: vibro: {what} interrupted" in out, (out, err)
    print(f"{call}: KeyboardInterrupt {elapsed:.3f} s after SIGINT")
    assert elapsed < LIMIT, f"KeyboardInterrupt {elapsed:.2f} s after SIGINT"
    # An orbit is found whole or not at all: the output file is removed, as by the command line.
    assert not (tmp_path / "orbit.h5").exists()
