"""What the contacts endure (docs/loads.md) through Python: the events' fields, the summary's loads,
the orbit's exact values, and the blocks argument."""
import math
import os

import numpy as np
import pytest

import vibro
from conftest import SCENES


def test_event_fields_and_summary_agree():
    r = vibro.simulate(os.path.join(SCENES, "fig08_preload.toml"), blocks=10)
    e = r.events
    for name in ("impulse", "energy_dissipated", "stick_duration", "reaction_integral", "reaction_max"):
        assert name in e.dtype.names
    impacts = e["kind"] == 1
    # One stop with unit effective mass (T_B = 1): P = (1 + r)|v⁻|, E = ½(1 − r²)v⁻².
    r_ = 0.75
    np.testing.assert_allclose(e["impulse"][impacts], (1 + r_) * np.abs(e["v_before"][impacts]), rtol=1e-12)
    np.testing.assert_allclose(e["energy_dissipated"][impacts], 0.5 * (1 - r_ ** 2) * e["v_before"][impacts] ** 2,
                               rtol=1e-12)
    releases = e["kind"] == 4
    assert np.all(np.isfinite(e["reaction_integral"][releases]))
    assert np.all(np.isnan(e["reaction_integral"][~releases]))
    loads = r.summary["loads"][0]
    w = r.summary["loads_window"]
    assert w["blocks"] == 10 and w["block_periods"] > 0
    lo, hi = loads["mean_force_ci"]
    assert lo <= loads["mean_force"] <= hi
    # The mean force from the events of the window, independently summed.
    T = 2 * math.pi / 2.8
    first, n = w["first_period"], w["periods"]
    t0, t1 = first * T, (first + n) * T
    sel = (e["t"] >= t0) & (e["t"] < t1)
    J = e["impulse"][sel].sum() + np.nansum(e["reaction_integral"][sel])
    assert abs(J / (n * T) - loads["mean_force"]) < 2e-2 * loads["mean_force"]  # phases cut at the window ends


def test_orbit_loads_equal_the_settled_run():
    path = os.path.join(SCENES, "fig08_preload.toml")
    o = vibro.orbit(path)
    assert o["status"] == "converged"
    exact = o["loads"][0]
    assert "mean_force_ci" not in exact
    run = vibro.simulate(path, blocks=10).summary["loads"][0]
    for k in ("impacts_per_period", "impulse_per_period", "reaction_integral_per_period", "mean_force",
              "dissipated_power", "work_rate", "contact_fraction"):
        lo, hi = run[k + "_ci"]
        assert lo - 1e-9 * abs(exact[k]) <= exact[k] <= hi + 1e-9 * abs(exact[k]), (k, exact[k], run[k + "_ci"])


def test_blocks_argument_and_too_short_run():
    path = os.path.join(SCENES, "fig08_preload.toml")
    with pytest.raises(ValueError):
        vibro.simulate(path, blocks=1)
    s = vibro.load_scene(path, set={"run.periods": 10})
    summary = vibro.simulate(s, blocks=10).summary
    assert summary["loads"][0]["mean_force_ci"] is None
    assert "too short" in summary["loads_window"]["note"]
