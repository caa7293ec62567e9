"""Peak force and contact duration of a compliant stop over a long run, with 95 % intervals
(docs/loads.md, "Peak force and contact duration over a run"), against truths written here without
vibro's code:

* a 1-DOF compliant scene settled on its periodic orbit (the scene of test_compliant_orbit.py, both
  separation rules): the orbit's contact phase integrated by mpmath's Taylor ODE solver at 30 digits
  from vibro's section state (test_compliant_orbit.return_map: peak force from λ' = 0, exit by
  bisection) gives the exact peak force and duration; `vibro orbit`'s loads carry them, and the
  long run's intervals contain them;
* the compliant tube where it is not periodic (ω = 1.45, past its grazing at 1.389): the means,
  largest peak and batch-means intervals recomputed here from the run's per-phase rows in its HDF5
  file (the releases of /events with a peak_time: reaction_max, stick_duration), equal to vibro's
  to rounding;
* the same run interrupted by SIGINT and resumed, and run in two invocations (--extend), report the
  uninterrupted run's figures to the bit.

ctest runs this file within python.pytest, with VIBRO_CLI set to the built `vibro`.
"""
import json
import os
import signal
import subprocess
import sys
import time

import h5py
import mpmath as mp
import numpy as np
import pytest

vibro = pytest.importorskip("vibro")

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_compliant_orbit import Ref, return_map, scene_text  # noqa: E402  (the same reference)

SCENES = os.environ.get("VIBRO_SCENES") or os.path.join(os.path.dirname(__file__), "..", "..", "data", "scenes")
TUBE = os.path.join(SCENES, "tube_compliant_support.toml")
# Two-sided 95 % quantiles of Student's t (standard tables), by degrees of freedom.
T975 = {4: 2.776, 9: 2.262, 19: 2.093}


@pytest.fixture(autouse=True)
def _keep_mpmath_precision():
    dps = mp.mp.dps
    yield
    mp.mp.dps = dps


def cli():
    path = os.environ.get("VIBRO_CLI", "")
    if not path:
        pytest.skip("VIBRO_CLI is not set")
    return path


def run_json(*args, check=True):
    p = subprocess.run([cli(), *args, "--json"], capture_output=True, text=True, timeout=900)
    if check:
        assert p.returncode == 0, p.stderr[-2000:]
    return json.loads(p.stdout) if p.returncode == 0 else p


@pytest.mark.parametrize("rule", ["force", "gap"])
def test_long_run_intervals_contain_the_orbits_exact_peak_and_duration(tmp_path, rule):
    path = tmp_path / f"{rule}.toml"
    path.write_text(scene_text(rule).replace("periods = 50", "periods = 1500"))
    scene = vibro.load_scene(str(path))
    out = tmp_path / f"{rule}_orbit.h5"
    o = vibro.orbit(scene, out=str(out))
    assert o["status"] == "converged" and o["period"] == 1 and len(o["contact_phases"]) == 1, o
    with h5py.File(out, "r") as f:
        a = f["orbit"].attrs
        t0, X, V = float(a["section_time"]), np.atleast_1d(a["X"]), np.atleast_1d(a["V"])
    # The truth: the orbit's contact phase integrated at 30 digits from vibro's section state.
    _, phases = return_map(mp.mpf(t0), [mp.mpf(X[0]), mp.mpf(V[0])], Ref(rule), periods=1, loads=True)
    assert len(phases) == 1
    peak, duration = float(phases[0]["peak_force"]), float(phases[0]["exit"] - phases[0]["entry"])
    # vibro orbit's per-orbit loads: one phase per period, its peak and duration.
    (c,) = o["loads"]
    assert c["contact_phases_per_period"] == 1.0
    assert abs(c["peak_force_mean"] - peak) <= 1e-13 * peak, (c["peak_force_mean"], peak)
    assert abs(c["peak_force_max"] - peak) <= 1e-13 * peak, (c["peak_force_max"], peak)
    assert abs(c["contact_duration_mean"] - duration) <= 1e-11 * duration, (c["contact_duration_mean"], duration)
    assert c["work_rate"] is None, "a compliant stop has no rigid-limit work rate"
    # The long run (1500 periods, settled long before its window starts at period 150): the
    # intervals contain the truth and are narrow (the blocks agree to rounding).
    r = vibro.simulate(scene, blocks=10)
    assert r.summary["attractor"]["kind"] == "contact-periodic", r.summary["attractor"]
    (run,) = r.summary["loads"]
    for key, want in (("peak_force_mean", peak), ("contact_duration_mean", duration),
                      ("contact_phases_per_period", 1.0)):
        lo, hi = run[key + "_ci"]
        assert lo <= want <= hi, (key, lo, want, hi)
        assert hi - lo <= 1e-9 * want, (key, hi - lo)
    assert abs(run["peak_force_max"] - peak) <= 1e-12 * peak, (run["peak_force_max"], peak)
    # The CLI says the same.
    js = run_json("simulate", str(path), "--blocks", "10")
    (c,) = js["loads"]
    for key in ("peak_force_mean", "peak_force_mean_ci", "contact_duration_mean", "contact_duration_mean_ci",
                "peak_force_max", "contact_phases_per_period"):
        assert c[key] == run[key], (key, c[key], run[key])


def independent_loads(path, window, blocks):
    """Per contact: (mean peak, its interval, mean duration, its interval, largest peak, phases per
    period) recomputed from the file's per-phase rows over vibro's window (its first period and
    length, the blocks its last `blocks`·L periods, L = block_periods): each block's ratio Σ peak /
    phases, the window's ratio, ± max(t s/√N, 16 ε L |mean of the block ratios|)."""
    with h5py.File(path, "r") as f:
        kinds = h5py.check_enum_dtype(f["events/kind"].dtype)
        ev = {k: f["events/" + k][()] for k in ("kind", "period", "contact", "peak_time", "reaction_max",
                                                 "stick_duration")}
    rel = (ev["kind"] == kinds["release"]) & np.isfinite(ev["peak_time"])
    a, n, L = window["first_period"], window["periods"], window["block_periods"]
    out = []
    for j in sorted(set(ev["contact"][rel].tolist())):
        sel = rel & (ev["contact"] == j)
        per, peak, dur = ev["period"][sel], ev["reaction_max"][sel], ev["stick_duration"][sel]
        win = (per >= a) & (per < a + n)
        res = {"phases_per_period": win.sum() / n, "peak_max": peak[win].max(),
               "peak_mean": peak[win].sum() / win.sum(), "duration_mean": dur[win].sum() / win.sum()}
        first_block = a + n - blocks * L
        for name, x in (("peak", peak), ("duration", dur)):
            ratios = []
            for i in range(blocks):
                b = (per >= first_block + i * L) & (per < first_block + (i + 1) * L)
                ratios.append(x[b].sum() / b.sum())
            ratios = np.array(ratios)
            half = max(T975[blocks - 1] * ratios.std(ddof=1) / np.sqrt(blocks),
                       16 * np.finfo(float).eps * L * abs(ratios.mean()))
            res[name + "_ci"] = (res[name + "_mean"] - half, res[name + "_mean"] + half)
        out.append(res)
    return out


def close(a, b, rel=1e-12):
    return abs(a - b) <= rel * max(abs(a), abs(b))


def test_irregular_tube_intervals_from_the_per_phase_rows(tmp_path):
    out = tmp_path / "tube145.h5"
    js = run_json("simulate", TUBE, "--set", "excitation.frequency=1.45", "--set", "run.periods=1000",
                  "--set", "run.samples_per_period=0", "--out", str(out))
    assert js["attractor"]["kind"] == "not-periodic", js["attractor"]
    w = js["loads_window"]
    assert w["block_periods"] > 0 and w["blocks"] == 10, w
    ref = independent_loads(out, w, 10)
    assert len(ref) == 2 == len(js["loads"])
    for c, r in zip(js["loads"], ref):
        assert close(c["contact_phases_per_period"], r["phases_per_period"]), (c, r)
        assert c["peak_force_max"] == r["peak_max"], (c["peak_force_max"], r["peak_max"])
        for key, name in (("peak_force_mean", "peak"), ("contact_duration_mean", "duration")):
            assert close(c[key], r[name + "_mean"]), (key, c[key], r[name + "_mean"])
            lo, hi = c[key + "_ci"]
            rlo, rhi = r[name + "_ci"]
            # Not a settled orbit: the interval is wide (the block ratios differ), and equal to the
            # independent one to rounding (t from the table: both use 2.262 for 9 degrees of freedom).
            assert hi - lo > 1e-4 * c[key], (key, lo, hi)
            assert close(hi - lo, rhi - rlo, 1e-9) and close(lo, rlo) and close(hi, rhi), (key, (lo, hi), (rlo, rhi))
        assert c["work_rate"] is None and c["work_rate_ci"] is None
    # The text's attractor line: a compliant stop is never "sticking" (docs/compliant.md), also when
    # the motion is not periodic.
    text = subprocess.run([cli(), "simulate", TUBE, "--set", "excitation.frequency=1.45", "--set", "run.periods=300"],
                          capture_output=True, text=True, timeout=600)
    assert text.returncode == 0, text.stderr
    line = next(x for x in text.stdout.splitlines() if x.startswith("attractor"))
    assert "not-periodic" in line and "contact fraction" in line and "sticking" not in line, line


def interrupt(args, path, past_period):
    """Runs vibro with `args` and sends SIGINT once the file is running with a checkpoint past
    `past_period`; returns the exit code."""
    proc = subprocess.Popen([cli(), *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 600
    while time.time() < deadline and proc.poll() is None:
        time.sleep(0.05)
        try:
            with h5py.File(path, "r") as f:
                if f.attrs["status"] == "running" and f["checkpoint"].attrs["period"] > past_period:
                    break
        except Exception:  # noqa: BLE001 (not created yet, or a flush in progress)
            pass
    proc.send_signal(signal.SIGINT)
    proc.communicate(timeout=600)
    return proc.returncode


COMPLIANT_KEYS = ("contact_phases_per_period", "contact_phases_per_period_ci", "peak_force_mean",
                  "peak_force_mean_ci", "contact_duration_mean", "contact_duration_mean_ci", "peak_force_max")


def same_loads(got, want):
    assert got["loads_window"] == want["loads_window"], (got["loads_window"], want["loads_window"])
    assert len(got["loads"]) == len(want["loads"]) == 2
    for x, y in zip(got["loads"], want["loads"]):
        for key in COMPLIANT_KEYS:
            assert key in y
        for key in sorted(set(x) | set(y)):
            assert x.get(key) == y.get(key), (key, x.get(key), y.get(key))


def test_resumed_and_extended_runs_give_the_whole_runs_figures_to_the_bit(tmp_path):
    base = [TUBE, "--set", "excitation.frequency=1.45", "--set", "run.samples_per_period=4"]
    whole = run_json("simulate", *base, "--set", "run.periods=1200", "--out", str(tmp_path / "whole.h5"))
    # Two invocations: 500 periods, then 700 more. Period 500 begins in the relaxing flight after a
    # force-rule exit (the surface still on its way back): the checkpoint carries it.
    ext = tmp_path / "ext.h5"
    run_json("simulate", *base, "--set", "run.periods=500", "--out", str(ext))
    with h5py.File(ext, "r") as f:
        assert int(f["checkpoint"].attrs["relax_contact"]) >= 0, dict(f["checkpoint"].attrs)
    same_loads(run_json("simulate", *base, "--out", str(ext), "--extend", "700"), whole)
    # A period boundary inside a contact phase (the first after period 100 in the whole run): the
    # checkpoint carries the phase's account (peak, its time, penetration, dissipated energy).
    with h5py.File(tmp_path / "whole.h5", "r") as f:
        kinds = h5py.check_enum_dtype(f["events/kind"].dtype)
        kind, t = f["events/kind"][()], f["events/t"][()]
    T = 2 * np.pi / 1.45
    inside = [int(np.ceil(a / T)) for a, b, k in zip(t[:-1], t[1:], kind[:-1])
              if k == kinds["stick"] and np.floor(b / T) > np.floor(a / T) and a > 100 * T]
    assert inside, "no contact phase across a period boundary"
    ext2 = tmp_path / "ext2.h5"
    run_json("simulate", *base, "--set", f"run.periods={inside[0]}", "--out", str(ext2))
    with h5py.File(ext2, "r") as f:
        assert int(f["checkpoint"].attrs["mode"]) == 1, dict(f["checkpoint"].attrs)  # in contact
    same_loads(run_json("simulate", *base, "--out", str(ext2), "--extend", str(1200 - inside[0])), whole)
    # Interrupted by SIGINT, then resumed (a longer run, so that the signal comes inside it).
    long = [TUBE, "--set", "excitation.frequency=1.45", "--set", "run.samples_per_period=0",
            "--set", "run.periods=20000"]
    whole = run_json("simulate", *long, "--out", str(tmp_path / "whole20k.h5"))
    res = tmp_path / "res.h5"
    args = ["simulate", *long, "--out", str(res)]
    interrupt(args, res, 1000)
    with h5py.File(res, "r") as f:
        stopped, status = int(f["checkpoint"].attrs["period"]), str(f.attrs["status"])
    if status != "interrupted":
        pytest.skip(f"the run was not interrupted inside ({status}): nothing to resume")
    assert 1000 < stopped < 20000, stopped
    same_loads(run_json(*args, "--resume"), whole)
