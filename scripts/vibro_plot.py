#!/usr/bin/python3
"""Plots of a vibro HDF5 run (called by `vibro plot FILE.h5 [--out PREFIX]`).

Writes PREFIX_basin.png for a basin study, PREFIX_sweep.png for a sweep (with a continuation
branch overlaid by --overlay BRANCH.h5), and for a run with samples PREFIX_xB.png (contact
displacement, sticking shaded, impacts marked), PREFIX_reaction.png (contact reaction R), PREFIX_phase.png (phase portrait x_B, dx_B/dt) and PREFIX_section.png
(stroboscopic section). The time plots show the last `--periods` forcing periods (default 5).
"""
import argparse
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def reaction(model, X, V, t):
    """MODEL eq. (5) with the damping term of §7: the reaction a state on the stop needs."""
    w = model.attrs["frequencies"]
    c = model.attrs["contact_shape"]
    z = model.attrs["damping_ratios"]
    elastic = (X * (c * w * w)).sum(axis=1) + (V * (c * 2 * z * w)).sum(axis=1)
    forcing = model.attrs["s_A"] * model.attrs["amplitude"] * np.sin(model.attrs["frequency"] * t)
    return (elastic - forcing) / model.attrs["s_B"]


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
    """Label map of a basin study, one colour per attractor (grey: unresolved)."""
    b = f["basin"]
    labels = b["labels"][:]
    a = attractor_table(f["attractors"])
    kinds = list(a["kind"])
    n = len(kinds)
    colors = plt.get_cmap("tab10")
    rgb = np.ones(labels.shape + (3,)) * 0.85
    rgb[labels == -2] = (1, 1, 1)
    for k in range(n):
        rgb[labels == k] = colors(k % 10)[:3]
    fig, ax = plt.subplots(figsize=(7, 6))
    xr, yr = b.attrs["x_range"], b.attrs["y_range"]
    ax.imshow(rgb, origin="lower", extent=(xr[0], xr[1], yr[0], yr[1]), aspect="auto",
              interpolation="nearest")
    from matplotlib.patches import Patch
    handles = []
    for k in range(n):
        per = int(a["period"][k])
        sp = a["sticking_fraction"][k]
        label = f"{k}: {kinds[k]}, period {per}" + (f", SP {sp:.3f}" if sp > 0 else "")  # NaN: none
        label += f" ({100 * a['basin_fraction'][k]:.1f} %)"
        handles.append(Patch(color=colors(k % 10), label=label))
    handles.append(Patch(color=(0.85, 0.85, 0.85),
                         label=f"unresolved ({100 * b.attrs['unresolved_fraction']:.1f} %)"))
    ax.legend(handles=handles, loc="upper right", fontsize=7)
    ax.set_xlabel(b.attrs["x"])
    ax.set_ylabel(b.attrs["y"])
    ax.set_title(f"{title}\nbasins of attraction ({labels.shape[1]} x {labels.shape[0]})")
    save(fig, "basin")


BIFURCATION_MARKERS = {"fold": "s", "flip": "D", "neimark-sacker": "*", "rising": "^",
                       "grazing": "v", "sticking-entry": ">", "sticking-lost": "X", "non-smooth": "o"}


def draw_branch(ax, f, quantity="sticking_fraction", label_prefix=""):
    """A continuation branch: solid where stable, dashed where unstable; bifurcations marked."""
    b = f["branch"]
    value = b["value"][:]
    y = b[quantity][:]
    stable = b["stable"][:].astype(bool)
    # Split into runs of equal stability (each run drawn with the neighbouring point included).
    start = 0
    for i in range(1, len(value) + 1):
        if i == len(value) or stable[i] != stable[start]:
            j = min(i + 1, len(value))
            ax.plot(value[start:j], y[start:j], "-" if stable[start] else "--", color="C0", lw=1.5,
                    label=None)
            start = i
    ax.plot([], [], "-", color="C0", label=f"{label_prefix}stable")
    ax.plot([], [], "--", color="C0", label=f"{label_prefix}unstable")
    bif = f["bifurcations"]
    kinds = [k.decode() if isinstance(k, bytes) else k for k in bif["kind"][:]]
    seen = set()
    for v, k in zip(bif["value"][:], kinds):
        yv = np.interp(v, value, y) if np.all(np.diff(value) > 0) else y[np.argmin(np.abs(value - v))]
        ax.plot([v], [yv], BIFURCATION_MARKERS.get(k, "o"), color="C3", ms=8,
                label=k if k not in seen else None)
        seen.add(k)


def plot_branch(f, title, save):
    """Bifurcation diagram of a continuation (sticking fraction and largest |multiplier|)."""
    b = f["branch"]
    param = b.attrs["param"]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    draw_branch(ax1, f)
    ax1.set_ylabel("sticking fraction")
    ax1.legend(fontsize=8, loc="best")
    m = f["model"].attrs
    ax1.set_title(f"{title}\ncontinued from f = {m['amplitude']:g}; period {b.attrs['period']}; "
                  f"end: {b.attrs['end']}", fontsize=9)
    draw_branch(ax2, f, "max_multiplier")
    ax2.axhline(1.0, color="0.6", lw=0.8)
    if np.nanmax(b["max_multiplier"][:]) > 10:
        ax2.set_yscale("log")
    ax2.set_ylabel("largest |multiplier|")
    ax2.set_xlabel(param)
    save(fig, "branch")


def plot_partition(f, title, save):
    """Curves of constant sticking fraction and existence boundaries in a parameter plane."""
    p = f["partition"]
    p1, p2 = p.attrs["param1"], p.attrs["param2"]
    xv1, xl, xv2 = p["crossing_value1"][:], p["crossing_level"][:], p["crossing_value2"][:]
    bv1, bv2 = p["boundary_value1"][:], p["boundary_value2"][:]
    bk = np.array([k.decode() if isinstance(k, bytes) else k for k in p["boundary_kind"][:]])
    fig, ax = plt.subplots(figsize=(7, 5.5))
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
        colour = cmap(i / max(1, len(levels) - 1))
        for n, (xs, ys, style) in enumerate(segments(xv1[sel], xv2[sel])):
            ax.plot(xs, ys, style, color=colour, lw=1.4, ms=3, label=f"SP = {s:g}" if n == 0 else None)
    for j, k in enumerate(sorted(set(bk))):
        sel = bk == k
        ax.plot(bv1[sel], bv2[sel], BIFURCATION_MARKERS.get(k, "o"), color=f"C{3 + j % 7}", ms=5,
                ls="none", label=k)
    handles, names = ax.get_legend_handles_labels()
    unique = dict(zip(names, handles))
    ax.legend(unique.values(), unique.keys(), fontsize=8, loc="best")
    ax.set_xlabel(p1)
    ax.set_ylabel(p2)
    ax.set_title(f"{title}\npartition: curves of constant sticking fraction", fontsize=9)
    save(fig, "partition")


def read_branch(path, param):
    """A continuation branch file (`vibro continue --out`): /branch and /bifurcations."""
    try:
        with h5py.File(path, "r") as f:
            b = f["branch"]
            br = {k: b[k][()] for k in ("value", "sticking_fraction", "stable")}
            br["param"] = b.attrs["param"]
            bif = f["bifurcations"] if "bifurcations" in f else None
            br["bif_value"] = bif["value"][()] if bif is not None else np.array([])
            kinds = bif["kind"][()] if bif is not None else []
            br["bif_kind"] = [k.decode() if isinstance(k, bytes) else str(k) for k in kinds]
    except (OSError, KeyError) as e:
        print(f"--overlay {path}: not a continuation branch file (needs /branch with value, "
              f"sticking_fraction, stable and the attribute param): {e}", file=sys.stderr)
        sys.exit(2)
    if br["param"] != param:
        print(f"--overlay {path}: the branch varies {br['param']}, the sweep {param}", file=sys.stderr)
        sys.exit(2)
    return br


def plot_sweep(f, title, save, overlay):
    """Brute-force bifurcation diagram: x_B at the section and the sticking fraction against the
    parameter, upward and downward runs marked; optionally a continuation branch overlaid."""
    s = f["sweep"]
    param = s.attrs["param"]
    value, up = s["value"][()], s["upward"][()].astype(bool)
    xB, sp = s["x_B"][()], s["sticking_fraction"][()]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for sel, marker, color, name in ((up, "o", "tab:blue", "upward"), (~up, "x", "tab:red", "downward")):
        if not sel.any():
            continue
        v = np.repeat(value[sel], xB.shape[1])
        ax1.plot(v, xB[sel].ravel(), marker, ms=2.5 if marker == "o" else 3.5, color=color,
                 mfc="none" if marker == "o" else color, lw=0, label=f"{name} sweep")
        ax2.plot(value[sel], sp[sel], marker, ms=4, color=color, mfc="none" if marker == "o" else color,
                 lw=0, label=f"{name} sweep")
    if overlay:
        br = read_branch(overlay, param)
        v, b_sp, stable = br["value"], br["sticking_fraction"], br["stable"].astype(bool)
        # Solid where stable, dashed where unstable (each segment takes the stability of its start).
        for i in range(len(v) - 1):
            ax2.plot(v[i:i + 2], b_sp[i:i + 2], "-" if stable[i] else "--", color="k", lw=1.2)
        ax2.plot([], [], "-", color="k", label="continuation, stable")
        ax2.plot([], [], "--", color="k", label="continuation, unstable")
        for bv, bk in zip(br["bif_value"], br["bif_kind"]):
            for ax in (ax1, ax2):
                ax.axvline(bv, color="tab:green", lw=0.8, ls=":")
            y = b_sp[np.argmin(np.abs(v - bv))] if len(v) else 0.0  # nearest point (folds)
            ax2.plot([bv], [y], "D", color="tab:green", ms=6)
            ax2.annotate(bk, (bv, y), textcoords="offset points", xytext=(4, 6), fontsize=8, color="tab:green")
    ax1.set_ylabel("$x_B$ at the section $t_0 + kT$")
    ax1.set_title(f"{title}\nbrute-force sweep of {param}, up and down")
    ax1.legend(loc="best", fontsize=8)
    ax2.set_xlabel(param)
    ax2.set_ylabel("sticking fraction")
    ax2.legend(loc="best", fontsize=8)
    save(fig, "sweep")


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("file")
    ap.add_argument("--out", default=None, help="prefix of the PNG files")
    ap.add_argument("--periods", type=float, default=5.0, help="forcing periods shown in time plots")
    ap.add_argument("--overlay", default=None, help="continuation branch (HDF5) drawn over a sweep")
    args = ap.parse_args()
    prefix = args.out or os.path.splitext(args.file)[0]
    written = []

    def save(fig, suffix):
        fig.tight_layout()
        fig.savefig(f"{prefix}_{suffix}.png", dpi=110)
        written.append(f"{prefix}_{suffix}.png")
        plt.close(fig)
    with h5py.File(args.file, "r") as f:
        title = f.attrs["scene"].splitlines()[0] if f.attrs["scene"].startswith("title") else args.file
        title = title.replace("title = ", "").strip("'\"")
        ma = f["model"].attrs
        title += f" (run as r = {ma['restitution']:g}, ω = {ma['frequency']:g}, f = {ma['amplitude']:g})"
        status = f.attrs["status"]
        T = float(f.attrs["forcing_period"])
        model = f["model"]
        c = model.attrs["contact_shape"]
        x0 = float(model.attrs["stop"])
        if "basin" in f:
            plot_basin(f, title, save)
        if "branch" in f:
            plot_branch(f, title, save)
        if "partition" in f:
            plot_partition(f, title, save)
        if "sweep" in f:
            plot_sweep(f, title, save, args.overlay)
        elif args.overlay:
            print(f"--overlay {args.overlay}: {args.file} holds no sweep to draw it over", file=sys.stderr)
            sys.exit(2)
        t = f["samples/t"][:]
        if len(t) == 0:
            if not any(g in f for g in ("basin", "branch", "partition", "sweep")):
                print("vibro plot: the file has no dense samples (run.samples_per_period = 0)",
                      file=sys.stderr)
            for w in written:
                print(w)
            return
        t_end = t[-1] if len(t) else 0.0
        t_from = t_end - args.periods * T
        sel = t >= t_from
        ts = t[sel]
        X = f["samples/X"][:][sel]
        V = f["samples/V"][:][sel]
        xB = f["samples/x_B"][:][sel]
        mode = f["samples/mode"][:][sel]
        vB = (V * c).sum(axis=1)
        ev_t = f["events/t"][:]
        kinds = f["events/kind"][:]
        ev_xB = f["events/x_B"][:]
        kind_of = h5py.check_enum_dtype(f["events/kind"].dtype)
        in_view = (ev_t >= t_from) & (ev_t <= t_end)

        def shade_sticking(ax):
            sticks = ev_t[(kinds == kind_of["stick"])]
            releases = ev_t[(kinds == kind_of["release"])]
            for s in sticks:
                later = releases[releases > s]
                e = later[0] if len(later) else t_end
                if e >= t_from and s <= t_end:
                    ax.axvspan(max(s, t_from), min(e, t_end), color="tab:orange", alpha=0.25, lw=0)

        fig, ax = plt.subplots(figsize=(9, 4))
        ax.plot(ts, xB, lw=1, label="$x_B$")
        ax.axhline(x0, color="k", lw=1.5, label="stop $x_0$")
        shade_sticking(ax)
        imp = in_view & (kinds == kind_of["impact"])
        ax.plot(ev_t[imp], ev_xB[imp], "v", ms=3, color="tab:red", label=f"impacts ({imp.sum()})")
        ax.set_xlabel("t")
        ax.set_ylabel("$x_B$")
        ax.set_title(f"{title}\ncontact displacement, sticking shaded ({status})")
        ax.legend(loc="upper right", fontsize=8)
        save(fig, "xB")

        fig, ax = plt.subplots(figsize=(9, 4))
        R = reaction(model, X, V, ts)
        ax.plot(ts, np.where(mode == 1, R, np.nan), lw=1.5, label="R (on the stop)")
        ax.plot(ts, np.where(mode == 0, R, np.nan), lw=0.8, ls="--", color="gray",
                label="R* (reaction the free state would need)")
        ax.axhline(0, color="k", lw=0.8)
        shade_sticking(ax)
        ax.set_xlabel("t")
        ax.set_ylabel("R")
        ax.set_title(f"{title}\ncontact reaction")
        ax.legend(loc="upper right", fontsize=8)
        save(fig, "reaction")

        fig, ax = plt.subplots(figsize=(6, 5))
        ax.plot(xB, vB, lw=0.8)
        ax.axvline(x0, color="k", lw=1.5)
        ax.set_xlabel("$x_B$")
        ax.set_ylabel("$\\dot x_B$")
        ax.set_title(f"{title}\nphase portrait (last {args.periods:g} periods)")
        save(fig, "phase")

        sX = f["section/X"][:]
        sV = f["section/V"][:]
        sxB = (sX * c).sum(axis=1)
        svB = (sV * c).sum(axis=1)
        fig, ax = plt.subplots(figsize=(6, 5))
        k = np.arange(len(sxB))
        sc = ax.scatter(sxB, svB, c=k, s=8, cmap="viridis")
        fig.colorbar(sc, ax=ax, label="period")
        ax.set_xlabel("$x_B(t_0 + kT)$")
        ax.set_ylabel("$\\dot x_B(t_0 + kT)$")
        ax.set_title(f"{title}\nstroboscopic section ({len(sxB)} points)")
        save(fig, "section")
        if "orbit" in f:
            re, im, stable, period = orbit_group(f["orbit"])
            fig, ax = plt.subplots(figsize=(5, 5))
            th = np.linspace(0, 2 * np.pi, 400)
            ax.plot(np.cos(th), np.sin(th), color="k", lw=0.8, label="unit circle")
            ax.plot(re, im, "o", color="tab:green" if stable else "tab:red",
                    label=f"Floquet multipliers ({'stable' if stable else 'unstable'})")
            lim = max(1.2, 1.1 * max([1.0] + list(np.hypot(re, im))))
            ax.set_xlim(-lim, lim)
            ax.set_ylim(-lim, lim)
            ax.set_aspect("equal")
            ax.axhline(0, color="gray", lw=0.5)
            ax.axvline(0, color="gray", lw=0.5)
            ax.set_title(f"{title}\nperiod-{period} orbit: multipliers")
            ax.legend(loc="upper right", fontsize=8)
            save(fig, "multipliers")
    for w in written:
        print(w)


if __name__ == "__main__":
    main()
