#!/usr/bin/python3
"""Fig. 5 of Toulemonde & Gontier (1998): the basins of the two coexisting period-1 orbits at
(r, ω, f, x0) = (0.75, 10, 1.1, 1): the sticking orbit with chattering (Fig. 5b) and the
single-impact orbit (Fig. 5a), over initial contact displacement x_B and velocity v_B.

    examples/fig05_basin.py [--grid N] [--out fig05_basin.png]

--grid 256 takes about 10 s on 2 cores; CI runs --grid 16.
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
p.add_argument("--grid", type=int, default=int(os.environ.get("VIBRO_EXAMPLE_GRID", 128)))
p.add_argument("--out", default="fig05_basin.png")
p.add_argument("--scene", default=os.path.join(here, "..", "data", "scenes", "fig05_coexistence.toml"))
args = p.parse_args()

scene = vibro.load_scene(args.scene, set={"run.periods": 100})
b = vibro.basin(scene, grid=(args.grid, args.grid))

fig, ax = plt.subplots(figsize=(6.4, 6.0))
colours = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"]
rgb = np.full(b["labels"].shape + (3,), 0.85)  # grey: unresolved
rgb[b["labels"] == -2] = 1.0                     # white: inside the stop
for k, a in enumerate(b["attractors"]):
    rgb[b["labels"] == k] = matplotlib.colors.to_rgb(colours[k % len(colours)])
    what = f"period {a['period']} {a['kind']}"
    if a.get("impacts_per_period"):
        what += f", {a['impacts_per_period']} impact(s)/period"
    if a.get("sticking_fraction"):
        what += f", SP = {a['sticking_fraction']:.3f}"
    ax.plot([], [], "s", color=colours[k % len(colours)], label=f"{what}: {100 * a['basin_fraction']:.1f} %")
ax.imshow(rgb, origin="lower", extent=b["extent"], aspect="auto", interpolation="nearest")
ax.set_xlabel("initial $x_B$")
ax.set_ylabel("initial $\\dot x_B$")
ax.set_title(f"{scene.title}\nbasins on a {args.grid}×{args.grid} grid (grey: unresolved, white: inside the stop)",
             fontsize=9)
ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=1, fontsize=8)
fig.tight_layout()
fig.savefig(args.out, dpi=120)
print(f"{args.out}: {len(b['attractors'])} attractors, unresolved {b['unresolved_fraction']:.3f}")
for a in b["attractors"]:
    print(f"  {a['kind']:<20} period {a['period']}  basin {a['basin_fraction']:.3f} ± {a['basin_fraction_error']:.3f}"
          f"  stable {a['stable']}")
