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
             ("resonant", "fig11_clearance.toml", ("excitation.frequency=1.0", "excitation.amplitude=0.05")),
             # A sum of two harmonics with their own forcing vectors and a phase (docs/harmonics.md):
             # the file's /model carries them, and the flight sums their particular solutions.
             ("two_harmonics", "two_harmonics_chain2.toml", ())]
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

    # Compliant stops (docs/compliant.md): the contact phase is linear, so the plot draws it
    # exactly (vibro_plot.compliant_states). Its truth is the exact engine's samples: from each
    # sample, through every entry and exit of its step, to the next sample; and the certified
    # peak of each phase (the release's reaction_max) is never exceeded by the drawn force.
    for name, scene in (("tube_compliant", "tube_compliant_support.toml"), ("sdnd121", "sdnd121_compliant.toml")):
        h5 = simulate(d, name, scene, "run.periods=20", "run.samples_per_period=128")
        with h5py.File(h5) as f:
            cs = vibro_plot.compliant_contacts(f)
            t, X, V = f["samples/t"][:], f["samples/X"][:], f["samples/V"][:]
            ev, kinds = f["events/t"][:], f["events/kind"][:]
            ev_c = f["events/contact"][:] if "contact" in f["events"] else np.zeros(len(ev), dtype=int)
            kind_of = h5py.check_enum_dtype(f["events/kind"].dtype)
            tt, XX, VV, jj = vibro_plot.compliant_states(f, t[0], t[-1], cs)
            n = X.shape[1]
            worst, compared = 0.0, 0
            for k in range(len(t) - 1):
                inside = np.nonzero((ev > t[k]) & (ev < t[k + 1]))[0]
                if not len(inside):
                    continue
                i = inside[-1]
                p_ = np.nonzero(tt == ev[i])[0]
                if not len(p_):
                    continue
                after = int(ev_c[i]) if kinds[i] == kind_of["stick"] else -1
                A = vibro_plot.phase_generator(f["model"], None if after < 0 else cs[after])
                y = np.concatenate([XX[p_[-1]], VV[p_[-1]], vibro_plot.forcing_phases(f["model"], [ev[i]])[0], [1.0]])
                y1 = vibro_plot.expm_batch(A[None] * (t[k + 1] - ev[i]))[0] @ y
                worst = max(worst, np.abs(y1[:n] - X[k + 1]).max() / np.abs(X).max(),
                            np.abs(y1[n:2 * n] - V[k + 1]).max() / np.abs(V).max())
                compared += 1
            rel = kinds == kind_of["release"]
            check(f"{name}: the drawn contact phases and flights reach the next sample through every entry "
                  f"and exit ({compared} steps)", compared >= rel.sum() and worst < 1e-9, f"worst {worst:.3g}")
            lam = vibro_plot.contact_forces(cs, XX, VV, jj)
            peaks = f["events/reaction_max"][:]
            # The peaks' instants are on the drawn grid: phase by phase, the largest drawn force is
            # the certified peak, evaluated independently (the matrix exponential of the phase).
            durations = f["events/stick_duration"][:]
            off, phases = 0.0, 0
            for i in np.nonzero(rel)[0]:
                j = int(ev_c[i])
                span = (tt >= ev[i] - durations[i]) & (tt <= ev[i])
                if not span.any():
                    continue
                off = max(off, abs(np.nanmax(lam[span, j]) - peaks[i]) / peaks[i])
                phases += 1
            check(f"{name}: every phase's drawn force reaches its certified peak and never exceeds it ({phases} phases)",
                  phases == rel.sum() > 5 and off <= 1e-9, f"worst relative {off:.3g}")
            inside = jj >= 0
            check(f"{name}: in contact the drawn gap is a penetration (g ≤ 0), in flight a clearance",
                  inside.any() and all((cs[j][2] * (XX[jj == j] @ cs[j][1] - cs[j][3]) <= 1e-12).all()
                                       for j in set(jj[inside].tolist())), "")
        for prefix in (name,):
            out = os.path.join(d, prefix)
            p = subprocess.run([vibro, "plot", h5, "--out", out], capture_output=True, text=True)
            made = sorted(n_ for n_ in os.listdir(d) if n_.startswith(prefix + "_"))
            check(f"{name}: vibro plot draws the forces and the peak histograms, no R* panel",
                  p.returncode == 0 and f"{prefix}_forces.png" in made and f"{prefix}_peaks.png" in made
                  and f"{prefix}_reaction.png" not in made, (p.returncode, p.stderr[-300:], made))

    # A run stored with 8 samples per period is drawn like one stored with 512.
    fine = simulate(d, "fine", "fig08_preload.toml", "run.periods=10", "run.samples_per_period=512")
    coarse = simulate(d, "coarse", "fig08_preload.toml", "run.periods=10", "run.samples_per_period=8")
    with h5py.File(fine) as ff, h5py.File(coarse) as fc:
        T = float(fc.attrs["forcing_period"])
        t_end = fc["samples/t"][-1]
        t0 = t_end - 3 * T
        tt, xx, vv, *_ = vibro_plot.dense_run(fc, t0, t_end)
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

    # --coordinate: a physical and a modal coordinate of the 3-DOF chain (sticking while masses 1
    # and 2 move), drawn from 16 samples per period, against the engine's exact states sampled
    # 512 times per period (q = Ψ X).
    fine = simulate(d, "c3fine", "chain3.toml", "run.periods=10", "run.samples_per_period=512")
    coarse = simulate(d, "c3coarse", "chain3.toml", "run.periods=10", "run.samples_per_period=16")
    with h5py.File(fine) as ff, h5py.File(coarse) as fc:
        T = float(fc.attrs["forcing_period"])
        t_end = fc["samples/t"][-1]
        t0 = t_end - 3 * T
        tt, _, _, _, XX, VV = vibro_plot.dense_run(fc, t0, t_end)
        choices = vibro_plot.coordinate_choices(fc)
        check("chain3 offers x_B, X1..X3, q0..q2", sorted(choices) == ["X1", "X2", "X3", "q0", "q1", "q2", "x_B"],
              sorted(choices))
        tf = ff["samples/t"][:]
        sel = (tf > t0) & (tf < t_end)
        stuck = ff["samples/mode"][:][sel] == 1
        XX, VV = vibro_plot.fill_stuck_states(fc, tt, XX, VV)
        for name in ("q0", "q1", "X2"):
            w, _ = choices[name]
            y, yd = XX @ w, VV @ w
            truth, truth_d = ff["samples/X"][:][sel] @ w, ff["samples/V"][:][sel] @ w
            drawn, drawn_d = np.interp(tf[sel], tt, y), np.interp(tf[sel], tt, yd)
            scale = np.abs(truth).max()
            err = np.abs(drawn - truth) / scale
            # The drawn points are exact; comparing at the fine samples' times interpolates
            # linearly between them (1500 per period: about (ω·T/1500)²/8 ≈ 1e-6).
            check(f"chain3 {name}: drawn within 1e-5 of the exact states, sticking phases included "
                  f"({stuck.sum()} of {sel.sum()} stuck)", stuck.sum() > 100 and err.max() < 1e-5,
                  f"worst {err.max():.3g} (free {err[~stuck].max():.3g}, stuck {err[stuck].max():.3g})")
            check(f"chain3 {name}: its velocity too", np.abs(drawn_d - truth_d).max() < 1e-4 * np.abs(truth_d).max(),
                  np.abs(drawn_d - truth_d).max())
        # The sticking motion itself, at the fine samples' own times: exact to rounding.
        ts = tf[sel][stuck]
        Xf, Vf = vibro_plot.fill_stuck_states(fc, ts, np.full((len(ts), 3), np.nan), np.full((len(ts), 3), np.nan))
        errs = max(np.abs(Xf - ff["samples/X"][:][sel][stuck]).max(), np.abs(Vf - ff["samples/V"][:][sel][stuck]).max())
        check("chain3 sticking motion (exp of its generator) equals the engine's stuck states to 1e-10",
              errs < 1e-10, errs)
        psi = fc["model"].attrs["mode_shapes"]
        check("q2 (contact DOF) is x_B", np.allclose(choices["q2"][0], choices["x_B"][0]) and np.allclose(psi[2], 1.0),
              psi[2])

    # chain3 sticking under two harmonics (the amplitude split 0.7 + 0.3 at 0.8 and 1.6, a phase on
    # the second): the sticking motion drawn from 16 samples per period (exp of the generator with a
    # (sin, cos) pair per harmonic) against the engine's states at 512 per period.
    with open(os.path.join(scenes, "chain3.toml")) as fh:
        text = fh.read().replace("amplitude = 1.0\nfrequency = 0.8",
                                 "amplitude = [0.7, 0.3]\nfrequency = [0.8, 1.6]\nphase = [0.0, 0.9]")
    check("chain3 with two harmonics written", "[0.7, 0.3]" in text)
    with open(os.path.join(d, "chain3_h2.toml"), "w") as fh:
        fh.write(text)
    fine = simulate(d, "h2fine", os.path.join(d, "chain3_h2.toml"), "run.periods=10", "run.samples_per_period=512")
    coarse = simulate(d, "h2coarse", os.path.join(d, "chain3_h2.toml"), "run.periods=10", "run.samples_per_period=16")
    with h5py.File(fine) as ff, h5py.File(coarse) as fc:
        check("/model carries the harmonics", list(fc["model"].attrs["harmonic_frequencies"]) == [0.8, 1.6],
              dict(fc["model"].attrs))
        T = float(fc.attrs["forcing_period"])
        t_end = fc["samples/t"][-1]
        t0 = t_end - 3 * T
        tf = ff["samples/t"][:]
        sel = (tf > t0) & (tf < t_end)
        stuck = ff["samples/mode"][:][sel] == 1
        ts = tf[sel][stuck]
        Xf, Vf = vibro_plot.fill_stuck_states(fc, ts, np.full((len(ts), 3), np.nan), np.full((len(ts), 3), np.nan))
        errs = max(np.abs(Xf - ff["samples/X"][:][sel][stuck]).max(), np.abs(Vf - ff["samples/V"][:][sel][stuck]).max())
        check(f"chain3 under two harmonics: sticking motion equals the engine's stuck states to 1e-10 "
              f"({len(ts)} stuck samples)", len(ts) > 100 and errs < 1e-10, errs)
        tt, xx, *_ = vibro_plot.dense_run(fc, t0, t_end)
        free = ~(ff["samples/mode"][:][sel] == 1)
        drawn = np.interp(tf[sel][free], tt, xx)
        err = np.abs(drawn - ff["samples/x_B"][:][sel][free]).max()
        check("chain3 under two harmonics: x_B drawn in flight within 1e-5 of the engine's",
              err < 1e-5 * np.abs(ff["samples/x_B"][:][sel]).max(), err)

    # `vibro plot` options (docs/cli.md): --size, --font-size, --title, --coordinate, editable SVG
    # text, absolute time ticks, bifurcation kinds on a sweep overlay.
    import re

    def plot(h5, prefix, *options):
        return subprocess.run([vibro, "plot", h5, "--out", os.path.join(d, prefix), *options],
                              capture_output=True, text=True)

    def svg_texts(path):
        """The strings of the SVG's <text> elements (matplotlib writes them when svg.fonttype is
        'none'; glyph paths otherwise)."""
        with open(path) as fh:
            svg = fh.read()
        return [re.sub(r"<[^>]+>", "", m) for m in re.findall(r"<text[^>]*>(.*?)</text>", svg, re.S)]

    c3 = simulate(d, "c3", "chain3.toml", "run.periods=10", "run.samples_per_period=64")
    p = plot(c3, "c3a", "--format", "svg", "--size", "8.5cm,6cm", "--font-size", "7", "--coordinate", "q1",
             "--title", "Mass 2 of the chain")
    check("plot --size --coordinate q1: exit 0", p.returncode == 0, p.stderr)
    q1 = os.path.join(d, "c3a_q1.svg")
    texts = svg_texts(q1) if os.path.exists(q1) else []
    with open(q1) as fh:
        head = fh.read(2000)
    size = re.search(r'width="([0-9.]+)pt" height="([0-9.]+)pt"', head)
    check("--size 8.5cm,6cm: the picture is exactly 8.5 cm x 6 cm",
          size and abs(float(size.group(1)) - 8.5 / 2.54 * 72) < 0.01 and abs(float(size.group(2)) - 6 / 2.54 * 72) < 0.01,
          size and size.groups())
    check("SVG text is editable: <text> elements with the title and tick labels",
          "Mass 2 of the chain" in texts and len(texts) > 10, texts[:20])
    check("--font-size 7: the SVG text is 7 pt", re.search(r"font: ?(?:[^;]*? )?7px|font-size: ?7px|font: 7px", open(q1).read())
          is not None or "7px" in open(q1).read(), "no 7px text")
    p = plot(c3, "c3b", "--format", "svg", "--title", "")
    texts = svg_texts(os.path.join(d, "c3b_xB.svg"))
    check("--title '': no title", p.returncode == 0 and not any("chain" in t or "contact displacement" in t for t in texts),
          texts)
    for bad, why in ((("--coordinate", "q3"), "q0..q2"), (("--coordinate", "X0"), "X1..X3"),
                     (("--size", "4x3"), "W,H"), (("--size", "8.5cm,3"), "W,H")):
        p = plot(c3, "bad", *bad)
        made = [n for n in os.listdir(d) if n.startswith("bad")]
        check(f"plot {' '.join(bad)}: exit 2, says why, writes nothing",
              p.returncode == 2 and why in p.stderr and not made, (p.returncode, p.stderr, made))
    fig08 = simulate(d, "late", "fig08_preload.toml", "run.periods=10", "initial.time=897500")
    p = plot(fig08, "late", "--format", "svg", "--coordinate", "q0")
    check("--coordinate q0 on a modal-form file: exit 2, no mode shapes stored",
          p.returncode == 2 and "no mode shapes" in p.stderr, p.stderr)
    p = plot(fig08, "late", "--format", "svg")
    ticks = [t for t in svg_texts(os.path.join(d, "late_xB.svg")) if re.fullmatch(r"[0-9.−-]+", t.strip())]
    offsets = [t for t in svg_texts(os.path.join(d, "late_xB.svg")) if re.search(r"^\s*\+|×|\de[+−-]?\d", t)]
    check("absolute time ticks: 8975xx, no offset +8.975e5",
          any(t.startswith("8975") for t in ticks) and not offsets, (ticks, offsets))

    # A sweep over a continuation branch with five kinds of bifurcation: one legend entry each.
    branch = os.path.join(d, "c2br.h5")
    sweep = os.path.join(d, "c2sw.h5")
    common = [os.path.join(scenes, "chain2.toml"), "--set", "stop.restitution=0.0", "--set", "excitation.frequency=0.4"]
    p = subprocess.run([vibro, "continue", *common, "--set", "excitation.amplitude=1.0", "--param", "excitation.amplitude",
                        "--to", "1.6", "--out", branch], capture_output=True, text=True)
    check("chain2 continuation", p.returncode == 0, p.stderr)
    p = subprocess.run([vibro, "sweep", *common, "--param", "excitation.amplitude", "--from", "1.0", "--to", "1.4",
                        "--steps", "10", "--out", sweep], capture_output=True, text=True)
    check("chain2 sweep", p.returncode == 0, p.stderr)
    with h5py.File(branch) as f:
        kinds = [vibro_plot.text(k) for k in f["bifurcations/kind"][:]]
    p = plot(sweep, "c2", "--format", "svg", "--overlay", branch)
    texts = svg_texts(os.path.join(d, "c2_sweep.svg"))
    entries = {k: sum(t.startswith(k + " (") for t in texts) for k in set(kinds)}
    check("sweep overlay: one legend entry per bifurcation kind",
          p.returncode == 0 and len(set(kinds)) >= 4 and len(kinds) > len(set(kinds)) and all(n == 1 for n in entries.values()),
          (kinds, entries))
    check("sweep overlay: a marker shape per kind",
          len({vibro_plot.BIFURCATION_MARKERS[k] for k in set(kinds)}) == len(set(kinds)), kinds)

    # Several contacts (docs/contacts.md): PREFIX_gaps, one panel per contact, the gaps drawn from
    # the samples open; PREFIX_phase and PREFIX_section of every gap; --coordinate draws its own.
    beam = simulate(d, "beam3", "contacts_beam3.toml", "run.periods=6", "run.samples_per_period=64")
    p = plot(beam, "beam3", "--format", "svg")
    texts = svg_texts(os.path.join(d, "beam3_gaps.svg")) if p.returncode == 0 else []
    check("several contacts: PREFIX_gaps with a panel per contact",
          p.returncode == 0 and sum(t.startswith("contact ") for t in texts) == 5 and
          not os.path.exists(os.path.join(d, "beam3_xB.svg")), (p.stderr, texts[:8]))
    with h5py.File(beam) as f:
        X = f["samples/X"][:]
        q = X @ np.asarray(f["model"].attrs["mode_shapes"]).reshape(-1, X.shape[1]).T
    check("several contacts: the samples keep q0 between its stops at -0.1 and 0.1",
          (q[:, 0] >= -0.1 - 1e-9).all() and (q[:, 0] <= 0.1 + 1e-9).all(), (q[:, 0].min(), q[:, 0].max()))
    check("several contacts: PREFIX_phase and PREFIX_section of every gap",
          all(os.path.exists(os.path.join(d, f"beam3_{k}.svg")) for k in ("phase", "section")) and
          sum(t.startswith("contact ") for t in svg_texts(os.path.join(d, "beam3_phase.svg"))) == 5, p.stderr)
    p = plot(beam, "beam3q", "--coordinate", "q1")
    check("several contacts: --coordinate q1 draws PREFIX_q1, _phase and _section",
          p.returncode == 0 and all(os.path.exists(os.path.join(d, f"beam3q_{k}.png")) for k in ("q1", "phase", "section")),
          p.stderr)
    # The dense states between coarse samples (free flights forward to each event and back from the
    # next sample) against the physics and a finely sampled run of the same scene: every gap stays
    # open, the contact of each impact is closed at its instant on both sides, and the dense q
    # reach the extremes the engine's fine samples reach.
    coarse = simulate(d, "beam3c", "contacts_beam3.toml", "run.periods=6", "run.samples_per_period=32")
    fine = simulate(d, "beam3f", "contacts_beam3.toml", "run.periods=6", "run.samples_per_period=2048")
    with h5py.File(coarse) as f:
        contacts = vibro_plot.scene_contacts(f)
        gaps = vibro_plot.gap_coordinates(f, contacts)
        T = float(f.attrs["forcing_period"])
        t0, t1 = f["samples/t"][0], f["samples/t"][-1]
        tt, XX, VV = vibro_plot.dense_states(f, t0, t1, per_period=4000)
        ev_t, ev_c, kinds = f["events/t"][:], f["events/contact"][:], f["events/kind"][:]
        impact = h5py.check_enum_dtype(f["events/kind"].dtype)["impact"]
        psi = np.asarray(f["model"].attrs["mode_shapes"]).reshape(-1, XX.shape[1])
    known = np.isfinite(tt)
    lowest = min(float((sigma * (XX[known] @ a - dd)).min()) for a, sigma, dd, _ in gaps)
    check("several contacts: the dense states keep every gap open", lowest >= -1e-9, lowest)
    worst = 0.0
    for te, j in zip(ev_t[kinds == impact], ev_c[kinds == impact]):
        a, sigma, dd, _ = gaps[j]
        at = known & (np.abs(tt - te) <= 1e-12 * max(1.0, abs(te)))
        if at.any():
            worst = max(worst, float(np.abs(sigma * (XX[at] @ a - dd)).max()))
    check("several contacts: each impact's gap is closed at its instant in the dense states",
          worst <= 1e-9 and (kinds == impact).sum() > 0, worst)
    with h5py.File(fine) as f:
        qf = f["samples/X"][:] @ psi.T
    qd = XX[known] @ psi.T
    # 2048 samples a period resolve an extreme to about (2π/2048)²/8 of the range: 1e-6.
    off = max(max(abs(qd[:, i].max() - qf[:, i].max()), abs(qd[:, i].min() - qf[:, i].min())) / np.ptp(qf[:, i])
              for i in range(qf.shape[1]))
    check("several contacts: the dense q of 32 samples a period reach the extremes of 2048", off <= 1e-4, off)
    # A refused plot writes nothing (issue 38): every option is checked before the first picture,
    # here options that were refused only after PREFIX_loads had been written.
    for prefix, options, why in (("refq", ("--coordinate", "q7"), "q7"),
                                 ("refw", ("--time-window", "1e300,1e301"), "--time-window"),
                                 ("refo", ("--overlay", beam), "--overlay")):
        p = plot(beam, prefix, *options)
        made = [n for n in os.listdir(d) if n.startswith(prefix)]
        check(f"several contacts: plot {' '.join(options[:1])} refused (exit 2, says why), nothing written",
              p.returncode == 2 and why in p.stderr and not made, (p.returncode, p.stderr, made))
    p = plot(c3, "refw3", "--time-window", "1e300,1e301")
    made = [n for n in os.listdir(d) if n.startswith("refw3")]
    check("--time-window outside the run: exit 2, nothing written", p.returncode == 2 and not made,
          (p.returncode, p.stderr, made))
    # A title matplotlib cannot typeset, or too long for any picture: named, not "data damaged".
    for prefix, title, why in (("reft1", "$\\frac{$", "cannot typeset"), ("reft2", "x" * 10000, "10000 characters")):
        p = plot(c3, prefix, "--title", title)
        made = [n for n in os.listdir(d) if n.startswith(prefix)]
        check(f"--title {title[:12]!r}: exit 2 naming the title, nothing written",
              p.returncode == 2 and "--title" in p.stderr and why in p.stderr and "damaged" not in p.stderr
              and len(p.stderr.strip().splitlines()) == 1 and not made, (p.returncode, p.stderr[:300], made))
        # Named as typed: the backslash of its mathtext once, not doubled as repr() shows it.
        check(f"--title {title[:12]!r}: the message shows the title as typed",
              f"'{title[:57]}" in p.stderr, p.stderr[:300])
    p = plot(c3, "okt", "--title", "$\\omega = 1.2$, $x_B$")
    check("--title with mathtext that typesets: exit 0", p.returncode == 0, p.stderr)

finish()
