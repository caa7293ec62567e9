#!/usr/bin/env python3
"""Draws a branch that `vibro continue --out` took through a grazing (docs/orbits.md, "Through a
grazing"): left, contact 0's stroboscopic coordinate along the branch, coloured by contact
sequence; middle, the slowest impact speed of each point's period; right, past the first grazing
the branch went through, the new impact's speed against the distance to it (log-log, with the
lines of slope 1 and 1/2). Stable points filled, unstable open.

    python3 scripts/plot_through_grazing.py BRANCH.h5 OUT.png [--zoom D] [--title T]
"""
import argparse

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def text(x):
    return x.decode() if isinstance(x, bytes) else str(x)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("branch")
    ap.add_argument("out")
    ap.add_argument("--zoom", type=float, default=3e-3, help="the largest distance to the grazing in the log-log panel")
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    with h5py.File(a.branch) as f:
        b = f["branch"]
        param = text(b.attrs["param"])
        value = b["value"][:]
        stable = b["stable"][:].astype(bool)
        strobe = b["strobe"][:]
        off = b["impact_offsets"][:]
        speeds = np.abs(b["impact_v_before"][:])
        bif = f["bifurcations"]
        through = [text(x) for x in bif["through"][:]] if "through" in bif else []
        marks = [(bif["value"][k], text(bif["sequence_before"][k]), text(bif["sequence_after"][k]), through[k])
                 for k in range(len(through)) if through[k]]
        seqs = [text(x) for x in b["sequence"][:]] if "sequence" in b else [""] * len(value)
        events = [text(x) for x in b["events"][:]]
    slow = np.array([speeds[off[k]:off[k + 1]].min() if off[k + 1] > off[k] else np.nan for k in range(len(value))])
    labels = [s or e for s, e in zip(seqs, events)]
    kinds = list(dict.fromkeys(labels))
    fig, (ax0, ax1, ax2) = plt.subplots(1, 3, figsize=(14, 4.3))
    for ax, y, ylabel in ((ax0, strobe[:, 0], "strobe: contact 0's coordinate"),
                          (ax1, slow, "slowest impact speed |ġ⁻| of the period")):
        ax.plot(value, y, "-", lw=0.6, color="0.6")
        for j, kind in enumerate(kinds):
            sel = np.array([l == kind for l in labels])
            ax.plot(value[sel & stable], y[sel & stable], "o", ms=3, color=f"C{j}", label=kind)
            ax.plot(value[sel & ~stable], y[sel & ~stable], "o", ms=3, mfc="none", color=f"C{j}")
        for (at, before, after, how) in marks:
            ax.axvline(at, color="k", lw=0.6, ls=":")
        ax.set_xlabel(param)
        ax.set_ylabel(ylabel)
    ax0.legend(fontsize=8, title="contact sequence", title_fontsize=8)
    for i, (at, before, after, how) in enumerate(marks):  # one text line per grazing, stacked
        ax1.annotate(f"grazing at {at:.10f}: the branch goes {'back' if how == 'back' else 'on past it'}",
                     xy=(at, 0), xytext=(0.05, 0.9 - 0.1 * i), textcoords="axes fraction", fontsize=7,
                     arrowprops=dict(arrowstyle="->", lw=0.6))
    if marks:
        at, before, after, how = marks[0]
        # Past the grazing: the points with its new sequence, next to it.
        sel = np.array([l == after for l in labels]) & (np.abs(value - at) < a.zoom) & (value != at)
        d = np.abs(value[sel] - at)
        ax2.loglog(d, slow[sel], "o", ms=3, mfc="none", color="C1", label=f"{after} (past the grazing)")
        ref = np.array([d.min(), d.max()])
        k = np.median(slow[sel] / d)
        ax2.loglog(ref, k * ref, "k-", lw=0.7, label=f"v = {k:.3f}·d (slope 1)")
        k2 = np.median(slow[sel] / np.sqrt(d))
        ax2.loglog(ref, k2 * np.sqrt(ref), "k--", lw=0.7, label="slope 1/2 (not the law)")
        ax2.set_xlabel(f"distance d = |{param} − {at:.6f}|")
        ax2.set_ylabel("new impact speed v")
        ax2.legend(fontsize=8)
    fig.suptitle(f"{a.title or a.branch}: a branch through a grazing (filled: stable, open: unstable)", fontsize=10)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)


if __name__ == "__main__":
    main()
