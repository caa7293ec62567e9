#!/usr/bin/python3
"""Histogram of |t_double - t_quad| / T over the matched events of a random search
(random_search.py --stats DT.npy), for docs/contacts.md.

    search_histogram.py DT.npy OUT.png [--title TEXT]
"""
import argparse

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("stats")
    ap.add_argument("out")
    ap.add_argument("--title", default="")
    args = ap.parse_args(argv)
    a = np.load(args.stats)
    equal = int(np.count_nonzero(a == 0))
    pos = a[a > 0]
    fig, ax = plt.subplots(figsize=(7, 4))
    bins = np.logspace(-18, -6, 49)
    ax.hist(np.clip(pos, bins[0], None), bins=bins, color="#4477aa")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axvline(1e-7, color="#cc3311", ls="--", lw=1)
    ax.text(1e-7, ax.get_ylim()[1] * 0.5, "tolerance 1e-7 T ", color="#cc3311", va="top", ha="right")
    ax.set_xlabel("|t_double − t_quad| / T  (per matched event of the scenes that pass)")
    ax.set_ylabel("events")
    ax.set_title(args.title or f"{a.size} events matched, {equal} equal to the bit (not shown), "
                 f"median {np.median(a):.1g}, largest {a.max():.1g}", fontsize=9)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
