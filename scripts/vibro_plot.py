#!/usr/bin/python3
"""Pictures of a vibro HDF5 file (called by `vibro plot FILE.h5 [options]`).

Draws what the file holds (docs/cli.md): for a run with dense samples PREFIX_xB (x_B against t,
sticking shaded, impacts marked), PREFIX_reaction (only when the run sticks), PREFIX_phase and
PREFIX_section (a run with several contacts: PREFIX_gaps, every gap, and PREFIX_phase and
PREFIX_section of every gap; a run with compliant stops: PREFIX_forces, every contact force
against t with its certified peaks, and PREFIX_peaks, histograms of the peak forces and contact
durations); PREFIX_multipliers for an orbit with multipliers; PREFIX_branch for a
continuation (and PREFIX_branch_loads: mean contact force and work rate along it; compliant stops:
PREFIX_branch_peaks, the certified peak force, contact duration and distance to the rigid model along
it), PREFIX_partition for a
partition (and PREFIX_partition_loads: the work rate over its plane), PREFIX_basin for a basin study, PREFIX_sweep for
a sweep (with a continuation branch overlaid by --overlay BRANCH.h5), PREFIX_curves for the
two-parameter curves of `vibro curve` (drawn over a partition's picture by
`vibro plot PARTITION.h5 --overlay CURVES.h5`). --coordinate draws another
coordinate than x_B (PREFIX_X2, PREFIX_q1); --title, --size and --font-size shape every picture
for a paper; SVG text stays text.

Free flights are drawn from the closed-form modal solution (docs/model.md §2, §7) evaluated
densely between the stored samples and events, so curves are smooth whatever
run.samples_per_period, and x_B reaches the stop exactly at every impact; multi-DOF sticking
phases, for coordinates other than x_B, from the exact sticking motion.
"""
import argparse
import os
import re
import sys
import textwrap

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# Okabe–Ito: distinguishable with every common colour-vision deficiency.
OKABE_ITO = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#000000"]
UP, DOWN, BRANCH, BIF = OKABE_ITO[0], OKABE_ITO[1], "#000000", OKABE_ITO[2]
STICK_SHADE = "#E69F00"

# Scene keys and the symbols the paper uses for them.
SYMBOLS = {"excitation.amplitude": "f", "excitation.frequency": "ω", "stop.restitution": "r",
           "stop.position": "x_0"}
PLAIN = {"excitation.amplitude": "f", "excitation.frequency": "ω", "stop.restitution": "r",
         "stop.position": "x0"}


def axis_label(key):
    """`$f$ (excitation.amplitude)` for a scene key, the key itself otherwise."""
    s = SYMBOLS.get(key)
    return f"${s}$ ({key})" if s else key


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


# What the user chose for every picture (main() sets it from the options; docs/cli.md):
# title None = the default two lines, "" = no title, else that text; size (W, H) in inches or None
# = each picture's own size, trimmed to what it draws; font_size in points (matplotlib's 10 by
# default, every other text size scales with it).
OPTIONS = {"title": None, "size": None, "font_size": 10.0}


def fs(points):
    """A text size given for the default font size of 10 pt, scaled to --font-size."""
    return points * OPTIONS["font_size"] / 10.0


def figure(*args, figsize, **kwargs):
    """plt.subplots at --size (laid out to fill exactly that size) or at the picture's own size."""
    if OPTIONS["size"] is not None:
        return plt.subplots(*args, figsize=OPTIONS["size"], layout="constrained", **kwargs)
    return plt.subplots(*args, figsize=figsize, **kwargs)


def set_title(ax, title, detail):
    """The default title: the scene line (make_title) over what the picture shows; --title TEXT
    replaces both lines, --title '' leaves the picture untitled."""
    chosen = OPTIONS["title"]
    if chosen == "":
        return
    ax.set_title(chosen if chosen is not None else f"{title}\n{detail}", fontsize=fs(9))


def absolute_time(ax):
    """Time ticks as the times themselves: no offset (+8.975e5) and no scientific notation."""
    from matplotlib.ticker import ScalarFormatter
    fmt = ScalarFormatter(useOffset=False)
    fmt.set_scientific(False)
    ax.xaxis.set_major_formatter(fmt)


def make_title(f, varied=(), width=100):
    """First title line: the scene's title without the parameter values it quotes, then the
    values as run, leaving out the varied parameters (their values are on an axis). A line longer
    than width characters is wrapped, never cut."""
    scene = text(f.attrs["scene"])
    m = re.search(r'^title\s*=\s*(["\'])(.*)\1\s*$', scene, re.M)
    name = m.group(2) if m else os.path.basename(f.filename)
    # "r = 0.75, omega = 2.8, f = 1.2" in a title: the values as run replace them.
    name = re.sub(r",?\s*\b(r|omega|ω|f|x0)\s*=\s*[-+0-9.eE]+", "", name).strip(" ,:")
    ma = f["model"].attrs
    values = {"stop.restitution": ma["restitution"], "excitation.frequency": ma["frequency"],
              "excitation.amplitude": ma["amplitude"]}
    tables = scene_contacts(f) or [scene_table(f, "stop")]
    if all(compliant_law(t) for t in tables):  # no restitution: the stops are spring–dashpots
        values.pop("stop.restitution")
    run = ", ".join(f"{PLAIN[k]} = {float(v):g}" for k, v in values.items() if k not in varied)
    line = f"{name}: {run}" if run else name
    return textwrap.fill(line, width=width, break_long_words=False)


# ---------------------------------------------------------------------------------------------
# Dense evaluation of free flights (docs/model.md §2 and §7).

def harmonics(model):
    """[(f_h, ω_h, ψ_h, T_A^(h), s_A^(h) = c·T_A^(h))]: the forcing Σ_h T_A^(h) f_h sin(ω_h t + ψ_h)
    in modal form (docs/harmonics.md); one entry, (f, ω, 0, T_A, s_A), for the single harmonic
    f sin ωt."""
    a = model.attrs
    if "harmonic_amplitudes" in a:
        TA = np.atleast_2d(np.asarray(a["harmonic_forcing"], dtype=float))
        c = np.asarray(a["contact_shape"], dtype=float)
        return [(float(fh), float(wh), float(ph), TA[k], float(c @ TA[k])) for k, (fh, wh, ph) in
                enumerate(zip(a["harmonic_amplitudes"], a["harmonic_frequencies"], a["harmonic_phases"]))]
    return [(float(a["amplitude"]), float(a["frequency"]), 0.0, np.asarray(a["forcing"], dtype=float),
             float(a["s_A"]))]


def free_flight(model, X0, V0, t0, t):
    """Modal state at times t (any order, before or after t0) of the free flight through
    (t0, X0, V0): Ẍ_i + 2ζ_iω_i Ẋ_i + ω_i² X_i = Σ_h T_A,i^(h) f_h sin(ω_h t + ψ_h), mode by mode,
    the particular solution summed over the harmonics."""
    a = model.attrs
    w, z = a["frequencies"], a["damping_ratios"]
    forcing = harmonics(model)
    t = np.asarray(t, dtype=float)
    s = t - t0
    X = np.empty((len(t), len(w)))
    V = np.empty_like(X)
    for i, (wi, zi) in enumerate(zip(w, z)):
        parts = []
        for f, W, ph, TA, _ in forcing:
            ta = TA[i]
            d2 = wi * wi - W * W
            D = d2 * d2 + (2 * zi * wi * W) ** 2
            if D > 1e-24 * max(1.0, wi ** 4):
                def U(tt, ta=ta, f=f, W=W, ph=ph, d2=d2, D=D):
                    return ta * f * (d2 * np.sin(W * tt + ph) - 2 * zi * wi * W * np.cos(W * tt + ph)) / D

                def dU(tt, ta=ta, f=f, W=W, ph=ph, d2=d2, D=D):
                    return ta * f * W * (d2 * np.cos(W * tt + ph) + 2 * zi * wi * W * np.sin(W * tt + ph)) / D
            else:  # undamped exact resonance: the secular particular solution
                def U(tt, ta=ta, f=f, W=W, ph=ph):
                    return -ta * f * tt * np.cos(W * tt + ph) / (2 * W)

                def dU(tt, ta=ta, f=f, W=W, ph=ph):
                    return -ta * f * (np.cos(W * tt + ph) - W * tt * np.sin(W * tt + ph)) / (2 * W)
            parts.append((U, dU))

        def Up(tt):
            return sum(U(tt) for U, _ in parts)

        def dUp(tt):
            return sum(dU(tt) for _, dU in parts)
        A = X0[i] - Up(t0)
        B = V0[i] - dUp(t0)
        al = zi * wi
        wd = wi * np.sqrt(1 - zi * zi)
        e = np.exp(-al * s)
        c, sn = np.cos(wd * s), np.sin(wd * s)
        X[:, i] = Up(t) + e * (A * c + (B + al * A) / wd * sn)
        V[:, i] = dUp(t) + e * (B * c - (wi * wi * A + al * B) / wd * sn)
    return X, V


def dense_run(f, t_from, t_to, per_period=1500):
    # At most about 2·10⁵ points, however long the window.
    """x_B, ẋ_B, the reaction a free state would need (R*, NaN while stuck) and the modal state
    X, Ẋ on a dense grid of [t_from, t_to], from the stored samples and events; event points are
    included exactly. X, Ẋ are NaN where the motion is drawn on the stop (sticking, the tail of a
    chattering sequence) and the file does not give them: 1-DOF states there are exact."""
    model = f["model"]
    c = model.attrs["contact_shape"]
    x0 = float(model.attrs["stop"])
    T = float(f.attrs["forcing_period"])
    per_period = max(50, min(per_period, int(2e5 * T / (t_to - t_from))))
    t = f["samples/t"][:]
    lo = max(0, np.searchsorted(t, t_from) - 1)
    hi = min(len(t), np.searchsorted(t, t_to) + 1)
    ts = t[lo:hi]
    Xs, Vs, ms = f["samples/X"][lo:hi], f["samples/V"][lo:hi], f["samples/mode"][lo:hi]
    ev_t = f["events/t"][:]
    kinds = f["events/kind"][:]
    ev_v = f["events/v_after"][:]
    ev_vb = f["events/v_before"][:]
    kind_of = h5py.check_enum_dtype(f["events/kind"].dtype)
    one_dof = len(c) == 1
    out_t, out_x, out_v, out_r, out_X, out_V = [], [], [], [], [], []

    def emit(tt, X, V):
        out_t.append(tt)
        out_x.append(X @ c)
        out_v.append(V @ c)
        out_r.append(reaction(model, X, V, tt))
        out_X.append(np.atleast_2d(X))
        out_V.append(np.atleast_2d(V))

    def emit_stop(tt, v=None):
        tt = np.atleast_1d(tt)
        out_t.append(tt)
        out_x.append(np.full(len(tt), x0))
        out_v.append(np.zeros(len(tt)) if v is None else np.atleast_1d(v))
        out_r.append(np.full(len(tt), np.nan))
        if one_dof:  # x_B = c_1 X_1: the modal state on the stop is known
            out_X.append(np.full((len(tt), 1), x0 / c[0]))
            out_V.append((out_v[-1] / c[0])[:, None])
        else:
            out_X.append(np.full((len(tt), len(c)), np.nan))
            out_V.append(np.full((len(tt), len(c)), np.nan))
    for k in range(len(ts) - 1):
        a, b = ts[k], ts[k + 1]
        if b <= a:
            continue
        n = max(2, int(np.ceil(per_period * (b - a) / T)))
        grid = np.linspace(a, b, n, endpoint=False)
        # Events in [a, b): one at the sample time itself comes before the flight that follows.
        i0, i1 = np.searchsorted(ev_t, a, side="left"), np.searchsorted(ev_t, b, side="left")
        evs = ev_t[i0:i1]
        first = evs[0] if len(evs) else b
        last = evs[-1] if len(evs) else a
        head = grid[grid < first]
        if ms[k] == 0 and len(head):
            emit(head, *free_flight(model, Xs[k], Vs[k], a, head))
        elif len(head):
            emit_stop(head)
        for j in range(len(evs)):
            te, kd = evs[j], kinds[i0 + j]
            nxt = evs[j + 1] if j + 1 < len(evs) else None
            emit_stop([te], [ev_vb[i0 + j]] if kd == kind_of["impact"] else None)
            if kd == kind_of["impact"]:
                emit_stop([te], [ev_v[i0 + j]])
            if nxt is None:
                break
            mid = grid[(grid > te) & (grid < nxt)]
            if one_dof and kd in (kind_of["impact"], kind_of["release"], kind_of["grazing"]):
                mid = np.linspace(te, nxt, max(3, int(per_period * (nxt - te) / T)))[1:-1]
                emit(mid, *free_flight(model, np.array([x0]), np.array([ev_v[i0 + j]]), te, mid))
            elif len(mid):
                emit_stop(mid)
        tail = grid[grid > last] if len(evs) else np.array([])
        if len(tail):
            if ms[k + 1] == 0:
                emit(tail, *free_flight(model, Xs[k + 1], Vs[k + 1], b, tail))
            else:
                emit_stop(tail)
    if len(ts):
        emit(np.array([ts[-1]]), Xs[-1:], Vs[-1:])
    if not out_t:
        return (np.array([]),) * 4 + (np.zeros((0, len(c))),) * 2
    tt, xx, vv, rr = (np.concatenate(v) for v in (out_t, out_x, out_v, out_r))
    XX, VV = np.concatenate(out_X), np.concatenate(out_V)
    # The tail of a chattering sequence, from the impact at which its accumulation point was
    # predicted to that point, is drawn on the stop: its bounces are below what the prediction
    # resolves (docs/chattering.md), and the free flight from that impact would dip through it.
    for i in np.nonzero(kinds == kind_of["accumulation"])[0]:
        if i > 0 and kinds[i - 1] == kind_of["impact"]:
            inside = (tt > ev_t[i - 1]) & (tt < ev_t[i])
            xx[inside], vv[inside], rr[inside] = x0, 0.0, np.nan
            XX[inside] = x0 / c[0] if one_dof else np.nan
            VV[inside] = 0.0 if one_dof else np.nan
    sel = (tt >= t_from) & (tt <= t_to)
    return tt[sel], xx[sel], vv[sel], rr[sel], XX[sel], VV[sel]


# ---------------------------------------------------------------------------------------------
# The coordinate drawn by the time plot, the phase portrait and the section (--coordinate).

def coordinate_choices(f):
    """{name: (weights w on the modal X, math label)}: y = w·X. x_B, the modal X1..Xn (the
    paper's X_i, numbered from 1 as `vibro model` does), and the physical q0..q(N-1) (numbered
    from 0 as forcing_dof and contact_dof are) when the file stores the mode shapes: q = Ψ X
    (docs/model.md §1.1)."""
    a = f["model"].attrs
    c = np.asarray(a["contact_shape"], dtype=float)
    out = {"x_B": (c, "x_B")}
    for i in range(len(c)):
        w = np.zeros(len(c))
        w[i] = 1.0
        out[f"X{i + 1}"] = (w, f"X_{{{i + 1}}}")
    if "mode_shapes" in a:
        psi = np.asarray(a["mode_shapes"], dtype=float)
        for j in range(psi.shape[0]):
            out[f"q{j}"] = (psi[j], f"q_{{{j}}}")
    return out


def coordinate_error(f, name):
    """None when the file can draw the coordinate `name`, else why not (one line)."""
    choices = coordinate_choices(f)
    if name in choices:
        return None
    n = len(f["model"].attrs["contact_shape"])
    modal = "X1" if n == 1 else f"X1..X{n}"
    if "mode_shapes" in f["model"].attrs:
        N = f["model"].attrs["mode_shapes"].shape[0]
        return f"expected x_B, {modal} (modal) or {'q0' if N == 1 else f'q0..q{N - 1}'} (physical)"
    hint = (" (the file stores no mode shapes: its scene is in modal form, so there is no physical q)"
            if re.fullmatch(r"q\d+", name) else "")
    return f"expected x_B or {modal} (modal){hint}"


def expm_batch(A):
    """e^A for a stack of small matrices (m, d, d): scaling and squaring with a Taylor series of
    degree 18 once the norm is at most 1/2 (truncation below 1e-22, relative)."""
    norm = np.abs(A).sum(axis=2).max(axis=1).max(initial=0.0)
    squarings = max(0, int(np.ceil(np.log2(norm / 0.5)))) if norm > 0.5 else 0
    B = A / 2.0 ** squarings
    E = np.broadcast_to(np.eye(A.shape[1]), A.shape).copy()
    term = E.copy()
    for k in range(1, 19):
        term = term @ B / k
        E = E + term
    for _ in range(squarings):
        E = E @ E
    return E


def stuck_generator(model):
    """The generator of the sticking motion (docs/model.md §3, §7) on y = (X, Ẋ, sin φ_0, cos φ_0,
    sin φ_1, cos φ_1, ...), φ_h = ω_h t + ψ_h one pair per harmonic: x_B = c·X stays at the stop
    and R is eq. (5) with the damping term, so that y(t + s) = exp(s A) y(t) exactly, forward or
    backward."""
    a = model.attrs
    w, z = np.asarray(a["frequencies"], float), np.asarray(a["damping_ratios"], float)
    TB, c = (np.asarray(a[k], float) for k in ("contact", "contact_shape"))
    sB = float(a["s_B"])
    forcing = harmonics(model)
    n, H = len(w), len(forcing)
    A = np.zeros((2 * n + 2 * H, 2 * n + 2 * H))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -np.diag(w * w) + np.outer(TB, c * w * w) / sB
    A[n:2 * n, n:2 * n] = -np.diag(2 * z * w) + np.outer(TB, c * 2 * z * w) / sB
    for h, (f, W, _, TA, sA) in enumerate(forcing):
        k = 2 * n + 2 * h
        A[n:2 * n, k] = TA * f - TB * sA * f / sB
        A[k, k + 1] = W
        A[k + 1, k] = -W
    return A


def forcing_phases(model, t):
    """(m, 2H): sin φ_h and cos φ_h at the times t, the trailing part of stuck_generator's y."""
    t = np.asarray(t, dtype=float)
    cols = []
    for _, W, ph, _, _ in harmonics(model):
        cols += [np.sin(W * t + ph), np.cos(W * t + ph)]
    return np.stack(cols, axis=1)


def fill_stuck_states(f, tt, XX, VV):
    """The modal state at the grid points that dense_run leaves without one (multi-DOF sticking,
    drawn for x_B on the stop): propagated exactly by the sticking motion (stuck_generator) from
    the stored sample of the same sticking phase, forward from the sample before or backward from
    the sample after when no event lies between. Points between two events inside one sample step
    (a short phase the samples do not see) are interpolated linearly between known states."""
    XX, VV = XX.copy(), VV.copy()
    missing = ~np.isfinite(XX).all(axis=1)
    if not missing.any():
        return XX, VV
    t = f["samples/t"][:]
    Xs, Vs, ms = f["samples/X"][:], f["samples/V"][:], f["samples/mode"][:]
    ev_t = f["events/t"][:]
    n = Xs.shape[1]
    A = stuck_generator(f["model"])
    idx = np.nonzero(missing)[0]
    k = np.clip(np.searchsorted(t, tt[idx], side="right") - 1, 0, len(t) - 1)
    k1 = np.minimum(k + 1, len(t) - 1)
    # Events strictly between the sample and the point decide which sample shares its phase.
    ev_before = np.searchsorted(ev_t, tt[idx], side="left") - np.searchsorted(ev_t, t[k], side="right")
    ev_after = np.searchsorted(ev_t, t[k1], side="left") - np.searchsorted(ev_t, tt[idx], side="right")
    fwd = (ms[k] == 1) & (ev_before == 0)
    bwd = ~fwd & (ms[k1] == 1) & (ev_after == 0)
    for sel, anchor in ((fwd, k), (bwd, k1)):
        if not sel.any():
            continue
        a = anchor[sel]
        y0 = np.concatenate([Xs[a], Vs[a], forcing_phases(f["model"], t[a])], axis=1)
        E = expm_batch(A[None] * (tt[idx[sel]] - t[a])[:, None, None])
        y = np.einsum("mij,mj->mi", E, y0)
        XX[idx[sel]], VV[idx[sel]] = y[:, :n], y[:, n:2 * n]
    rest = idx[~fwd & ~bwd]
    if len(rest):
        known = np.isfinite(XX).all(axis=1)
        for i in range(n):
            XX[rest, i] = np.interp(tt[rest], tt[known], XX[known, i])
            VV[rest, i] = np.interp(tt[rest], tt[known], VV[known, i])
    return XX, VV


def reaction(model, X, V, t):
    """Eq. (5) of the paper with the damping term of docs/model.md §7: the reaction a state on
    the stop needs."""
    w = model.attrs["frequencies"]
    c = model.attrs["contact_shape"]
    z = model.attrs["damping_ratios"]
    X, V = np.atleast_2d(X), np.atleast_2d(V)
    elastic = (X * (c * w * w)).sum(axis=1) + (V * (c * 2 * z * w)).sum(axis=1)
    forcing = sum(sA * f * np.sin(W * np.asarray(t) + ph) for f, W, ph, _, sA in harmonics(model))
    return (elastic - forcing) / model.attrs["s_B"]


# ---------------------------------------------------------------------------------------------

KIND_ORDER = {"sticking-periodic": 0, "impact-periodic": 1, "no-contact-periodic": 2,
              "permanent-contact": 3, "not-periodic": 4}
KIND_NAME = {"sticking-periodic": "sticking", "impact-periodic": "impact",
             "no-contact-periodic": "no contact", "permanent-contact": "permanent contact",
             "not-periodic": "not periodic"}


def attractor_table(g):
    """/attractors as columns. Files since provenance was stored hold one dataset per column
    (strings as str, integers as integers, null floats NaN); older files one attribute per column
    (kind and orbit_status comma-joined, nulls −1)."""
    if "kind" in g:
        return {k: (g[k].asstr()[:] if h5py.check_string_dtype(g[k].dtype) else g[k][:]) for k in g}
    a = dict(g.attrs)
    for k in ("kind", "orbit_status"):
        if k in a:
            a[k] = a[k].split(",") if a[k] else []
    return a


def orbit_group(o):
    """/orbit: multipliers (m, 2), stable, period. Older files: multipliers_re/_im and floats of
    shape (1,)."""
    a = o.attrs
    if "multipliers" in a:
        mu = np.asarray(a["multipliers"]).reshape(-1, 2)
        return mu[:, 0], mu[:, 1], bool(a["stable"]), int(a["period"])
    return a["multipliers_re"], a["multipliers_im"], a["stable"][0] > 0.5, int(a["period"][0])


def plot_basin(f, title, save):
    """Label map of a basin study. Colours are keyed to the attractor (kind, period, impacts,
    sticking fraction), not to the label numbers, which depend on the grid."""
    b = f["basin"]
    labels = b["labels"][:]
    a = attractor_table(f["attractors"])
    kinds = list(a["kind"])
    n = len(kinds)
    ipp = a["impacts_per_period"] if "impacts_per_period" in a else np.zeros(n)
    sp_of = [0.0 if np.isnan(float(a["sticking_fraction"][k])) else float(a["sticking_fraction"][k])
             for k in range(n)]
    key = sorted(range(n), key=lambda k: (KIND_ORDER.get(kinds[k], 9), int(a["period"][k]),
                                          float(ipp[k]), -round(sp_of[k], 6)))
    colour = {k: OKABE_ITO[i % len(OKABE_ITO)] for i, k in enumerate(key)}
    rgb = np.ones(labels.shape + (3,)) * 0.85
    rgb[labels == -2] = (1, 1, 1)
    for k in range(n):
        rgb[labels == k] = matplotlib.colors.to_rgb(colour[k])
    fig, ax = figure(figsize=(8.4, 5.2))
    xr, yr = b.attrs["x_range"], b.attrs["y_range"]
    ax.imshow(rgb, origin="lower", extent=(xr[0], xr[1], yr[0], yr[1]), aspect="auto",
              interpolation="nearest")
    from matplotlib.patches import Patch
    handles = []
    for k in key:
        per = int(a["period"][k])
        sp = float(a["sticking_fraction"][k])
        label = f"{KIND_NAME.get(kinds[k], kinds[k])}, period {per}"
        if kinds[k] == "impact-periodic" and ipp[k] > 0:
            label += f", {int(ipp[k])} impact{'s' if ipp[k] > 1 else ''}"
        if sp > 0:
            label += f", SP {sp:.3f}"
        label += f": {100 * a['basin_fraction'][k]:.1f} %"
        handles.append(Patch(color=colour[k], label=label))
    unresolved = float(b.attrs["unresolved_fraction"])
    if unresolved > 0:
        handles.append(Patch(color=(0.85, 0.85, 0.85), label=f"unresolved: {100 * unresolved:.1f} %"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=fs(8),
              frameon=False, title="attractor: basin share", title_fontsize=fs(8))
    names = {"x_B": "$x_B$", "v_B": "$\\dot x_B$"}
    ax.set_xlabel(f"initial {names.get(text(b.attrs['x']), text(b.attrs['x']))}")
    ax.set_ylabel(f"initial {names.get(text(b.attrs['y']), text(b.attrs['y']))}")
    set_title(ax, title, f"basins of attraction, {labels.shape[1]} × {labels.shape[0]} initial states")
    save(fig, "basin")


BIFURCATION_MARKERS = {"fold": "s", "flip": "D", "neimark-sacker": "*", "rising": "^",
                       "grazing": "v", "sticking-entry": ">", "sticking-lost": "X", "non-smooth": "o",
                       "undetermined": "P", "branch-point": "p", "simultaneous": "h", "no-jacobian": "x"}
# Colours of the kinds drawn on a sweep, in the order they first appear (Okabe–Ito, without the
# blue and vermilion of the up and down sweeps).
BIF_COLOURS = [OKABE_ITO[2], OKABE_ITO[3], OKABE_ITO[4], OKABE_ITO[5], OKABE_ITO[7], OKABE_ITO[6]]


def draw_branch(ax, f, y, color=BRANCH, name=None, markers=True):
    """A continuation branch: solid where stable, dashed where unstable; bifurcations marked.
    `name` labels the curve (one of several drawn on the axes); `markers` False leaves the
    bifurcations to another curve."""
    b = f["branch"]
    value = b["value"][:]
    stable = b["stable"][:].astype(bool)
    start = 0
    for i in range(1, len(value) + 1):
        if i == len(value) or stable[i] != stable[start]:
            j = min(i + 1, len(value))
            ax.plot(value[start:j], y[start:j], "-" if stable[start] else "--", color=color, lw=1.4)
            start = i
    if name is not None:
        ax.plot([], [], "-", color=color, label=name)
    if markers and stable.any():
        ax.plot([], [], "-", color="0.3" if name else color, label="stable")
    if markers and (~stable).any():
        ax.plot([], [], "--", color="0.3" if name else color, label="unstable")
    if not markers:
        return
    bif = f["bifurcations"]
    kinds = [text(k) for k in bif["kind"][:]]
    seen = set()
    for v, k in zip(bif["value"][:], kinds):
        yv = y[np.argmin(np.abs(value - v))] if len(value) else np.nan
        if np.all(np.diff(value) > 0) and np.all(np.isfinite(y)):
            yv = np.interp(v, value, y)
        ax.plot([v], [yv], BIFURCATION_MARKERS.get(k, "o"), color=OKABE_ITO[1], ms=8, mec="k", mew=0.5,
                label=f"{k} ({v:.7g})" if k not in seen else None)
        seen.add(k)


def mark_sequences(fig, ax, f):
    """Several contacts: the contact sequence of each stretch of the branch, lettered on the axes
    (A, B, ...) and spelled out under the figure; dotted lines where it changes."""
    b = f["branch"]
    if "sequence" not in b:
        return
    # Grouped as a person reads them: the impacts vibro followed before predicting an accumulation
    # point are one chattering sequence ("0:chattering"; how many are followed is numerics), and a
    # point exactly at a simultaneous impact ("0+1:impact", a boundary) joins the stretch before.
    seq = [re.sub(r"\b(\d+):impact(\*\d+)? \1:accumulation", r"\1:chattering", text(x)) for x in b["sequence"][:]]
    value = b["value"][:]
    if not any(seq) or len(seq) != len(value):
        return
    runs = []  # (first, last, sequence)
    for i, s in enumerate(seq):
        if runs and (runs[-1][2] == s or "+" in s):
            runs[-1][1] = i
        else:
            runs.append([i, i, s])
    names = {}
    for first, last, s in runs:
        names.setdefault(s, chr(ord("A") + len(names)) if len(names) < 26 else "?")
    for k, (first, last, s) in enumerate(runs):
        if k > 0:
            ax.axvline(0.5 * (value[runs[k - 1][1]] + value[first]), color="0.45", lw=0.8, ls=":")
        ax.annotate(names[s], (0.5 * (value[first] + value[last]), 1.0), xycoords=("data", "axes fraction"),
                    xytext=(0, -11), textcoords="offset points", ha="center", fontsize=fs(8), color="0.25")
    if len(runs) > 1:  # no key for a change the branch does not have (one sequence: no line drawn)
        ax.plot([], [], ":", color="0.45", lw=0.8, label="contact sequence changes")
    shown = 6  # the key lists this many sequences, long ones cut (all are in /branch/sequence)
    lines = [f"{n}: {s if len(s) <= 110 else s[:107] + '...'}" for s, n in list(names.items())[:shown]]
    if len(names) > shown:
        lines.append(f"... {len(names) - shown} more (in /branch/sequence)")
    fig.text(0.01, 0.005, "contact sequences\n" + "\n".join(lines), fontsize=fs(7),
             family="monospace", va="bottom", ha="left", color="0.2")
    if OPTIONS["size"] is None:
        fig.subplots_adjust(bottom=0.12 + 0.022 * (len(lines) + 1))


def draw_strobe(ax, f):
    """The stroboscopic state along a branch (/branch/strobe, docs/output.md): each contact's
    coordinate at t ≡ t0 (mod the orbit's period), t0 the scene's initial.time, the phase of a
    sweep's x_B(t0 + kT), whatever the section. Contacts on the same coordinate (equal columns)
    share one curve."""
    b = f["branch"]
    strobe = np.atleast_2d(b["strobe"][()])
    if strobe.shape[0] != len(b["value"]):
        strobe = strobe.T
    curves = []  # [column, contacts]
    for j in range(strobe.shape[1]):
        for c in curves:
            if np.allclose(strobe[:, j], strobe[:, c[0]], rtol=0, atol=1e-12, equal_nan=True):
                c[1].append(j)
                break
        else:
            curves.append([j, [j]])
    period = int(b.attrs["period"])
    at = "t_0 + kT" if period == 1 else f"t_0 + {period}kT"
    if len(curves) == 1:
        draw_branch(ax, f, strobe[:, 0])
        ax.set_ylabel(f"$x_B({at})$" if strobe.shape[1] == 1
                      else f"contacts {', '.join(map(str, curves[0][1]))} at ${at}$")
        return
    for k, (j, contacts) in enumerate(curves):
        draw_branch(ax, f, strobe[:, j], color=OKABE_ITO[(k + 4) % len(OKABE_ITO)],
                    name="contact " + ", ".join(map(str, contacts)), markers=k == len(curves) - 1)
    ax.set_ylabel(f"contact coordinate at ${at}$")


def plot_branch(f, title, save):
    """Bifurcation diagram of a continuation: the sticking fraction (sticking orbits) or the
    stroboscopic state (impact orbits: every contact's coordinate at the start's forcing phase,
    /branch/strobe; x_B at the section in older files), and the largest |μ| when the orbits have
    multipliers."""
    b = f["branch"]
    param = text(b.attrs["param"])
    value = b["value"][:]
    sp = b["sticking_fraction"][:]
    mu = b["max_multiplier"][:]
    has_sp = np.nanmax(sp, initial=0) > 0
    has_mu = np.isfinite(mu).any() and np.nanmax(np.where(np.isfinite(mu), mu, 0), initial=0) > 0
    rows = 2 if has_mu else 1
    fig, axes = figure(rows, 1, figsize=(7.5, 6.2 if rows == 2 else 4.2), sharex=True, squeeze=False)
    ax1 = axes[0, 0]
    if has_sp:
        draw_branch(ax1, f, sp)
        ax1.set_ylabel("sticking fraction")
    elif "strobe" in b:
        draw_strobe(ax1, f)
    else:  # a file written before /branch/strobe: x_B at the section (it jumps where the section moves)
        draw_branch(ax1, f, b["x_B"][:])
        ax1.set_ylabel("$x_B$ at the section")
    mark_sequences(fig, ax1, f)
    ax1.legend(fontsize=fs(8), loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    sym = SYMBOLS.get(param, param)
    set_title(ax1, title, f"continuation in ${sym}$ from {value[0]:g}, period {int(b.attrs['period'])}; "
                  f"end: {text(b.attrs['end'])}")
    if has_mu:
        ax2 = axes[1, 0]
        draw_branch(ax2, f, mu)
        ax2.axhline(1.0, color="0.6", lw=0.8)
        if np.nanmax(mu) > 10:
            ax2.set_yscale("log")
        ax2.set_ylabel("largest $|\\mu|$")
    axes[-1, 0].set_xlabel(axis_label(param))
    save(fig, "branch")


def read_curves(path):
    """The /curves of a `vibro curve --out` file: (param1, param2, [curve dicts])."""
    try:
        with h5py.File(path, "r") as f:
            g = f["curves"]
            out = []
            for name in sorted(k for k in g if isinstance(g[k], h5py.Group)):
                c = g[name]
                sp = c["special"]
                out.append({"kind": text(c.attrs["kind"]), "contact": int(c.attrs["contact"]),
                            "value1": c["value1"][()], "value2": c["value2"][()],
                            "stable": c["stable"][()].astype(bool),
                            "special": [(text(k), v1, v2) for k, v1, v2 in
                                        zip(sp["kind"][()], sp["value1"][()], sp["value2"][()])]})
            return text(g.attrs["param1"]), text(g.attrs["param2"]), out
    except (OSError, KeyError) as e:
        refuse(f"--overlay {path}: not a file of two-parameter curves (`vibro curve --out`, /curves): {e}")


CURVE_COLOURS = {"sticking-lost": OKABE_ITO[1], "sticking-entry": OKABE_ITO[0], "fold": OKABE_ITO[7],
                 "flip": OKABE_ITO[3], "neimark-sacker": OKABE_ITO[2], "branch-point": OKABE_ITO[5],
                 "grazing": OKABE_ITO[4], "rising": OKABE_ITO[6], "simultaneous": "#777777"}


def draw_curves(ax, curves, swap=False):
    """Traced curves as lines (one colour per kind), their codimension-two points as black stars."""
    seen = set()
    for c in curves:
        x, y = (c["value2"], c["value1"]) if swap else (c["value1"], c["value2"])
        name = c["kind"] + (f" (contact {c['contact']})" if c["contact"] >= 0 else "")
        ax.plot(x, y, "-", color=CURVE_COLOURS.get(c["kind"], "k"), lw=2.0,
                label=f"{name}, traced" if name not in seen else None, zorder=4)
        seen.add(name)
        for k, v1, v2 in c["special"]:
            ax.plot(v2 if swap else v1, v1 if swap else v2, "*", color="k", ms=11, zorder=5,
                    label=k if k not in seen else None)
            seen.add(k)


def plot_curves(f, title, save):
    """The two-parameter curves of `vibro curve`: each curve in the plane of its two keys."""
    p1, p2 = text(f["curves"].attrs["param1"]), text(f["curves"].attrs["param2"])
    _, _, curves = read_curves(f.filename)
    fig, ax = figure(figsize=(8.4, 5.4))
    draw_curves(ax, curves)
    ax.legend(fontsize=fs(8), loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax.set_xlabel(axis_label(p1))
    ax.set_ylabel(axis_label(p2))
    kinds = ", ".join(sorted({c["kind"] for c in curves}))
    set_title(ax, title, f"{kinds}: curves traced in the (${SYMBOLS.get(p1, p1)}$, ${SYMBOLS.get(p2, p2)}$) plane")
    save(fig, "curves")


def plot_partition(f, title, save, overlay=None):
    """Curves of constant sticking fraction and existence boundaries in a parameter plane; with
    `overlay` (a `vibro curve --out` file of the same two keys), the traced curves over it."""
    p = f["partition"]
    p1, p2 = text(p.attrs["param1"]), text(p.attrs["param2"])
    xv1, xl, xv2 = p["crossing_value1"][:], p["crossing_level"][:], p["crossing_value2"][:]
    bv1, bv2 = p["boundary_value1"][:], p["boundary_value2"][:]
    bk = np.array([text(k) for k in p["boundary_kind"][:]])
    fig, ax = figure(figsize=(8.4, 5.4))
    cmap = plt.get_cmap("viridis")
    levels = list(p.attrs["levels"])
    span2 = max(1e-300, np.ptp(np.concatenate([xv2, bv2])) if len(xv2) + len(bv2) else 1.0)

    def segments(v1, v2):
        """Points of one level joined column to column by rank, only where both columns have the
        same number of crossings and the curve does not jump (otherwise it is broken there)."""
        cols = sorted(set(v1))
        per_col = [sorted(v2[v1 == c]) for c in cols]
        segs = []
        for k in range(len(cols)):
            ys = per_col[k]
            if not ys:
                continue
            segs.append(([cols[k]] * len(ys), ys, "."))
            if k + 1 < len(cols) and len(per_col[k + 1]) == len(ys):
                for y0, y1 in zip(ys, per_col[k + 1]):
                    if abs(y1 - y0) < 0.1 * span2:
                        segs.append(([cols[k], cols[k + 1]], [y0, y1], "-"))
        return segs
    for i, s in enumerate(levels):
        sel = xl == s
        colour = cmap(0.9 * i / max(1, len(levels) - 1))
        for n, (xs, ys, style) in enumerate(segments(xv1[sel], xv2[sel])):
            ax.plot(xs, ys, style, color=colour, lw=1.4, ms=3, label=f"SP = {s:g}" if n == 0 else None)
    for j, k in enumerate(sorted(set(bk))):
        sel = bk == k
        ax.plot(bv1[sel], bv2[sel], BIFURCATION_MARKERS.get(k, "o"), color=OKABE_ITO[(1 + j) % 8],
                mec="k", mew=0.3, ms=5, ls="none", label=k + (" (columns)" if overlay else ""),
                alpha=0.6 if overlay else 1.0)
    if overlay:
        c1, c2, curves = read_curves(overlay)
        if {c1, c2} != {p1, p2}:
            refuse(f"--overlay {overlay}: its curves are in ({c1}, {c2}), the partition in ({p1}, {p2})")
        draw_curves(ax, curves, swap=(c1 != p1))
    handles, names = ax.get_legend_handles_labels()
    unique = dict(zip(names, handles))
    ax.legend(unique.values(), unique.keys(), fontsize=fs(8), loc="upper left", bbox_to_anchor=(1.01, 1.0),
              frameon=False)
    ax.set_xlabel(axis_label(p1))
    ax.set_ylabel(axis_label(p2))
    set_title(ax, title, f"curves of constant sticking fraction SP in the "
                 f"(${SYMBOLS.get(p1, p1)}$, ${SYMBOLS.get(p2, p2)}$) plane")
    save(fig, "partition")


def load_columns(g):
    """The per-contact loads of a /branch/loads or /partition/points group (docs/loads.md):
    mean force and work rate, arrays of shape (rows, m); None when the file has none."""
    if "mean_force" not in g or "work_rate" not in g or g["mean_force"].ndim != 2 or g["mean_force"].shape[1] == 0:
        return None
    return g["mean_force"][:], g["work_rate"][:]


def log_scale_if_wide(ax, y):
    """A logarithmic axis when the positive values span more than three decades."""
    pos = y[np.isfinite(y) & (y > 0)]
    if len(pos) > 1 and pos.max() > 1e3 * pos.min():
        ax.set_yscale("log")


def plot_branch_loads(f, title, save):
    """Mean contact force and normal work rate (rigid limit) along a branch, per contact, against
    the parameter (docs/loads.md): solid where the orbit is stable, dashed where unstable."""
    b = f["branch"]
    cols = load_columns(b["loads"]) if "loads" in b else None
    if cols is None or len(b["value"]) == 0:
        return
    force, work = cols
    param = text(b.attrs["param"])
    value = b["value"][:]
    stable = b["stable"][:].astype(bool)
    m = force.shape[1]
    fig, axes = figure(2, 1, figsize=(7.5, 6.2), sharex=True, squeeze=False)
    for ax, y, label in ((axes[0, 0], force, "mean contact force"), (axes[1, 0], work, "normal work rate")):
        for j in range(m):
            colour = BRANCH if m == 1 else OKABE_ITO[j % 7]
            start = 0
            for i in range(1, len(value) + 1):
                if i == len(value) or stable[i] != stable[start]:
                    k = min(i + 1, len(value))
                    ax.plot(value[start:k], y[start:k, j], "-" if stable[start] else "--", color=colour, lw=1.4,
                            label=(f"contact {j}" if m > 1 else None) if start == 0 else None)
                    start = i
        if (~stable).any():
            ax.plot([], [], "--", color="0.4", label="unstable")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=fs(8), loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
        ax.set_ylabel(label)
    log_scale_if_wide(axes[1, 0], work)
    if np.isnan(work).all():  # compliant stops only: no impacts, no rigid-limit work (docs/loads.md)
        axes[1, 0].text(0.5, 0.5, "does not apply: a compliant stop has no impacts\n(its peak forces and "
                        "durations: PREFIX_branch_peaks)", transform=axes[1, 0].transAxes, ha="center",
                        va="center", fontsize=fs(9), color="0.3")
        axes[1, 0].set_yticks([])
    unknown = int(np.isnan(force).sum())
    set_title(axes[0, 0], title, f"contact loads along the branch in ${SYMBOLS.get(param, param)}$, exact per period"
              + (f" ({unknown} unknown values: see /branch/loads/note)" if unknown else ""))
    axes[-1, 0].set_xlabel(axis_label(param))
    save(fig, "branch_loads")


def plot_branch_peaks(f, title, save):
    """A compliant stop's contact phases along a branch (docs/compliant.md, "Along a continued
    branch"): per contact the largest certified peak force and the longest contact duration of the
    orbit's phases, and the largest distance between the orbit and the rigid model's, against the
    parameter; solid where the orbit is stable, dashed where unstable."""
    b = f["branch"]
    if "contact_phases" not in b or len(b["value"]) == 0:
        return
    g = b["contact_phases"]
    peak, duration, rigid = g["peak_force"][:], g["duration"][:], g["rigid_distance"][:]
    param = text(b.attrs["param"])
    value = b["value"][:]
    stable = b["stable"][:].astype(bool)
    m = peak.shape[1]
    fig, axes = figure(3, 1, figsize=(7.5, 8.0), sharex=True, squeeze=False)
    rows = ((axes[0, 0], peak, "peak contact force", True), (axes[1, 0], duration, "contact duration", True),
            (axes[2, 0], rigid[:, None], "distance to the rigid model", False))
    for ax, y, label, per_contact in rows:
        for j in range(y.shape[1]):
            colour = BRANCH if (m == 1 or not per_contact) else OKABE_ITO[j % 7]
            start = 0
            for i in range(1, len(value) + 1):
                if i == len(value) or stable[i] != stable[start]:
                    k = min(i + 1, len(value))
                    ax.plot(value[start:k], y[start:k, j], "-" if stable[start] else "--", color=colour, lw=1.4,
                            label=(f"contact {j}" if m > 1 and per_contact else None) if start == 0 else None)
                    start = i
        if (~stable).any():
            ax.plot([], [], "--", color="0.4", label="unstable")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=fs(8), loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
        ax.set_ylabel(label)
    set_title(axes[0, 0], title, f"contact phases along the branch in ${SYMBOLS.get(param, param)}$, exact per orbit")
    axes[-1, 0].set_xlabel(axis_label(param))
    save(fig, "branch_peaks")


def plot_partition_loads(f, title, save):
    """The normal work rate (rigid limit, the wear power of docs/loads.md) over a partition plane,
    per contact: each column's branch points drawn as a strip of cells at its value of the first
    parameter, coloured on a logarithmic scale; blank where no orbit of the kind exists."""
    from matplotlib.colors import LogNorm
    p = f["partition"]
    if "points" not in p:
        return
    g = p["points"]
    cols = load_columns(g)
    if cols is None or len(g["value1"]) == 0:
        return
    _, work = cols
    p1, p2 = text(p.attrs["param1"]), text(p.attrs["param2"])
    column, v2 = g["column"][:], g["value2"][:]
    value1 = p["column_value1"][:]
    m = work.shape[1]
    fig, axes = figure(1, m, figsize=(7.6 * m, 5.4), squeeze=False)
    # Strip edges halfway between neighbouring columns (the columns are evenly spaced).
    order = np.argsort(value1)
    centres = value1[order]
    mids = (centres[1:] + centres[:-1]) / 2
    half = (centres[1] - centres[0]) / 2 if len(centres) > 1 else 0.5
    left = dict(zip(order, np.concatenate([[centres[0] - half], mids])))
    right = dict(zip(order, np.concatenate([mids, [centres[-1] + half]])))
    for j in range(m):
        ax = axes[0, j]
        w = work[:, j]
        pos = w[np.isfinite(w) & (w > 0)]
        if len(pos) == 0:
            ax.text(0.5, 0.5, "no impacts: the work rate is zero everywhere", transform=ax.transAxes, ha="center")
            continue
        hi = pos.max()
        lo = max(pos.min(), hi * 1e-8)  # below: drawn in the colour of the lowest decade (extend="min")
        norm = LogNorm(vmin=lo, vmax=hi)
        cmap = plt.get_cmap("viridis").copy()
        cmap.set_bad("0.85")  # unknown (NaN) or zero work
        mesh = None
        for k in range(len(value1)):
            sel = np.flatnonzero(column == k)
            if len(sel) == 0:
                continue
            sel = sel[np.argsort(v2[sel], kind="stable")]
            y = v2[sel]
            edges = np.concatenate([[y[0]], (y[1:] + y[:-1]) / 2, [y[-1]]])
            X = np.array([[left[k], right[k]]] * len(edges))
            Y = np.stack([edges, edges], axis=1)
            C = np.where(w[sel] > 0, np.maximum(w[sel], lo), np.nan)[:, None]
            mesh = ax.pcolormesh(X, Y, np.ma.masked_invalid(C), cmap=cmap, norm=norm, shading="flat")
        if mesh is not None:
            cb = fig.colorbar(mesh, ax=ax, extend="min" if pos.min() < lo else "neither")
            cb.set_label("normal work rate" + (f", contact {j}" if m > 1 else "") + " (log scale)")
        ax.set_xlabel(axis_label(p1))
        ax.set_ylabel(axis_label(p2))
        set_title(ax, title, f"normal work rate (wear power) of the sticking orbits over the "
                  f"(${SYMBOLS.get(p1, p1)}$, ${SYMBOLS.get(p2, p2)}$) plane" + (f", contact {j}" if m > 1 else ""))
    save(fig, "partition_loads")


def read_branch(path, param):
    """A continuation branch file (`vibro continue --out`): /branch and /bifurcations."""
    try:
        with h5py.File(path, "r") as f:
            b = f["branch"]
            br = {k: b[k][()] for k in ("value", "sticking_fraction", "stable")}
            br["param"] = text(b.attrs["param"])
            bif = f["bifurcations"] if "bifurcations" in f else None
            br["bif_value"] = bif["value"][()] if bif is not None else np.array([])
            kinds = bif["kind"][()] if bif is not None else []
            br["bif_kind"] = [text(k) for k in kinds]
    except (OSError, KeyError) as e:
        print(f"--overlay {path}: not a continuation branch file (needs /branch with value, "
              f"sticking_fraction, stable and the attribute param): {e}", file=sys.stderr)
        sys.exit(2)
    if br["param"] != param:
        print(f"--overlay {path}: the branch varies {br['param']}, the sweep {param}", file=sys.stderr)
        sys.exit(2)
    return br


def plot_sweep(f, title, save, overlay):
    """Brute-force bifurcation diagram: x_B at the section and (when anything sticks) the
    sticking fraction against the parameter, upward and downward runs marked; optionally a
    continuation branch overlaid."""
    s = f["sweep"]
    param = text(s.attrs["param"])
    value, up = s["value"][()], s["upward"][()].astype(bool)
    xB, sp = s["x_B"][()], s["sticking_fraction"][()]
    br = read_branch(overlay, param) if overlay else None
    has_sp = np.nanmax(np.where(np.isfinite(sp), sp, 0), initial=0) > 0 or br is not None
    rows = 2 if has_sp else 1
    fig, axes = figure(rows, 1, figsize=(8.6, 6.6 if rows == 2 else 4.2), sharex=True, squeeze=False)
    ax1 = axes[0, 0]
    for sel, marker, color, name in ((up, "o", UP, "upward"), (~up, "x", DOWN, "downward")):
        if not sel.any():
            continue
        v = np.repeat(value[sel], xB.shape[1])
        ax1.plot(v, xB[sel].ravel(), marker, ms=2.5 if marker == "o" else 3.5, color=color,
                 mfc="none" if marker == "o" else color, lw=0, label=f"{name} sweep")
        if has_sp:
            axes[1, 0].plot(value[sel], sp[sel], marker, ms=4, color=color,
                            mfc="none" if marker == "o" else color, lw=0, label=f"{name} sweep")
    if br is not None:
        ax2 = axes[1, 0]
        v, b_sp, stable = br["value"], br["sticking_fraction"], br["stable"].astype(bool)
        for i in range(len(v) - 1):
            ax2.plot(v[i:i + 2], b_sp[i:i + 2], "-" if stable[i] else "--", color=BRANCH, lw=1.2)
        ax2.plot([], [], "-", color=BRANCH, label="continuation, stable")
        if (~stable).any():
            ax2.plot([], [], "--", color=BRANCH, label="continuation, unstable")
        # One marker shape and colour, and one legend entry, per kind of bifurcation.
        kinds = list(dict.fromkeys(br["bif_kind"]))
        for j, kind in enumerate(kinds):
            at = np.array([bv for bv, bk in zip(br["bif_value"], br["bif_kind"]) if bk == kind])
            colour = BIF_COLOURS[j % len(BIF_COLOURS)]
            for bv in at:
                for ax in axes[:, 0]:
                    ax.axvline(bv, color=colour, lw=0.8, ls=":")
            y = [b_sp[np.argmin(np.abs(v - bv))] if len(v) else 0.0 for bv in at]  # nearest point (folds)
            shown = ", ".join(f"{bv:.7g}" for bv in at[:3]) + (f", … ({len(at)} points)" if len(at) > 3 else "")
            ax2.plot(at, y, BIFURCATION_MARKERS.get(kind, "o"), color=colour, ms=7, mec="k", mew=0.5,
                     ls="none", label=f"{kind} ({shown})")
    sym = SYMBOLS.get(param, param)
    ax1.set_ylabel("$x_B(t_0 + kT)$")
    set_title(ax1, title, f"brute-force sweep in ${sym}$, up and down")
    ax1.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=fs(8), frameon=False)
    if has_sp:
        axes[1, 0].set_ylabel("sticking fraction")
        axes[1, 0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=fs(8), frameon=False)
    axes[-1, 0].set_xlabel(axis_label(param))
    save(fig, "sweep")


def plot_diagram(f, title, save):
    """A diagram (`vibro diagram --out`): the sweep's stroboscopic points x_B(t0 + kT) and, over
    them, every branch's stroboscopic state (/diagram/branches/NNN/branch/strobe, contact 0: the
    same observable at the same forcing phase), stable solid, unstable dashed, one colour per
    branch; its branch points and flips (where branches were switched) and the ends of branches
    that stop at a grazing or another non-smooth point marked."""
    d, s = f["diagram"], f["sweep"]
    param = text(d.attrs["param"])
    fig, ax = figure(1, 1, figsize=(9.2, 5.4))
    value, xB = s["value"][()], s["x_B"][()]
    v = np.repeat(value, xB.shape[1])
    ax.plot(v, xB.ravel(), ".", ms=2.5, color="0.6", lw=0, label="sweep (up and down), $x_B(t_0+kT)$", zorder=1)
    colours = [OKABE_ITO[i % len(OKABE_ITO)] for i in (0, 1, 2, 4, 5, 6, 3, 7)]
    names = sorted(d["branches"].keys())
    marked = set()
    for k, name in enumerate(names):
        g = d["branches"][name]
        b = g["branch"]
        val, strobe, stable = b["value"][()], b["strobe"][()][:, 0], b["stable"][()].astype(bool)
        c = colours[k % len(colours)]
        if int(b.attrs["period"]) == 1:
            for i in range(len(val) - 1):
                ax.plot(val[i:i + 2], strobe[i:i + 2], "-" if stable[i] and stable[i + 1] else "--", color=c,
                        lw=1.3, zorder=2)
        else:
            # A q-periodic orbit has q stroboscopic points and the branch stores one of them, which
            # one following the section along the branch: points, not a line (filled: stable).
            ax.plot(val[stable], strobe[stable], "o", ms=3, color=c, zorder=2)
            ax.plot(val[~stable], strobe[~stable], "o", ms=3, mfc="none", color=c, zorder=2)
        ax.plot([], [], "-", color=c, label=f"branch {int(name)} (period {int(b.attrs['period'])}, "
                f"{text(g.attrs['origin'])})")
        bif = g["bifurcations"]
        for bv, bk in zip(bif["value"][()], [text(x) for x in bif["kind"][()]]):
            if bk in ("branch-point", "flip") and len(val):
                i = int(np.argmin(np.abs(val - bv)))
                ax.plot([bv], [strobe[i]], BIFURCATION_MARKERS.get(bk, "o"), color="k", mfc="w", ms=7, zorder=3,
                        label=None if bk in marked else bk)
                marked.add(bk)
        for end, at in ((text(g.attrs["end_first"]), 0), (text(g.attrs["end_last"]), -1)):
            if len(val) and any(w in end for w in ("grazing", "non-smooth", "sticking", "no orbit")):
                ax.plot([val[at]], [strobe[at]], "x", color="k", ms=8, mew=1.5, zorder=3,
                        label=None if "end" in marked else "end: grazing or non-smooth")
                marked.add("end")
    ax.plot([], [], "--", color="0.3", label="unstable (dashed; open circles for period > 1)")
    sym = SYMBOLS.get(param, param)
    ax.set_xlabel(axis_label(param))
    ax.set_ylabel("$x_B$ at $t \\equiv t_0$ (mod $T$)")
    set_title(ax, title, f"diagram in ${sym}$: {len(names)} branches over the sweep")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=fs(7.5), frameon=False)
    save(fig, "diagram")


def time_window(t, T, window):
    """The time plots' window: --time-window A,B within the samples t, or the last 5 periods."""
    t_from, t_to = window if window else (t[-1] - 5 * T, t[-1])
    t_from, t_to = max(t_from, t[0]), min(t_to, t[-1])
    if t_to <= t_from:
        print(f"vibro plot: --time-window holds no sample (the run covers {t[0]:g} ≤ t ≤ {t[-1]:g})",
              file=sys.stderr)
        sys.exit(2)
    return t_from, t_to


# ---------------------------------------------------------------------------------------------
# Compliant stops (docs/compliant.md): the contact phase is linear too, so it is drawn exactly.

def compliant_contacts(f):
    """Per contact of a scene whose stops include a compliant one: (F_j, a_j, σ_j, d_j, k_j, c_j)
    with the gap g_j = σ_j (a_jᵀX − d_j) on the modal state and the contact force λ_j entering the
    modal equations as F_j λ_j (k_j = c_j = 0 for a rigid contact). None when no stop is compliant
    or the scene's form does not give F_j (several contacts in the modal form)."""
    a = f["model"].attrs
    contacts = scene_contacts(f)
    if not contacts:
        stop = scene_table(f, "stop")
        if not compliant_law(stop):
            return None
        c = np.asarray(a["contact_shape"], dtype=float)
        return [(np.asarray(a["contact"], dtype=float), c, 1.0, float(a["stop"]),
                 float(stop["stiffness"]), float(stop.get("damping", 0.0)))]
    if not any(compliant_law(c) for c in contacts) or "mode_shapes" not in a:
        return None
    n = len(a["frequencies"])
    phi = np.asarray(a["mode_shapes"], dtype=float).reshape(-1, n)
    mass = np.asarray(scene_table(f, "structure")["mass"], dtype=float)
    if phi.shape[0] != n or mass.shape != (n, n):
        return None  # constrained DOFs: the modal force of a contact is not recoverable here
    out = []
    for c, (a_j, sigma, d, _) in zip(contacts, gap_coordinates(f, contacts)):
        dofs = c.get("dofs", [c.get("dof", 0)])
        w = np.zeros(n)
        w[int(dofs[0])] = 1.0
        if len(dofs) > 1:
            w[int(dofs[1])] = -1.0
        # M q̈ + … = σ w λ and q = Φ X: the modal force is Φ⁻¹ M⁻¹ σ w λ.
        F = sigma * np.linalg.solve(phi, np.linalg.solve(mass, w))
        law = compliant_law(c) is not None
        out.append((F, a_j, sigma, d, float(c["stiffness"]) if law else 0.0,
                    float(c.get("damping", 0.0)) if law else 0.0))
    return out


def phase_generator(model, contact=None):
    """The generator A of a free flight (contact None) or of a compliant contact phase on
    y = (X, Ẋ, sin φ_0, cos φ_0, …, 1), φ_h = ω_h t + ψ_h, so that y(t + s) = exp(s A) y(t):
    Ẍ + DẊ + ΩX = Σ_h T_A^(h) f_h sin φ_h + F λ with λ = −k g − c ġ, g = σ (aᵀX − d)
    (docs/compliant.md, "the contact phase")."""
    a = model.attrs
    w, z = np.asarray(a["frequencies"], float), np.asarray(a["damping_ratios"], float)
    forcing = harmonics(model)
    n, H = len(w), len(forcing)
    d_all = 2 * n + 2 * H + 1
    A = np.zeros((d_all, d_all))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -np.diag(w * w)
    A[n:2 * n, n:2 * n] = -np.diag(2 * z * w)
    for h, (fh, W, _, TA, _) in enumerate(forcing):
        k = 2 * n + 2 * h
        A[n:2 * n, k] = TA * fh
        A[k, k + 1] = W
        A[k + 1, k] = -W
    if contact is not None:
        F, a_j, sigma, d, k_j, c_j = contact
        A[n:2 * n, :n] -= sigma * k_j * np.outer(F, a_j)
        A[n:2 * n, n:2 * n] -= sigma * c_j * np.outer(F, a_j)
        A[n:2 * n, -1] += sigma * k_j * d * F
    return A


def contact_force(contact, X, V):
    """λ = −k g − c ġ of a compliant contact at the modal states X, Ẋ (rows)."""
    _, a_j, sigma, d, k_j, c_j = contact
    return -k_j * sigma * (np.atleast_2d(X) @ a_j - d) - c_j * sigma * (np.atleast_2d(V) @ a_j)


def compliant_states(f, t_from, t_to, contacts, per_period=600):
    """A run with compliant stops: the modal state on a dense grid of [t_from, t_to] and the
    contact in which each point lies (−1 in flight), exact: from each stored sample forward
    through the events of its sample step, the flight's or the contact phase's own linear flow
    (phase_generator), switched at each entry (`stick`) and exit (`release`); the state is
    continuous at both. A rigid impact in the step (a scene mixing rigid and compliant stops)
    ends what is known of the step: a NaN row breaks the curve up to the next sample."""
    model = f["model"]
    T = float(f.attrs["forcing_period"])
    # At least 2 000 points over a short window (one contact phase), at most about 2·10⁵.
    per_period = max(50, min(max(per_period, int(2e3 * T / (t_to - t_from))), int(2e5 * T / (t_to - t_from))))
    t = f["samples/t"][:]
    lo = max(0, np.searchsorted(t, t_from) - 1)
    hi = min(len(t), np.searchsorted(t, t_to) + 1)
    ts = t[lo:hi]
    Xs, Vs, ms = f["samples/X"][lo:hi], f["samples/V"][lo:hi], f["samples/mode"][lo:hi]
    ev_t, kinds = f["events/t"][:], f["events/kind"][:]
    ev_c = f["events/contact"][:] if "contact" in f["events"] else np.zeros(len(ev_t), dtype=int)
    kind_of = h5py.check_enum_dtype(f["events/kind"].dtype)
    n = Xs.shape[1]
    gens = [phase_generator(model)] + [phase_generator(model, c) if c[4] > 0 else None for c in contacts]
    out_t, out_X, out_V, out_j = [], [], [], []

    def emit(tt, y, j):
        out_t.append(np.atleast_1d(tt))
        out_X.append(np.atleast_2d(y)[:, :n])
        out_V.append(np.atleast_2d(y)[:, n:2 * n])
        out_j.append(np.full(len(np.atleast_1d(tt)), j))

    def state(X, V, tt):
        return np.concatenate([X, V, forcing_phases(model, [tt])[0], [1.0]])
    sticks = kinds == kind_of["stick"]
    releases = kinds == kind_of["release"]
    peak_t = f["events/peak_time"][:] if "peak_time" in f["events"] else np.array([])
    peak_t = np.sort(peak_t[np.isfinite(peak_t)])
    for k in range(len(ts) - 1):
        a, b = ts[k], ts[k + 1]
        if b <= a:
            continue
        # The contact of the sample: the last entry at or before it, if the sample is in contact.
        j = -1
        if ms[k] != 0:
            before = np.nonzero(sticks & (ev_t <= a))[0]
            j = int(ev_c[before[-1]]) if len(before) else -1
            if j < 0 or gens[j + 1] is None:
                emit([a, np.nan], np.full((2, 2 * n), np.nan), -1)
                continue
        y = state(Xs[k], Vs[k], a)
        grid = np.linspace(a, b, max(2, int(np.ceil(per_period * (b - a) / T))), endpoint=False)
        # Each phase's peak force at its certified instant, so that the drawn force reaches it.
        grid = np.union1d(grid, peak_t[(peak_t > a) & (peak_t < b)])
        i0, i1 = np.searchsorted(ev_t, a, side="right"), np.searchsorted(ev_t, b, side="left")
        stops = list(range(i0, i1)) + [None]
        start = a
        for i in stops:
            end = b if i is None else ev_t[i]
            pts = grid[(grid >= start) & (grid < end)]
            pts = np.append(pts, end) if i is not None else pts
            if len(pts):
                E = expm_batch(gens[j + 1][None] * (pts - start)[:, None, None])
                ys = np.einsum("mij,j->mi", E, y)
                emit(pts, ys, j)
            if i is None:
                break
            y = ys[-1] if len(pts) else y
            start = end
            if sticks[i] and gens[int(ev_c[i]) + 1] is None:
                emit([np.nan], np.full((1, 2 * n), np.nan), -1)  # rigid sticking: not followed
                break
            if sticks[i]:
                j = int(ev_c[i])
            elif releases[i]:
                j = -1
            elif kinds[i] == kind_of["impact"] or kinds[i] == kind_of["accumulation"]:
                emit([np.nan], np.full((1, 2 * n), np.nan), -1)  # a rigid impact: not followed
                break
    if len(ts):
        before = np.nonzero(sticks & (ev_t <= ts[-1]))[0]
        j = int(ev_c[before[-1]]) if ms[-1] != 0 and len(before) else -1
        emit([ts[-1]], np.concatenate([Xs[-1], Vs[-1]])[None], j)
    if not out_t:
        return np.array([]), np.zeros((0, n)), np.zeros((0, n)), np.array([], dtype=int)
    tt, XX, VV, jj = (np.concatenate(v) for v in (out_t, out_X, out_V, out_j))
    sel = np.isnan(tt) | ((tt >= t_from) & (tt <= t_to))
    return tt[sel], XX[sel], VV[sel], jj[sel]


def contact_forces(contacts, XX, VV, jj):
    """(m, J): every contact's force along compliant_states' points, 0 where it is not in contact."""
    out = np.zeros((len(XX), len(contacts)))
    for j, c in enumerate(contacts):
        inside = jj == j
        if inside.any():
            out[inside, j] = contact_force(c, XX[inside], VV[inside])
    out[~np.isfinite(XX).all(axis=1)] = np.nan
    return out


def plot_contact_forces(f, title, save, window, contacts):
    """A run with compliant stops (docs/loads.md): PREFIX_forces, every compliant contact's force
    λ = −k g − c ġ against t (exact, from compliant_states), with each phase's certified peak
    (the release event's reaction_max at its peak_time) marked; and PREFIX_peaks, the histograms of
    the peak forces and of the contact durations of every phase of the run."""
    T = float(f.attrs["forcing_period"])
    t = f["samples/t"][:]
    t_from, t_to = time_window(t, T, window)
    tt, XX, VV, jj = compliant_states(f, t_from, t_to, contacts)
    lam = contact_forces(contacts, XX, VV, jj)
    ev = f["events"]
    kind_of = h5py.check_enum_dtype(ev["kind"].dtype)
    kinds, ev_t = ev["kind"][:], ev["t"][:]
    ev_c = ev["contact"][:] if "contact" in ev else np.zeros(len(kinds), dtype=int)
    rel = kinds == kind_of["release"]
    peak, peak_t, dur = ev["reaction_max"][:], ev["peak_time"][:], ev["stick_duration"][:]
    ids = [j for j, c in enumerate(contacts) if c[4] > 0]
    names = [f"contact {j}" for j in ids] if len(contacts) > 1 else ["the stop"]
    status = text(f.attrs["status"])
    # Only the contacts in contact somewhere in the window (all of them if none is).
    shown = [j for j in ids if (jj == j).any()] or ids
    fig, axes = figure(len(shown), 1, figsize=(9, 1.4 + 1.8 * len(shown)), sharex=True, squeeze=False)
    if fig.get_layout_engine() is None:
        fig.set_layout_engine("constrained")
    for row, j in enumerate(shown):
        ax = axes[row, 0]
        ax.plot(tt, lam[:, j], lw=1, color=OKABE_ITO[j % 7], label=f"$\\lambda_{{{j}}}$")
        ax.axhline(0, color="k", lw=0.8)
        mine = rel & (ev_c == j) & (peak_t >= t_from) & (peak_t <= t_to) & np.isfinite(peak)
        if mine.any():
            ax.plot(peak_t[mine], peak[mine], "v", ms=3.5, color="k",
                    label=f"certified peaks ({int(mine.sum())})")
        ax.set_ylabel("$\\lambda$")
        ax.set_title(f"{names[ids.index(j)]}: {compliant_law(scene_contacts(f)[j] if scene_contacts(f) else scene_table(f, 'stop'))}",
                     fontsize=fs(9), loc="left")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=fs(8), frameon=False)
    axes[-1, 0].set_xlabel("$t$")
    axes[-1, 0].set_xlim(t_from, t_to)
    absolute_time(axes[-1, 0])
    if OPTIONS["title"] != "":
        head = OPTIONS["title"] if OPTIONS["title"] is not None else \
            f"{title}\ncontact force, {t_from:.6g} ≤ t ≤ {t_to:.6g} ({status})"
        fig.suptitle(head, fontsize=fs(10))
    save(fig, "forces")

    fig, axes = figure(len(ids), 2, figsize=(8.0, 1.0 + 2.4 * len(ids)), squeeze=False)
    if fig.get_layout_engine() is None:
        fig.set_layout_engine("constrained")
    for row, j in enumerate(ids):
        mine = rel & (ev_c == j) & np.isfinite(peak) & np.isfinite(dur)
        for ax, data, label in ((axes[row, 0], peak[mine], "peak force"), (axes[row, 1], dur[mine], "contact duration")):
            if len(data):
                # Counts on a log scale: the few phases of a transient stay visible beside the
                # steady state's many.
                ax.hist(data, bins=min(40, max(5, int(np.sqrt(len(data))))), color=OKABE_ITO[row % 7], log=True)
                ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
                ax.axvline(data.max(), color="k", lw=0.8, ls="--", label=f"largest {data.max():.4g}")
                ax.legend(fontsize=fs(8), frameon=False)
            ax.set_xlabel(f"{label}, {names[row]}")
            ax.set_ylabel("contact phases")
    if OPTIONS["title"] != "":
        head = OPTIONS["title"] if OPTIONS["title"] is not None else \
            f"{title}\nevery contact phase of the run ({int(rel.sum())}, {status})"
        fig.suptitle(head, fontsize=fs(10))
    save(fig, "peaks")


def plot_run(f, title, save, window, coordinate="x_B"):
    """Time plots of a run with dense samples: the coordinate (x_B by default) against t, the
    reaction, the phase portrait and the section of that coordinate."""
    model = f["model"]
    x0 = float(model.attrs["stop"])
    T = float(f.attrs["forcing_period"])
    status = text(f.attrs["status"])
    t = f["samples/t"][:]
    t_from, t_to = time_window(t, T, window)
    compliant = compliant_contacts(f)
    if compliant:  # the contact phases drawn exactly, the penetration included
        tt, XX, VV, _ = compliant_states(f, t_from, t_to, compliant)
        c = np.asarray(model.attrs["contact_shape"], dtype=float)
        xx, vv, rstar = XX @ c, VV @ c, None
    else:
        tt, xx, vv, rstar, XX, VV = dense_run(f, t_from, t_to)
    on_xB = coordinate == "x_B"
    w, sym = coordinate_choices(f)[coordinate]
    if not on_xB:
        if not compliant:
            XX, VV = fill_stuck_states(f, tt, XX, VV)
        xx, vv = XX @ w, VV @ w
    labels = model.attrs["dof_labels"] if "dof_labels" in model.attrs else []
    what = ("contact displacement" if on_xB else
            f"physical displacement {coordinate} ({text(labels[int(coordinate[1:])])})"
            if coordinate.startswith("q") else f"modal coordinate {coordinate}")
    ev_t = f["events/t"][:]
    kinds = f["events/kind"][:]
    kind_of = h5py.check_enum_dtype(f["events/kind"].dtype)
    in_view = (ev_t >= t_from) & (ev_t <= t_to)
    sticks = ev_t[kinds == kind_of["stick"]]
    releases = ev_t[kinds == kind_of["release"]]
    mode_all = f["samples/mode"][:]
    sticks_at_all = len(sticks) > 0 or (mode_all == 1).any()
    span = f"{t_from:.6g} ≤ t ≤ {t_to:.6g}"

    def shade_sticking(ax):
        # Sticking phases: from each stick event (or a start on the stop) to the next release.
        starts = list(sticks)
        if mode_all[0] == 1:
            starts.insert(0, t[0])
        spans = set()
        for s in starts:
            later = releases[releases > s]
            e = later[0] if len(later) else t_to
            if e >= t_from and s <= t_to:
                spans.add((max(s, t_from), min(e, t_to)))
        for n, (a, b) in enumerate(sorted(spans)):
            ax.axvspan(a, b, color=STICK_SHADE, alpha=0.25, lw=0, label=contact_shade_label(f) if n == 0 else None)

    fig, ax = figure(figsize=(9, 3.8))
    ax.plot(tt, xx, lw=1, color=OKABE_ITO[0], label=f"${sym}$")
    if on_xB:
        ax.axhline(x0, color="k", lw=1.2, label="stop $x_0$")
    shade_sticking(ax)
    imp = in_view & (kinds == kind_of["impact"])
    if imp.any():
        # On x_B the impacts are on the stop; on another coordinate, on its curve.
        yi = np.full(imp.sum(), x0) if on_xB else np.interp(ev_t[imp], tt, xx)
        ax.plot(ev_t[imp], yi, "v", ms=3.5, color=OKABE_ITO[1], label=f"impacts ({imp.sum()})")
    ax.set_xlabel("$t$")
    ax.set_ylabel(f"${sym}$")
    ax.set_xlim(t_from, t_to)
    absolute_time(ax)
    set_title(ax, title, f"{what}, {span} ({status})")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=fs(8), frameon=False)
    save(fig, "xB" if on_xB else coordinate)

    if compliant:
        plot_contact_forces(f, title, save, window, compliant)
    elif sticks_at_all:
        ts = t[(t >= t_from) & (t <= t_to)]
        sel = (t >= t_from) & (t <= t_to)
        X, V, mode = f["samples/X"][sel], f["samples/V"][sel], f["samples/mode"][sel]
        R = reaction(model, X, V, ts)
        fig, ax = figure(figsize=(9, 3.8))
        ax.plot(ts, np.where(mode == 1, R, np.nan), lw=1.6, color=OKABE_ITO[0], label="$R$ (on the stop)")
        ax.plot(tt, rstar, lw=0.8, ls="--", color="0.45", label="$R^*$ (reaction a free state would need)")
        ax.axhline(0, color="k", lw=0.8)
        shade_sticking(ax)
        ax.set_xlabel("$t$")
        ax.set_ylabel("$R$")
        ax.set_xlim(t_from, t_to)
        absolute_time(ax)
        set_title(ax, title, f"contact reaction, {span}")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=fs(8), frameon=False)
        save(fig, "reaction")

    fig, ax = figure(figsize=(6.4, 5))
    ax.plot(xx, vv, lw=0.8, color=OKABE_ITO[0])
    if on_xB:
        ax.axvline(x0, color="k", lw=1.2)
    ax.set_xlabel(f"${sym}$")
    ax.set_ylabel(f"$\\dot {sym}$")
    set_title(ax, title, f"phase portrait, {span}")
    save(fig, "phase")

    sX = f["section/X"][:]
    sV = f["section/V"][:]
    sxB = sX @ w
    svB = sV @ w
    fig, ax = figure(figsize=(6.4, 5))
    k = np.arange(len(sxB))
    sc = ax.scatter(sxB, svB, c=k, s=6, cmap="viridis")
    fig.colorbar(sc, ax=ax, label="period $k$")
    ax.set_xlabel(f"${sym}(t_0 + kT)$")
    ax.set_ylabel(f"$\\dot {sym}(t_0 + kT)$")
    set_title(ax, title, f"stroboscopic section, {len(sxB)} periods")
    save(fig, "section")

    if "orbit" in f:
        plot_multipliers(f, title, save)


def plot_multipliers(f, title, save):
    """PREFIX_multipliers: the Floquet multipliers of the stored orbit against the unit circle."""
    re_, im, stable, period = orbit_group(f["orbit"])
    re_, im = np.atleast_1d(re_), np.atleast_1d(im)
    if len(re_) == 0:
        return  # a superstable 1-DOF sticking orbit has no multipliers to draw
    fig, ax = figure(figsize=(5.6, 5))
    th = np.linspace(0, 2 * np.pi, 400)
    ax.plot(np.cos(th), np.sin(th), color="k", lw=0.8, label="unit circle")
    ax.plot(re_, im, "o", color=OKABE_ITO[2] if stable else OKABE_ITO[1],
            label=f"multipliers $\\mu$ ({'stable' if stable else 'unstable'})")
    lim = max(1.2, 1.1 * max([1.0] + list(np.hypot(re_, im))))
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.axhline(0, color="0.7", lw=0.5)
    ax.axvline(0, color="0.7", lw=0.5)
    ax.set_xlabel("Re $\\mu$")
    ax.set_ylabel("Im $\\mu$")
    set_title(ax, title, f"period-{period} orbit: Floquet multipliers")
    ax.legend(loc="upper left", fontsize=fs(8), framealpha=0.9)
    save(fig, "multipliers")


def parse_size(value):
    """--size W,H: inches, or centimetres when both carry "cm" (8.5cm,6cm). Exit 2 otherwise."""
    m = re.fullmatch(r"\s*([0-9.eE+-]+)\s*(cm)?\s*,\s*([0-9.eE+-]+)\s*(cm)?\s*", value)
    try:
        ok = m is not None and (m.group(2) == m.group(4))
        w, h = (float(m.group(1)), float(m.group(3))) if ok else (0.0, 0.0)
    except ValueError:
        ok = False
    if ok and m.group(2):
        w, h = w / 2.54, h / 2.54
    if not ok or not (0.5 <= w <= 100 and 0.5 <= h <= 100):
        print(f"vibro plot: --size {value}: expected W,H in inches (3.5,2.6) or in centimetres "
              "(8.5cm,6.5cm), each 0.5 to 100 inches", file=sys.stderr)
        sys.exit(2)
    return (w, h)


MAX_TITLE = 500  # characters: a longer title does not fit any picture


def check_title(title, font_size):
    """--title: typeset once before anything is drawn (matplotlib's mathtext between $ signs), so
    that a title it cannot typeset, or one too long for a picture, is refused naming the title
    (exit 2, nothing written) instead of failing in the middle of the pictures."""
    if not title:
        return
    # The title as it was typed, between quotes: repr() would double every backslash of its mathtext
    # ('$\\frac{$' for $\frac{$); only characters that cannot be printed are escaped.
    cut = title if len(title) <= 60 else title[:57] + "..."
    shown = "'" + "".join(c if c.isprintable() else repr(c)[1:-1] for c in cut) + "'"
    if len(title) > MAX_TITLE:
        refuse(f"--title {shown}: {len(title)} characters, at most {MAX_TITLE} (a title longer than any "
               "picture is wide)")
    fig = plt.figure(figsize=(6.0, 4.0))
    try:
        fig.suptitle(title, fontsize=font_size)
        fig.canvas.draw()
    except Exception as e:  # noqa: BLE001 (mathtext raises ValueError, fonts RuntimeError, ...)
        first = str(e).strip().splitlines()[0] if str(e).strip() else ""
        refuse(f"--title {shown}: matplotlib cannot typeset it ({type(e).__name__}: {first})")
    finally:
        plt.close(fig)


def read_everything(path):
    """Reads every attribute and dataset of the file (raises what h5py raises on damage)."""
    def visit(_name, obj):
        for k in obj.attrs:
            obj.attrs[k]
        if isinstance(obj, h5py.Dataset):
            obj[()]
    with h5py.File(path, "r") as f:
        for k in f.attrs:
            f.attrs[k]
        f.visititems(visit)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file")
    ap.add_argument("--out", default=None, help="prefix of the files")
    ap.add_argument("--overlay", default=None,
                    help="continuation branch (HDF5) drawn over a sweep, or curves (vibro curve --out) over a partition")
    ap.add_argument("--format", default="png", choices=["png", "pdf", "svg"])
    ap.add_argument("--dpi", type=int, default=150)
    ap.add_argument("--time-window", default=None, help="A,B: time plots show A ≤ t ≤ B")
    ap.add_argument("--title", default=None, help="title of every picture ('' for none)")
    ap.add_argument("--size", default=None, help="W,H in inches, or W,H with cm (8.5cm,6cm)")
    ap.add_argument("--font-size", type=float, default=10.0, help="font size in points")
    ap.add_argument("--coordinate", default="x_B", help="x_B, X1..Xn (modal) or q0..q(N-1) (physical)")
    args = ap.parse_args()
    if not 10 <= args.dpi <= 2400:
        refuse(f"--dpi {args.dpi}: expected 10 to 2400 dots per inch")
    if args.size is not None:
        OPTIONS["size"] = parse_size(args.size)
    if not (np.isfinite(args.font_size) and 1 <= args.font_size <= 72):
        print(f"vibro plot: --font-size {args.font_size:g}: expected a size in points, 1 to 72", file=sys.stderr)
        sys.exit(2)
    OPTIONS["title"], OPTIONS["font_size"] = args.title, args.font_size
    check_title(args.title, args.font_size)
    # Editable text: SVG keeps <text> elements and PDF embeds TrueType fonts, not glyph outlines.
    matplotlib.rcParams.update({"svg.fonttype": "none", "pdf.fonttype": 42, "ps.fonttype": 42,
                                "font.size": args.font_size, "axes.formatter.useoffset": False})
    window = None
    if args.time_window:
        try:
            window = tuple(float(v) for v in args.time_window.split(","))
            ok = len(window) == 2 and window[0] < window[1]
        except ValueError:
            ok = False
        if not ok:
            print(f"vibro plot: --time-window {args.time_window}: expected A,B with A < B", file=sys.stderr)
            sys.exit(2)
    prefix = args.out or os.path.splitext(args.file)[0]
    written = []

    def save(fig, suffix):
        path = f"{prefix}_{suffix}.{args.format}"
        # No creation dates in PDF and SVG files: the same data give the same file.
        meta = {"pdf": {"CreationDate": None}, "svg": {"Date": None}}.get(args.format, {})
        # At --size the file is exactly that size; otherwise trimmed to what is drawn.
        tight = {} if OPTIONS["size"] is not None else {"bbox_inches": "tight"}
        fig.savefig(path, dpi=args.dpi, metadata=meta, **tight)
        written.append(path)
        plt.close(fig)
    # A corrupt file (a damaged compressed chunk that the HDF5 library reports cleanly) is bad
    # input: every dataset and attribute is read before any picture is written (exit 2, nothing
    # created); a picture that fails on damaged values removes what was written.
    try:
        read_everything(args.file)
    except Exception as e:  # noqa: BLE001 (h5py raises OSError, KeyError, ValueError, TypeError)
        print(f"vibro plot: {args.file}: a corrupt file ({type(e).__name__}: {e}); nothing was written",
              file=sys.stderr)
        sys.exit(2)
    def remove_written():
        for w in written:
            if os.path.exists(w):
                os.remove(w)
    try:
        draw(args, save, window)
    except SystemExit:
        remove_written()  # a refusal after a picture: nothing is kept either
        raise
    except (OSError, KeyError, ValueError, IndexError, TypeError) as e:
        remove_written()
        print(f"vibro plot: {args.file}: cannot be drawn, its data are damaged ({type(e).__name__}: {e}); "
              "nothing was written", file=sys.stderr)
        sys.exit(2)
    for w in written:
        print(w)


def scene_contacts(f):
    """The [[contact]] tables of the run's scene (empty for a [stop] scene)."""
    import tomllib
    try:
        return tomllib.loads(text(f.attrs["scene"])).get("contact", [])
    except (KeyError, tomllib.TOMLDecodeError):
        return []


def compliant_law(table):
    """'k = …, c = …' for a compliant contact's table ([stop] or [[contact]]), None for a rigid one
    (docs/compliant.md)."""
    if not isinstance(table, dict) or "stiffness" not in table:
        return None
    law = f"k = {float(table['stiffness']):g}"
    if float(table.get("damping", 0.0)) > 0:
        law += f", c = {float(table['damping']):g}"
    return law


def scene_table(f, name):
    """A top-level table of the run's scene ({} when absent or unreadable)."""
    import tomllib
    try:
        return tomllib.loads(text(f.attrs["scene"])).get(name, {})
    except (KeyError, tomllib.TOMLDecodeError):
        return {}


def contact_shade_label(f):
    """The legend of the shaded contact phases: a compliant stop's phases are contact phases
    (the body presses on the spring–dashpot), a rigid stop's are sticking."""
    tables = scene_contacts(f) or [scene_table(f, "stop")]
    return "in contact (compliant)" if any(compliant_law(t) for t in tables) else "sticking"


def gap_coordinates(f, contacts):
    """Per contact j (docs/contacts.md): (a_j, σ_j, d_j, name) with g_j = σ_j (a_jᵀX − d_j) on the
    modal state X: a_j = Φᵀw_j in the physical form (w_j picks q_dof, minus q_partner for an impact
    pair); in the modal form a_0 = σ_0 (1, …, 1) and a_j = `modal` on the kept modes (the lowest
    frequencies)."""
    n = len(f["model"].attrs["frequencies"])
    out = []
    if "mode_shapes" in f["model"].attrs:
        phi = np.asarray(f["model"].attrs["mode_shapes"], dtype=float).reshape(-1, n)
    else:
        import tomllib
        freqs = np.asarray(tomllib.loads(text(f.attrs["scene"]))["structure"]["frequencies"], dtype=float)
        kept = np.argsort(freqs, kind="stable")[:n]
    for j, c in enumerate(contacts):
        sigma = 1.0 if c.get("side", "below") == "below" else -1.0
        if "mode_shapes" in f["model"].attrs:
            dofs = c.get("dofs", [c.get("dof", 0)])
            w = np.zeros(phi.shape[0])
            w[int(dofs[0])] = 1.0
            if len(dofs) > 1:
                w[int(dofs[1])] = -1.0
            a = phi.T @ w
            where = f"q{dofs[0]}" + (f" − q{dofs[1]}" if len(dofs) > 1 else "")
        else:
            a = sigma * np.ones(n) if j == 0 else np.asarray(c["modal"], dtype=float)[kept]
            where = f"a{j}·X"
        out.append((a, sigma, float(c["position"]), where))
    return out


def dense_states(f, t_from, t_to, per_period=600):
    """Several contacts: the modal state X, Ẋ on a dense grid of [t_from, t_to], exact: the free
    flight (docs/model.md §2, §7) forward from each stored sample in flight to the first event
    after it, and backward from the next sample in flight to the last event before it, so that
    both sides of every impact are on the grid at its instant. While a contact holds, and between
    two events inside one sample step, the stored samples alone (straight between them); a NaN
    row breaks the curve where the state between two events is not known."""
    model = f["model"]
    T = float(f.attrs["forcing_period"])
    per_period = max(50, min(per_period, int(2e5 * T / (t_to - t_from))))
    t = f["samples/t"][:]
    lo = max(0, np.searchsorted(t, t_from) - 1)
    hi = min(len(t), np.searchsorted(t, t_to) + 1)
    ts = t[lo:hi]
    Xs, Vs, ms = f["samples/X"][lo:hi], f["samples/V"][lo:hi], f["samples/mode"][lo:hi]
    ev_t = f["events/t"][:]
    n = Xs.shape[1]
    gap = np.full((1, n), np.nan)
    out_t, out_X, out_V = [], [], []

    def emit(tt, X, V):
        out_t.append(np.atleast_1d(tt))
        out_X.append(np.atleast_2d(X))
        out_V.append(np.atleast_2d(V))
    for k in range(len(ts) - 1):
        a, b = ts[k], ts[k + 1]
        emit(a, Xs[k], Vs[k])
        if b <= a:
            continue
        evs = ev_t[np.searchsorted(ev_t, a, side="right"):np.searchsorted(ev_t, b, side="left")]
        m = max(2, int(np.ceil(per_period * (b - a) / T)))
        grid = np.linspace(a, b, m, endpoint=False)[1:]
        if len(evs) == 0:
            if ms[k] == 0:
                emit(grid, *free_flight(model, Xs[k], Vs[k], a, grid))
            continue
        if ms[k] == 0:
            head = np.append(grid[grid < evs[0]], evs[0])
            emit(head, *free_flight(model, Xs[k], Vs[k], a, head))
        if len(evs) > 1 or ms[k] != 0 or ms[k + 1] != 0:
            emit([np.nan], gap, gap)  # the state between the events is not known
        if ms[k + 1] == 0:
            tail = np.insert(grid[grid > evs[-1]], 0, evs[-1])
            emit(tail, *free_flight(model, Xs[k + 1], Vs[k + 1], b, tail))
    if len(ts):
        emit(ts[-1], Xs[-1], Vs[-1])
    tt, XX, VV = np.concatenate(out_t), np.concatenate(out_X), np.concatenate(out_V)
    sel = np.isnan(tt) | ((tt >= t_from) & (tt <= t_to))
    return tt[sel], XX[sel], VV[sel]


def plot_contacts_run(f, title, save, window, contacts, coordinate):
    """Several contacts: PREFIX_phase and PREFIX_section of every gap g_j (one panel each), or of
    --coordinate (then also PREFIX_<coordinate>, that coordinate against t with every contact's
    impacts marked and its sticking shaded), from dense_states."""
    T = float(f.attrs["forcing_period"])
    status = text(f.attrs["status"])
    t = f["samples/t"][:]
    t_from, t_to = time_window(t, T, window)
    span = f"{t_from:.6g} ≤ t ≤ {t_to:.6g}"
    compliant = compliant_contacts(f)
    if compliant:  # the contact phases drawn exactly, the penetration included
        tt, XX, VV, _ = compliant_states(f, t_from, t_to, compliant)
    else:
        tt, XX, VV = dense_states(f, t_from, t_to)
    sX, sV = f["section/X"][:], f["section/V"][:]
    k = np.arange(len(sX))
    if coordinate != "x_B":
        w, sym = coordinate_choices(f)[coordinate]
        labels = f["model"].attrs["dof_labels"] if "dof_labels" in f["model"].attrs else []
        what = (f"physical displacement {coordinate} ({text(labels[int(coordinate[1:])])})"
                if coordinate.startswith("q") and len(labels) else
                f"physical displacement {coordinate}" if coordinate.startswith("q") else f"modal coordinate {coordinate}")
        ev_t, kinds, ev_c = f["events/t"][:], f["events/kind"][:], f["events/contact"][:]
        kind_of = h5py.check_enum_dtype(f["events/kind"].dtype)
        fig, ax = figure(figsize=(9, 3.8))
        ax.plot(tt, XX @ w, lw=1, color=OKABE_ITO[0], label=f"${sym}$")
        for j in range(len(contacts)):
            sticks = ev_t[(ev_c == j) & (kinds == kind_of["stick"])]
            releases = ev_t[(ev_c == j) & (kinds == kind_of["release"])]
            for n_, s0 in enumerate(sticks):
                later = releases[releases > s0]
                e = later[0] if len(later) else t_to
                if e >= t_from and s0 <= t_to:
                    ax.axvspan(max(s0, t_from), min(e, t_to), color=STICK_SHADE, alpha=0.25, lw=0,
                               label=contact_shade_label(f) if n_ == 0 and j == 0 else None)
            imp = (ev_c == j) & (kinds == kind_of["impact"]) & (ev_t >= t_from) & (ev_t <= t_to)
            if imp.any():
                known = np.isfinite(tt)
                ax.plot(ev_t[imp], np.interp(ev_t[imp], tt[known], (XX @ w)[known]), "v^os"[j % 4], ms=3.5,
                        color=OKABE_ITO[(j + 1) % 7], label=f"impacts on contact {j} ({imp.sum()})")
        ax.set_xlabel("$t$")
        ax.set_ylabel(f"${sym}$")
        ax.set_xlim(t_from, t_to)
        absolute_time(ax)
        set_title(ax, title, f"{what}, {span} ({status})")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=fs(8), frameon=False)
        save(fig, coordinate)
        panels = [(w, 0.0, 1.0, sym, None)]
    else:
        panels = [(a, d, sigma, f"g_{{{j}}}", f"contact {j}: {where} {'≥' if sigma > 0 else '≤'} {d:g}")
                  for j, (a, sigma, d, where) in enumerate(gap_coordinates(f, contacts))]

    def grid_of(m):
        fig, axes = figure(1, m, figsize=(4.2 * m + 1.0, 4.4), squeeze=False)
        if fig.get_layout_engine() is None:
            fig.set_layout_engine("constrained")
        return fig, axes[0]
    fig, axes = grid_of(len(panels))
    for ax, (a, d, sigma, sym, name) in zip(axes, panels):
        ax.plot(sigma * (XX @ a - d), sigma * (VV @ a), lw=0.8, color=OKABE_ITO[0])
        if name:
            ax.axvline(0, color="k", lw=1.2)
            ax.set_title(name, fontsize=fs(9), loc="left")
        ax.set_xlabel(f"${sym}$")
        ax.set_ylabel(f"$\\dot {sym}$")
    detail = f"phase portrait{'s of the gaps' if coordinate == 'x_B' else ''}, {span}"
    if len(axes) == 1:
        set_title(axes[0], title, detail)
    elif OPTIONS["title"] != "":
        fig.suptitle(OPTIONS["title"] if OPTIONS["title"] is not None else f"{title}\n{detail}", fontsize=fs(10))
    save(fig, "phase")

    fig, axes = grid_of(len(panels))
    for ax, (a, d, sigma, sym, name) in zip(axes, panels):
        sc = ax.scatter(sigma * (sX @ a - d), sigma * (sV @ a), c=k, s=6, cmap="viridis")
        if name:
            ax.set_title(name, fontsize=fs(9), loc="left")
        ax.set_xlabel(f"${sym}(t_0 + kT)$")
        ax.set_ylabel(f"$\\dot {sym}(t_0 + kT)$")
    fig.colorbar(sc, ax=list(axes), label="period $k$")
    detail = f"stroboscopic section{' of the gaps' if coordinate == 'x_B' else ''}, {len(sX)} periods"
    if len(axes) == 1:
        set_title(axes[0], title, detail)
    elif OPTIONS["title"] != "":
        fig.suptitle(OPTIONS["title"] if OPTIONS["title"] is not None else f"{title}\n{detail}", fontsize=fs(10))
    save(fig, "section")


def plot_gaps(f, title, save, window, contacts):
    """Several contacts (docs/contacts.md): every gap g_j = σ_j (w_jᵀq − d_j) against t, one panel
    per contact, from the stored samples (exact states) and the contact's own events (g_j = 0 at
    its impacts and while it sticks); sticking on that contact shaded, impacts marked."""
    T = float(f.attrs["forcing_period"])
    status = text(f.attrs["status"])
    t = f["samples/t"][:]
    t_from, t_to = time_window(t, T, window)
    X = f["samples/X"][:]
    gaps = gap_coordinates(f, contacts)
    ev_t, kinds, ev_c = f["events/t"][:], f["events/kind"][:], f["events/contact"][:]
    kind_of = h5py.check_enum_dtype(f["events/kind"].dtype)
    m = len(contacts)
    fig, axes = figure(m, 1, figsize=(9, 1.2 + 1.5 * m), sharex=True, squeeze=False)
    if fig.get_layout_engine() is None:
        fig.set_layout_engine("constrained")
    compliant = compliant_contacts(f)
    if compliant:  # exact between the samples, through every contact phase (its penetration g < 0)
        dense_t, dense_X, _, _ = compliant_states(f, t_from, t_to, compliant)
    for j, (c, ax) in enumerate(zip(contacts, axes[:, 0])):
        a, sigma, d, where = gaps[j]
        mine = ev_c == j
        if compliant:
            tt, gg = dense_t, sigma * (dense_X @ a - d)
        else:
            g = sigma * (X @ a - d)
            zero_t = ev_t[mine & np.isin(kinds, [kind_of["impact"], kind_of["accumulation"], kind_of["stick"],
                                                kind_of["release"], kind_of["grazing"]])]
            tt = np.concatenate([t, zero_t])
            gg = np.concatenate([g, np.zeros(len(zero_t))])
            order = np.argsort(tt, kind="stable")
            tt, gg = tt[order], gg[order]
        sel = np.isnan(tt) | ((tt >= t_from) & (tt <= t_to))
        ax.plot(tt[sel], gg[sel], lw=1, color=OKABE_ITO[j % 7])
        ax.axhline(0, color="k", lw=1.0)
        sticks = ev_t[mine & (kinds == kind_of["stick"])]
        releases = ev_t[mine & (kinds == kind_of["release"])]
        drawn = 0
        for s0 in sticks:
            later = releases[releases > s0]
            e = later[0] if len(later) else t_to
            if e >= t_from and s0 <= t_to:
                ax.axvspan(max(s0, t_from), min(e, t_to), color=STICK_SHADE, alpha=0.25, lw=0,
                           label=contact_shade_label(f) if drawn == 0 else None)
                drawn += 1
        imp = mine & (kinds == kind_of["impact"]) & (ev_t >= t_from) & (ev_t <= t_to)
        if imp.any():
            ax.plot(ev_t[imp], np.zeros(imp.sum()), "v", ms=3.5, color=OKABE_ITO[1],
                    label=f"impacts ({imp.sum()})")
        rel = "≥" if sigma > 0 else "≤"
        ax.set_ylabel(f"$g_{j}$")
        law = compliant_law(c) or f"r = {c.get('restitution', 0):g}"
        ax.set_title(f"contact {j}: {where} {rel} {c['position']:g}, {law}",
                     fontsize=fs(9), loc="left")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=fs(8), frameon=False)
    ax = axes[-1, 0]
    ax.set_xlabel("$t$")
    ax.set_xlim(t_from, t_to)
    absolute_time(ax)
    sequence = text(f["orbit"].attrs["sequence"]) if "orbit" in f and "sequence" in f["orbit"].attrs else ""
    seq_line = f"\ncontact sequence of the orbit: {sequence}" if sequence else ""
    chosen = OPTIONS["title"]  # --title replaces the scene line and the window, never the sequence
    if chosen != "" or sequence:
        head = chosen if chosen is not None else f"{title}\nevery gap, {t_from:.6g} ≤ t ≤ {t_to:.6g} ({status})"
        fig.suptitle((head + seq_line).lstrip("\n"), fontsize=fs(10))
    save(fig, "gaps")
    if compliant:
        plot_contact_forces(f, title, save, window, compliant)
    if "orbit" in f and "multipliers" in f["orbit"].attrs:
        plot_multipliers(f, title, save)


def plot_loads(f, title, save):
    """Histograms of the impact speeds |v⁻| and of the impulses P, per contact (docs/loads.md), on
    logarithmic bins: a chattering sequence spans many decades. Accumulation tails are not impacts
    followed: they are left out (their summed impulses are in the loads of the summary)."""
    ev = f["events"]
    kind_of = h5py.check_enum_dtype(ev["kind"].dtype)
    kinds = ev["kind"][:]
    impacts = kinds == kind_of["impact"]
    contact = ev["contact"][:] if "contact" in ev else np.zeros(len(kinds), dtype=int)
    v = np.abs(ev["v_before"][:])
    P = ev["impulse"][:]
    ids = sorted(set(contact[impacts].tolist()))
    if not ids:
        return
    fig, axes = figure(len(ids), 2, figsize=(8.0, 2.8 * len(ids)), squeeze=False)
    for row, j in enumerate(ids):
        sel = impacts & (contact == j) & (v > 0) & (P > 0)
        for ax, data, label in ((axes[row][0], v[sel], "impact speed |v⁻|"), (axes[row][1], P[sel], "impulse P")):
            if len(data) == 0:
                continue
            lo, hi = np.log10(data.min()), np.log10(data.max())
            bins = np.logspace(lo, hi + 1e-9, 40) if hi > lo else 10
            ax.hist(data, bins=bins, color="C0" if row % 2 == 0 else "C1")
            if hi > lo:
                ax.set_xscale("log")
            ax.set_xlabel(label + (f", contact {j}" if len(ids) > 1 else ""))
            ax.set_ylabel("impacts")
    set_title(axes[0][0], title, f"{int(impacts.sum())} impacts")
    if OPTIONS["size"] is None:
        fig.tight_layout()
    save(fig, "loads")


def refuse(message):
    """Bad input: one line, exit 2 (main() removes any picture written)."""
    print(f"vibro plot: {message}", file=sys.stderr)
    sys.exit(2)


def check_options(f, args, window):
    """Every option checked against the file before anything is drawn: a refused plot writes
    nothing (docs/cli.md)."""
    dense = "samples" in f and len(f["samples/t"]) > 1
    if args.coordinate != "x_B":
        why = coordinate_error(f, args.coordinate)
        if why is None and not dense:
            why = "the file has no dense samples to draw it from (it applies to the time plot, phase portrait and section)"
        if why is not None:
            refuse(f"--coordinate {args.coordinate}: {why}")
    if args.overlay and "sweep" not in f and "partition" not in f:
        refuse(f"--overlay {args.overlay}: {args.file} holds no sweep or partition to draw it over")
    if args.overlay and "partition" in f:
        c1, c2, _ = read_curves(args.overlay)
        p1, p2 = text(f["partition"].attrs["param1"]), text(f["partition"].attrs["param2"])
        if {c1, c2} != {p1, p2}:
            refuse(f"--overlay {args.overlay}: its curves are in ({c1}, {c2}), the partition in ({p1}, {p2})")
    if dense:
        time_window(f["samples/t"][:], float(f.attrs["forcing_period"]), window)


def draw(args, save, window):
    with h5py.File(args.file, "r") as f:
        check_options(f, args, window)
        varied = set()
        for g, attr in (("branch", "param"), ("sweep", "param"), ("diagram", "param"), ("partition", "param1"),
                        ("partition", "param2"), ("curves", "param1"), ("curves", "param2")):
            if g in f:
                varied.add(text(f[g].attrs[attr]))
        title = make_title(f, varied)
        if "basin" in f:
            plot_basin(f, title, save)
        if "branch" in f:
            plot_branch(f, title, save)
            plot_branch_loads(f, title, save)
            plot_branch_peaks(f, title, save)
        if "partition" in f:
            plot_partition(f, title, save, args.overlay)
            plot_partition_loads(f, title, save)
        if "sweep" in f:
            plot_sweep(f, title, save, args.overlay)
        if "diagram" in f:
            plot_diagram(f, title, save)
        if "curves" in f:
            plot_curves(f, title, save)
        if "events" in f and "impulse" in f["events"]:
            plot_loads(f, title, save)
        contacts = scene_contacts(f)
        if len(contacts) > 1 and len(f["samples/t"]) > 1:
            plot_gaps(f, title, save, window, contacts)
            plot_contacts_run(f, title, save, window, contacts, args.coordinate)
        elif len(f["samples/t"]) > 1:
            plot_run(f, title, save, window, args.coordinate)
        elif not any(g in f for g in ("basin", "branch", "partition", "sweep", "diagram", "curves")):
            print("vibro plot: the file has no dense samples (run.samples_per_period = 0)", file=sys.stderr)


if __name__ == "__main__":
    main()
