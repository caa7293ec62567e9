#!/usr/bin/python3
"""A branch stored by `vibro continue --out FILE.h5` as the CSV `vibro validate` reads.

    scripts/branch_to_csv.py BRANCH.h5 [OUT.csv]     (in a checkout)
    vibro-branch-to-csv BRANCH.h5 [OUT.csv]     (installed by `cmake --install`)

Columns: value, time (the section time of each point), displacement_1..n and velocity_1..n in the
scene's [initial] convention (physical DOFs q, q_dot for a physical scene, modal X, V otherwise),
period, stable, sticking_fraction (empty when the orbit does not stick), and sequence (each
point's contact sequence, when the branch is of a scene with several contacts: /branch/sequence
holds a non-empty entry), then strobe_0..strobe_{m-1} (each contact's coordinate at the start's
forcing phase, /branch/strobe: for plots; `vibro validate` claims nothing from them, only checks them as numbers; a NaN is written empty). Writes to stdout without OUT.csv. Exit 2 when the file holds no branch
with orbit states.
"""
import csv
import sys

import h5py
import numpy as np


def main(argv):
    if len(argv) not in (2, 3):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    try:
        with h5py.File(argv[1], "r") as f:
            b = f["branch"]
            value, t0 = b["value"][()], b["section_time"][()]
            x, v = (b["q"][()], b["q_dot"][()]) if "q" in b else (b["X"][()], b["V"][()])
            stable, sp = b["stable"][()], b["sticking_fraction"][()]
            period = int(b.attrs["period"])
            strobe = b["strobe"][()] if "strobe" in b else None  # (N, contacts); absent in older files
            sequence = None
            if "sequence" in b:
                sequence = [s.decode() if isinstance(s, bytes) else str(s) for s in b["sequence"][()]]
                if not any(sequence):
                    sequence = None
    except (OSError, KeyError) as e:
        print(f"{argv[1]}: not a branch with orbit states (vibro continue --out): {e}", file=sys.stderr)
        return 2
    out = open(argv[2], "w", newline="") if len(argv) == 3 else sys.stdout
    w = csv.writer(out, lineterminator="\n")
    n = x.shape[1]
    w.writerow(["value", "time"] + [f"displacement_{i + 1}" for i in range(n)]
               + [f"velocity_{i + 1}" for i in range(n)] + ["period", "stable", "sticking_fraction"]
               + (["sequence"] if sequence else [])
               + ([f"strobe_{j}" for j in range(strobe.shape[1])] if strobe is not None else []))
    for i in range(len(value)):
        w.writerow([repr(float(value[i])), repr(float(t0[i]))] + [repr(float(a)) for a in x[i]]
                   + [repr(float(a)) for a in v[i]]
                   + [period, int(stable[i]), "" if np.isnan(sp[i]) else repr(float(sp[i]))]
                   + ([sequence[i]] if sequence else [])
                   + (["" if np.isnan(a) else repr(float(a)) for a in strobe[i]] if strobe is not None else []))
    if out is not sys.stdout:
        out.close()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
