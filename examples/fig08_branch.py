#!/usr/bin/python3
"""Fig. 8 of Toulemonde & Gontier (1998): the period-1 sticking orbit of the 1-DOF oscillator with
preload (x0 = 1, r = 0.75, ω = 2.8) continued in the forcing amplitude f, its sticking fraction
SP (stable solid, unstable dashed) and its bifurcations; and a simulation at each end of the
branch as a check that the continued orbit is the motion one actually sees.

    examples/fig08_branch.py [--to 1.4] [--out fig08_branch.png]
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import vibro  # noqa: E402

here = os.path.dirname(os.path.abspath(__file__))
p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
p.add_argument("--to", type=float, default=1.4, help="last amplitude f (default 1.4)")
p.add_argument("--out", default="fig08_branch.png")
p.add_argument("--scene", default=os.path.join(here, "..", "data", "scenes", "fig08_preload.toml"))
args = p.parse_args()

# The branch starts just above f = 1, where the preload is first overcome (MODEL §6.1).
scene = vibro.load_scene(args.scene, set={"excitation.amplitude": 1.001})
branch = vibro.continue_(scene, "excitation.amplitude", args.to)
t = branch["table"]

fig, ax = plt.subplots(figsize=(6.4, 4.4))
# Stable stretches solid, unstable dashed.
start = 0
for i in range(1, len(t) + 1):
    if i == len(t) or t["stable"][i] != t["stable"][start]:
        seg = slice(start, min(i + 1, len(t)))
        ax.plot(t["value"][seg], t["sticking_fraction"][seg], "-" if t["stable"][start] else "--", color="k")
        start = i
for b in branch["bifurcations"]:
    sp = np.interp(b["value"], t["value"], t["sticking_fraction"])
    ax.plot(b["value"], sp, "o", label=f"{b['kind']} at f = {b['value']:.5f}")

# Check: simulations at a few amplitudes settle on the branch's sticking fraction.
for f in np.linspace(t["value"][0], t["value"][-1], 4)[1:]:
    run = vibro.simulate(scene.with_({"excitation.amplitude": float(f), "run.periods": 100,
                                      "run.samples_per_period": 0}))
    sp = run.summary["attractor"].get("sticking_fraction")
    if sp is not None:
        ax.plot(f, sp, "x", color="tab:red", ms=8)
ax.plot([], [], "x", color="tab:red", label="simulation (100 periods)")
ax.set_xlabel("forcing amplitude $f$")
ax.set_ylabel("sticking fraction SP")
ax.set_title(f"Fig. 8: period-1 sticking orbit, r = 0.75, ω = 2.8, x0 = 1\nbranch end: {branch['end']}", fontsize=9)
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(args.out, dpi=120)
print(f"{args.out}: {len(t)} points from f = {t['value'][0]:.4g} to {t['value'][-1]:.4g}; "
      f"{len(branch['bifurcations'])} bifurcation(s); end: {branch['end']}")
