#!/usr/bin/python3
"""The events of a run stored by `vibro simulate --out FILE.h5` as the CSV `vibro score` reads.

    scripts/events_to_csv.py RUN.h5 [OUT.csv]     (in a checkout)
    vibro-events-to-csv RUN.h5 [OUT.csv]     (installed by `cmake --install`)

Columns t, kind, velocity (contact velocity just before the event), 17 significant digits.
Writes to stdout without OUT.csv. Exit 2 when the file holds no events.
"""
import sys

import h5py

KINDS = {1: "impact", 2: "accumulation", 3: "stick", 4: "release", 5: "grazing"}


def rows(path):
    """(t, kind, v_before) of every event in the run file."""
    with h5py.File(path, "r") as f:
        ev = f["events"]
        return list(zip(ev["t"][()], (KINDS[int(k)] for k in ev["kind"][()]), ev["v_before"][()]))


def write(events, out):
    out.write("t,kind,velocity\n")
    for t, kind, v in events:
        out.write(f"{float(t):.17g},{kind},{float(v):.17g}\n")


def main(argv):
    if len(argv) not in (2, 3):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    try:
        events = rows(argv[1])
    except (OSError, KeyError) as e:
        print(f"{argv[1]}: not a vibro run with events: {e}", file=sys.stderr)
        return 2
    if len(argv) == 3:
        with open(argv[2], "w") as out:
            write(events, out)
    else:
        write(events, sys.stdout)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
