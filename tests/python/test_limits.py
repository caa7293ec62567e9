"""The Python functions hold their arguments to the command line's limits (src/frontend/limits.hpp):
each bad argument raises ValueError naming it and the limit, before anything is computed or
written, where the calls used to run until killed, run out of memory, or silently accept it."""
import math
import os
import subprocess

import numpy as np
import pytest

import vibro
from conftest import CLI, SCENES

DEFAULT = os.path.join(SCENES, "default.toml")
AMPLITUDE = "excitation.amplitude"


@pytest.fixture(scope="module")
def scene():
    return vibro.load_scene(DEFAULT, set={"run.periods": 20})


# (call, the message's start): each call returned, ran until killed or raised another error.
CASES = [
    (lambda s: vibro.basin(s, grid=(46341, 46341)), "grid (46341, 46341): at most 16777216 cells"),
    (lambda s: vibro.basin(s, grid=(70000, 2)), "grid (70000, 2): expected NX, NY ≤ 65536"),
    (lambda s: vibro.continue_(s, AMPLITUDE, to=math.nan), "to nan: expected a finite number"),
    (lambda s: vibro.continue_(s, AMPLITUDE, to=math.inf), "to inf: expected a finite number"),
    (lambda s: vibro.continue_(s, AMPLITUDE, to=1.2, step=math.nan), "step nan: expected a finite number"),
    (lambda s: vibro.continue_(s, AMPLITUDE, to=1.2, max_points=0), "max_points 0: expected an integer in [1, "),
    (lambda s: vibro.continue_(s, AMPLITUDE, to=1.2, period=5000), "period 5000: expected an integer in [0, 4096]"),
    (lambda s: vibro.attractors(s, samples=2 ** 31), "samples 2147483648: expected an integer in [1, 16777216]"),
    (lambda s: vibro.sweep(s, AMPLITUDE, 1.0, 1.2, steps=10 ** 9), "steps 1000000000: expected an integer in [1, "),
    (lambda s: vibro.sweep(s, AMPLITUDE, 1.0, 1.2, record=0), "record 0: expected an integer in [1, 65536]"),
    (lambda s: vibro.sweep(s, AMPLITUDE, math.nan, 1.2), "from_ nan: expected a finite number"),
    (lambda s: vibro.partition(s, (AMPLITUDE, "excitation.frequency"), (1.0, 1.2), (2.7, 2.9), 0.5, steps1=10 ** 9),
     "steps1 1000000000: expected an integer in [1, 65536]"),
    (lambda s: vibro.partition(s, (AMPLITUDE, "excitation.frequency"), (1.0, 1.2), (2.7, 2.9), 0.5, threads=-1),
     "threads -1: expected an integer in [0, 4096]"),
    (lambda s: vibro.basin(s, grid=(2, 2), threads=-1), "threads -1: expected an integer in [0, 4096]"),
    (lambda s: vibro.attractors(s, threads=5000), "threads 5000: expected an integer in [0, 4096]"),
    (lambda s: vibro.basin(s, grid=(2, 2), x="X1099511627776"), "x X1099511627776: modal index out of range"),
    (lambda s: vibro.orbit(s, period=-1), "period -1: expected an integer in [0, 4096]"),
    (lambda s: vibro.orbit(s, impacts=2 ** 21), "impacts 2097152: expected an integer in [0, 1048576]"),
    (lambda s: vibro.orbit(s, transient=-5), "transient -5: expected an integer ≥ 0"),
    (lambda s: vibro.orbit(s, guess=(1.0, math.nan)), "guess 1,nan: expected finite numbers"),
    (lambda s: vibro.sweep(s, AMPLITUDE, 1.0, 1.2, steps=10 ** 30),  # beyond 64 bits: not a TypeError
     "steps 1000000000000000000000000000000: expected a 64-bit integer"),
    (lambda s: vibro.sweep(s, AMPLITUDE, 1.0, 1.2, steps=2.5), "steps 2.5: expected an integer, got float"),
    (lambda s: vibro.continue_(s, AMPLITUDE, to="far"), "to 'far': expected a number, got str"),
    (lambda s: vibro.validate(s, {"value": [1.2], "time": [0.0], "displacement_1": [1.1], "velocity_1": [0.0]},
                              AMPLITUDE, period=2 ** 40), "period 1099511627776: expected an integer in [0, 4096]"),
    (lambda s: vibro.attractors(s, seed=-1), "seed -1: expected an integer in [0, 2^63 - 1)"),
]


@pytest.mark.parametrize("call, message", CASES, ids=[m.split(":")[0] for _, m in CASES])
def test_bad_argument_is_value_error_naming_it(scene, call, message, tmp_path):
    with pytest.raises(ValueError) as e:
        call(scene)
    assert str(e.value).startswith(message), str(e.value)
    assert "\n" not in str(e.value)


def test_bad_argument_writes_nothing(scene, tmp_path):
    out = tmp_path / "b.h5"
    with pytest.raises(ValueError, match="threads -1"):
        vibro.basin(scene, grid=(2, 2), threads=-1, out=out)
    with pytest.raises(ValueError, match="steps1 0"):
        vibro.partition(scene, (AMPLITUDE, "excitation.frequency"), (1.0, 1.2), (2.7, 2.9), 0.5, steps1=0, out=out)
    assert not out.exists()


def test_the_command_line_refuses_the_same_values(tmp_path):
    """The same limits as the command line's: one value past each limit is refused there too
    (exit 2), the limit itself is accepted by both."""
    if not CLI:
        pytest.fail("VIBRO_CLI is not set: run the tests through ctest")
    for args in (["basin", DEFAULT, "--grid", "46341,46341"], ["basin", DEFAULT, "--x", "X1099511627776"],
                 ["attractors", DEFAULT, "--samples", str(2 ** 24 + 1)], ["sweep", DEFAULT, "--param", AMPLITUDE,
                 "--from", "1", "--to", "1.2", "--steps", str(2 ** 22 + 1)], ["basin", DEFAULT, "--threads", "-1"]):
        p = subprocess.run([CLI, *args], capture_output=True, text=True, timeout=120, cwd=tmp_path)
        assert p.returncode == 2, (args, p.stderr)
    s = vibro.load_scene(DEFAULT, set={"run.periods": 2})
    with pytest.raises(ValueError, match=r"samples 16777217: expected an integer in \[1, 16777216\]"):
        vibro.attractors(s, samples=2 ** 24 + 1)


def test_nul_in_a_file_name_is_refused(tmp_path):
    with pytest.raises(ValueError, match=r"default\.toml\\0junk': a file name cannot contain a NUL character"):
        vibro.load_scene(DEFAULT + "\x00junk")
    s = vibro.load_scene(DEFAULT, set={"run.periods": 2})
    with pytest.raises(ValueError, match=r"out '.*run\.h5\\0x': a file name cannot contain a NUL"):
        vibro.simulate(s, out=str(tmp_path / "run.h5") + "\x00x")
    assert not (tmp_path / "run.h5").exists()
    with pytest.raises(ValueError, match=r"events 'e\.csv\\0': a file name"):
        vibro.score(s, "e.csv\x00")
    with pytest.raises(ValueError, match=r"path 'x\.h5\\0y'"):
        vibro.info("x.h5\x00y")


def test_limits_are_inclusive(scene):
    """The ends of each range are accepted (the checks are not off by one)."""
    r = vibro.attractors(vibro.load_scene(DEFAULT, set={"run.periods": 2}), samples=1, threads=1)
    assert "attractors" in r
    d = vibro.continue_(scene, AMPLITUDE, to=1.05, max_points=1)
    assert len(d["points"]) <= 1
