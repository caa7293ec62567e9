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


def test_studies_and_sweeps_carry_the_exponents_as_the_cli():
    """basin, attractors and sweep report the exponents of each attractor (and of the first
    not-periodic cell) and of each run as their --json does (tests/regression/lyapunov_studies_test.py
    checks them against the Floquet multipliers)."""
    fig5 = os.path.join(SCENES, "fig05_coexistence.toml")
    b = vibro.basin(vibro.load_scene(fig5), grid=(8, 8))
    cli = cli_json("basin", fig5, "--grid", "8,8")
    keys = ("lyapunov_exponents", "lyapunov_ci", "lyapunov_periods", "chaotic")
    assert [[a[k] for k in keys] for a in b["attractors"]] == [[a[k] for k in keys] for a in cli["attractors"]]
    assert all(a["chaotic"] is False for a in b["attractors"])
    chaos = os.path.join(SCENES, "chaotic", "chain2_sticking.toml")
    a = vibro.attractors(vibro.load_scene(chaos, set={"run.periods": 600}), samples=4)
    assert a["unresolved_lyapunov"]["chaotic"] is True
    assert a == cli_json("attractors", chaos, "--set", "run.periods=600", "--samples", "4")
    s = vibro.sweep(vibro.load_scene(chaos), "excitation.frequency", 1.6, 1.601, steps=1, one_way=True)
    assert [p["chaotic"] for p in s["points"]] == [True, True]
    assert s == cli_json("sweep", chaos, "--param", "excitation.frequency", "--from", "1.6", "--to", "1.601",
                         "--steps", "1", "--one-way")
    off = vibro.sweep(vibro.load_scene(chaos, set={"run.lyapunov": False}), "excitation.frequency", 1.6, 1.601,
                      steps=1, one_way=True)
    assert all("chaotic" not in p for p in off["points"])
