#!/usr/bin/python3
"""The dense flights of scripts/vibro_plot.py against the engine's own samples.

`vibro plot` draws free flights from the closed-form modal solution evaluated between the stored
samples (docs/model.md §2, §7). Its truth here is the exact engine: a run stored with many
samples per period must be reproduced by propagating each sample to the next one (no event in
between), on undamped, damped, multi-DOF and exactly resonant scenes; and a coarsely sampled run
must be drawn through the stop at every impact and as high as the finely sampled run.

    plot_test.py VIBRO SCENES_DIR SCRIPTS_DIR
"""
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

vibro, scenes, scripts = sys.argv[1:4]
sys.path.insert(0, scripts)
import vibro_plot  # noqa: E402


def simulate(d, name, scene, *sets):
    h5 = os.path.join(d, name + ".h5")
    args = [vibro, "simulate", os.path.join(scenes, scene), "--out", h5]
    for s in sets:
        args += ["--set", s]
    p = subprocess.run(args, capture_output=True, text=True)
    check(f"{name}: simulate", p.returncode == 0, p.stderr)
    return h5


with tempfile.TemporaryDirectory() as d:
    cases = [("fig08", "fig08_preload.toml", ()),
             ("chain2_damped", "chain2_damped.toml", ()),
             ("chain3", "chain3.toml", ()),
             # ω = ω_1 = 1: the secular (resonant) particular solution.
             ("resonant", "fig11_clearance.toml", ("excitation.frequency=1.0", "excitation.amplitude=0.05"))]
    for name, scene, sets in cases:
        h5 = simulate(d, name, scene, "run.periods=20", "run.samples_per_period=256", *sets)
        with h5py.File(h5) as f:
            t, X, V, mode = f["samples/t"][:], f["samples/X"][:], f["samples/V"][:], f["samples/mode"][:]
            ev = f["events/t"][:]
            worst, compared = 0.0, 0
            scale = max(1.0, np.abs(X).max(), np.abs(V).max())
            for k in range(len(t) - 1):
                if mode[k] or mode[k + 1] or t[k + 1] <= t[k]:
                    continue
                if np.any((ev >= t[k]) & (ev <= t[k + 1])):
                    continue
                Xk, Vk = vibro_plot.free_flight(f["model"], X[k], V[k], t[k], np.array([t[k + 1]]))
                worst = max(worst, np.abs(Xk[0] - X[k + 1]).max(), np.abs(Vk[0] - V[k + 1]).max())
                compared += 1
            check(f"{name}: closed-form flight reproduces the next sample ({compared} steps)",
                  compared > 100 and worst < 1e-9 * scale, f"worst {worst:.3g} over {compared}")

    # A run stored with 8 samples per period is drawn like one stored with 512.
    fine = simulate(d, "fine", "fig08_preload.toml", "run.periods=10", "run.samples_per_period=512")
    coarse = simulate(d, "coarse", "fig08_preload.toml", "run.periods=10", "run.samples_per_period=8")
    with h5py.File(fine) as ff, h5py.File(coarse) as fc:
        T = float(fc.attrs["forcing_period"])
        t_end = fc["samples/t"][-1]
        t0 = t_end - 3 * T
        tt, xx, vv, _ = vibro_plot.dense_run(fc, t0, t_end)
        x0 = float(fc["model"].attrs["stop"])
        kinds = h5py.check_enum_dtype(fc["events/kind"].dtype)
        ev_t, ev_k = fc["events/t"][:], fc["events/kind"][:]
        impacts = ev_t[(ev_k == kinds["impact"]) & (ev_t >= t0) & (ev_t <= t_end)]
        on_stop = [np.any((np.abs(tt - ti) < 1e-12) & (np.abs(xx - x0) < 1e-12)) for ti in impacts]
        check("coarse run drawn through the stop at every impact", len(impacts) > 10 and all(on_stop),
              f"{sum(on_stop)} of {len(impacts)}")
        check("drawn x_B never below the stop", xx.min() >= x0 - 1e-12, xx.min() - x0)
        tf, xf = ff["samples/t"][:], ff["samples/x_B"][:]
        peak_fine = xf[(tf >= t0) & (tf <= t_end)].max()
        peak_coarse_samples = fc["samples/x_B"][:][(fc["samples/t"][:] >= t0)].max()
        check("the drawn peak is the true peak, not the samples'",
              # 512 samples per period miss the peak by at most x''Δt²/8 ≈ 1e-5 of its height.
              -1e-12 <= xx.max() - peak_fine < 2e-5 * (peak_fine - x0) and
              peak_coarse_samples < peak_fine - 1e-4 * (peak_fine - x0),
              f"drawn {xx.max()!r}, 512 samples {peak_fine!r}, 8 samples {peak_coarse_samples!r}")

finish()
