#!/usr/bin/python3
"""STOPGAP until `vibro continue --out` is on this branch (it is on main): writes the JSON of
`vibro continue --json` (stdin) as a continuation file in the layout of `continue --out`
(/branch: value, sticking_fraction, stable, x_B = NaN here, attribute param; /bifurcations:
value, kind), for `vibro plot SWEEP.h5 --overlay BRANCH.h5`. Remove after the rebase.

usage: vibro continue SCENE --param KEY --to B --json | branch_from_json.py KEY OUT.h5
"""
import json
import sys

import h5py
import numpy as np

param, out = sys.argv[1], sys.argv[2]
j = json.load(sys.stdin)
pts = j["points"]
with h5py.File(out, "w") as f:
    b = f.create_group("branch")
    b.attrs["param"] = param
    b["value"] = np.array([p["value"] for p in pts], dtype=float)
    b["sticking_fraction"] = np.array([np.nan if p["sticking_fraction"] is None else p["sticking_fraction"]
                                       for p in pts], dtype=float)
    b["stable"] = np.array([1 if p["stable"] else 0 for p in pts], dtype=np.uint8)
    b["x_B"] = np.full(len(pts), np.nan)
    g = f.create_group("bifurcations")
    g["value"] = np.array([x["value"] for x in j["bifurcations"]], dtype=float)
    g.create_dataset("kind", data=[x["kind"] for x in j["bifurcations"]], dtype=h5py.string_dtype())
