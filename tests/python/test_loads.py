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


def _mean_x(scene_path, value, t0, X, V, spp=4000):
    """⟨x⟩ over one period of the 1-DOF Fig. 8 orbit through (t0, X, V) at f = value: a dense run
    of two periods from that state, the trapezoid rule over the first period's samples. With
    ω_1 = 1 and T_A = T_B = 1 it is the mean elastic force, which the mean contact force must
    equal (momentum balance over a period, docs/loads.md §6)."""
    s = vibro.load_scene(scene_path, set={"excitation.amplitude": float(value), "initial.time": float(t0),
                                          "initial.displacement": [float(x) for x in X],
                                          "initial.velocity": [float(v) for v in V],
                                          "run.periods": 2, "run.samples_per_period": spp})
    smp = vibro.simulate(s).samples
    x = smp["x_B"][:spp + 1]
    T = 2 * math.pi / 2.8
    assert abs(smp["t"][spp] - smp["t"][0] - T) < 1e-9 * T
    return (x.sum() - 0.5 * (x[0] + x[-1])) * (T / spp) / T


def test_branch_loads(tmp_path):
    """Along a Fig. 8 branch: the loads arrays are the points' JSON and the file's /branch/loads;
    each point's mean force is the orbit's mean deflection (positions, not impulses); a point's
    loads are vibro.orbit's at its value."""
    path = os.path.join(SCENES, "fig08_preload.toml")
    out = str(tmp_path / "b.h5")
    scene = vibro.load_scene(path, set={"excitation.amplitude": 1.001})
    b = vibro.continue_(scene, "excitation.amplitude", 1.4, out=out)
    n = len(b["points"])
    assert n > 10
    for k in vibro.LOAD_FIELDS:
        assert b["loads"][k].shape == (n, 1)
        assert list(b["loads"][k][:, 0]) == [p["loads"][0][k] for p in b["points"]]
    f = vibro.read(out)["branch"]
    for k in vibro.LOAD_FIELDS:
        np.testing.assert_array_equal(f["loads"][k], b["loads"][k])
    assert f["loads"].attrs["contacts"] == 1 and all(note == "" for note in f["loads"]["note"])
    for i in range(0, n, n // 5):
        p = b["points"][i]
        F = b["loads"]["mean_force"][i, 0]
        mean_x = _mean_x(path, p["value"], f["section_time"][i], f["X"][i], f["V"][i])
        assert abs(F - mean_x) < 2e-6 * F, (p["value"], F, mean_x)
    for i in (n // 3, n // 2):
        p = b["points"][i]
        o = vibro.orbit(vibro.load_scene(path, set={"excitation.amplitude": p["value"]}))
        assert o["status"] == "converged"
        for k in vibro.LOAD_FIELDS:
            assert abs(o["loads"][0][k] - p["loads"][0][k]) <= 1e-8 * abs(o["loads"][0][k]) + 1e-14, k


def test_partition_cells_loads(tmp_path):
    """Over the Fig. 9 plane: the cells and their loads in the dict, the JSON and /partition/points;
    a cell's loads are vibro.orbit's at (ω, f)."""
    path = os.path.join(SCENES, "fig08_preload.toml")
    out = str(tmp_path / "p.h5")
    d = vibro.partition(path, ("excitation.frequency", "excitation.amplitude"), (2.8, 6.0), (1.0, 1.4), [0.5],
                        steps1=1, from2=1.02, out=out)
    cells = d["cells"]
    assert len(cells) == sum(len(c["points"]) for c in d["columns"]) > 20
    assert set(cells["value1"]) == {2.8, 6.0}
    g = vibro.read(out)["partition"]["points"]
    np.testing.assert_array_equal(g["value1"], cells["value1"])
    np.testing.assert_array_equal(g["value2"], cells["value2"])
    for k in vibro.LOAD_FIELDS:
        assert d["loads"][k].shape == (len(cells), 1)
        np.testing.assert_array_equal(g[k], d["loads"][k])
    i = len(cells) // 3
    w, fv = cells["value1"][i], cells["value2"][i]
    o = vibro.orbit(vibro.load_scene(path, set={"excitation.frequency": float(w), "excitation.amplitude": float(fv)}))
    assert o["status"] == "converged"
    for k in vibro.LOAD_FIELDS:
        assert abs(o["loads"][0][k] - d["loads"][k][i, 0]) <= 1e-8 * abs(o["loads"][0][k]) + 1e-14, k


def test_held_set_phases_in_closed_form():
    """Two masses held on both stops at once (contacts_held_pair.toml, docs/loads.md "Phases held on
    several contacts at once"): every phase of mass 1 has ∫λ_1 dt = 0.1Δt + 0.5(cos ωt_r − cos ωt_s)/ω
    and max λ_1 that of 0.1 − 0.5 sin ωt over [t_s, t_r] (λ = K d − b f sin ωt with q = d held), and
    the summary's loads are known."""
    path = os.path.join(os.path.dirname(__file__), "..", "reference", "contacts", "scenes", "contacts_held_pair.toml")
    r = vibro.simulate(vibro.load_scene(path, set={"run.periods": 20}))
    e = r.events
    w = 0.7
    one = e["contact"] == 1
    sticks, releases = e[one & (e["kind"] == 3)], e[one & (e["kind"] == 4)]
    assert len(releases) >= 15
    for rel in releases:
        ts = sticks["t"][sticks["t"] < rel["t"]].max()
        exact = 0.1 * (rel["t"] - ts) + 0.5 * (math.cos(w * rel["t"]) - math.cos(w * ts)) / w
        assert abs(rel["reaction_integral"] - exact) < 1e-12 * rel["t"], (rel["t"], rel["reaction_integral"], exact)
        lam = [0.1 - 0.5 * math.sin(w * t) for t in (ts, rel["t"])]
        k = math.ceil((w * ts - 1.5 * math.pi) / (2 * math.pi))  # sin ωt = −1 inside: λ = 0.6
        if ts < (1.5 * math.pi + 2 * math.pi * k) / w < rel["t"]:
            lam.append(0.6)
        assert abs(rel["reaction_max"] - max(lam)) < 1e-12, (rel["t"], rel["reaction_max"], max(lam))
    assert not np.any((e["contact"] == 0) & (e["kind"] == 4))  # mass 0 never leaves
    for c in r.summary["loads"]:
        assert c["mean_force"] is not None and c["reaction_integral_per_period"] is not None


def test_max_reaction_agrees_across_engines():
    """max R of every sticking phase of chain3.toml (a held flow of two modes) from the exact
    engine's certified search, from quad precision, and from CVODE's grid searched step by step
    (docs/loads.md §3): the same phases, the same maxima."""
    path = os.path.join(SCENES, "chain3.toml")
    runs = {}
    for name, sets in (("exact", {}), ("quad", {"run.precision": "quad"}),
                       ("cvode", {"run.engine": "cvode", "run.rtol": 1e-12, "run.atol": 1e-14})):
        e = vibro.simulate(vibro.load_scene(path, set={"run.periods": 12, **sets})).events
        rel = e[e["kind"] == 4]
        runs[name] = (rel["t"], rel["reaction_max"])
    t, m = runs["exact"]
    assert len(t) >= 10 and np.all(m[1:] > 1.0)  # the first: the rest it starts from (R = x0/φ)
    np.testing.assert_allclose(runs["quad"][0], t, atol=1e-10)
    np.testing.assert_allclose(runs["quad"][1], m, rtol=1e-12)
    np.testing.assert_allclose(runs["cvode"][0], t, atol=1e-6)
    np.testing.assert_allclose(runs["cvode"][1], m, rtol=1e-8)
