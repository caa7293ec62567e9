"""Lyapunov exponents from Python: the summary of `simulate` carries them as the CLI's JSON does
(docs/model.md §5.8, docs/output.md)."""
import math
import os

import vibro

from conftest import SCENES, cli_json


def test_chaotic_sticking_response_has_a_positive_exponent_beyond_its_interval():
    path = os.path.join(SCENES, "chaotic", "chain2_sticking.toml")
    s = vibro.simulate(vibro.load_scene(path)).summary
    assert s["chaotic"] is True
    assert s["lyapunov_ci"][0][0] > 0
    assert s["lyapunov_exponents"][2:] == [None, None]  # sticking collapses two directions (-inf)
    assert s["lyapunov_exponents"] == cli_json("simulate", path)["lyapunov_exponents"]


def test_periodic_sticking_orbit_has_negative_exponents_and_can_be_switched_off():
    scene = vibro.load_scene(os.path.join(SCENES, "chain2.toml"))
    s = vibro.simulate(scene).summary
    assert not s["chaotic"] and all(e is None or e < 0 for e in s["lyapunov_exponents"])
    assert math.isclose(s["lyapunov_exponents"][0], -0.1601, abs_tol=2e-3)  # ln|μ|/T, |μ| = 0.2844
    off = vibro.simulate(scene.with_({"run.lyapunov": False})).summary
    assert "lyapunov_exponents" not in off and "chaotic" not in off
