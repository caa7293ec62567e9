#!/usr/bin/env bash
# Makes every picture of docs/figures/ (shown in README.md and docs/figures.md): the paper's
# continuation figures (Figs. 8, 9, 12, 13), the multi-DOF phenomena of Figs. 14-17 on our own
# 2-DOF chain, the Fig. 5 basins and a sweep over a continuation branch.
# Usage: scripts/paper_figures.sh [BUILD_DIR]   (about 4 minutes on 2 cores)
# docs/figures.md quotes the `run` lines below as commands; a test (docs.links) checks they agree.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
vibro=${1:-$root/build}/vibro
out=$root/docs/figures
# The HDF5 files go to a temporary directory, or are kept in $VIBRO_FIGURES_WORK when it is set.
if [ -n "${VIBRO_FIGURES_WORK:-}" ]; then
  tmp=$VIBRO_FIGURES_WORK
  mkdir -p "$tmp"
else
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
fi
mkdir -p "$out"
S=$root/data/scenes
run() { echo "+ vibro $*" >&2; "$vibro" "$@" > /dev/null; }
# fig NAME PANEL: plot $tmp/NAME.h5 and keep its PANEL picture as docs/figures/NAME.png.
fig() { run plot "$tmp/$1.h5"; cp "$tmp/$1_$2.png" "$out/$1.png"; }

# Fig. 8: 1-DOF preload, r = 0.75, ω = 2.8: sticking fraction against f, from f → 1⁺ to f_max.
run continue "$S/fig08_preload.toml" --set excitation.amplitude=1.001 --param excitation.amplitude \
  --to 1.4 --out "$tmp/fig08.h5"
run plot "$tmp/fig08.h5"
cp "$tmp/fig08_branch.png" "$out/fig08.png"
# Its contact loads along the branch (docs/loads.md): mean force and normal work rate.
cp "$tmp/fig08_branch_loads.png" "$out/fig08_loads.png"
# Fig. 9: its (ω, f) partition.
run partition "$S/fig08_preload.toml" --params excitation.frequency,excitation.amplitude \
  --range1 1.0,20 --steps1 60 --range2 1,12 --from2 1.02 \
  --sticking-fraction 0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.9 --out "$tmp/fig09.h5"
run plot "$tmp/fig09.h5"
cp "$tmp/fig09_partition.png" "$out/fig09.png"
# The wear-power map of the same partition (docs/loads.md): normal work rate over (ω, f).
cp "$tmp/fig09_partition_loads.png" "$out/fig09_wear.png"
# Fig. 12: 1-DOF clearance, r = 0, ω = 1.4: from f = 40 down to f_min = 2.0204 (docs/model.md
# §6.3), where the sticking phase is lost.
run continue "$S/fig11_clearance.toml" --set excitation.amplitude=40 --param excitation.amplitude \
  --to 2 --step 0.2 --out "$tmp/fig12.h5"
fig fig12 branch
# Fig. 13: the clearance (ω, f) partition.
run partition "$S/fig11_clearance.toml" --params excitation.frequency,excitation.amplitude \
  --range1 1.0,4 --steps1 40 --range2 1,40 --from2 10 \
  --sticking-fraction 0.05,0.1,0.2,0.3,0.4 --out "$tmp/fig13.h5"
fig fig13 partition
# Figs. 15, 17 on the 2-DOF chain, r = 0, ω = 0.4: a rising bifurcation and the sharp drop of the
# sticking fraction after it; the (ω, f) partition whose curves stop at rising bifurcations.
run continue "$S/chain2.toml" --set stop.restitution=0.0 --set excitation.frequency=0.4 \
  --set excitation.amplitude=1.0 --param excitation.amplitude --to 1.3 --out "$tmp/chain2_rising.h5"
fig chain2_rising branch
run partition "$S/chain2.toml" --set stop.restitution=0.0 \
  --params excitation.frequency,excitation.amplitude --range1 0.3,0.5 --steps1 20 --range2 0.9,2 \
  --from2 1.0 --sticking-fraction 0.6,0.65,0.7,0.75,0.8 --out "$tmp/chain2_partition.h5"
fig chain2_partition partition
# Fig. 14: a Neimark-Sacker point on the 2-DOF sticking branch and the quasi-periodic sticking
# motion (stroboscopic section on an invariant circle) just past it.
run continue "$S/chain2.toml" --set stop.restitution=0.0 --set excitation.frequency=0.4 \
  --set excitation.amplitude=1.5 --param excitation.amplitude --to 1.3 --out "$tmp/chain2_ns.h5"
fig chain2_ns branch
run simulate "$S/chain2.toml" --set stop.restitution=0.0 --set excitation.frequency=0.4 \
  --set excitation.amplitude=1.3495 --set run.periods=4000 --set run.samples_per_period=64 \
  --set initial.time=3.75 \
  --out "$tmp/chain2_torus.h5"
fig chain2_torus section
# Fig. 5: basins of the sticking orbit and the single-impact orbits.
run basin "$S/fig05_coexistence.toml" --grid 512,512 --set run.periods=100 --out "$tmp/fig05_basin.h5"
fig fig05_basin basin
# A brute-force sweep across f_free-flight (1-DOF, r = 0, ω = 2.8) with the continuation branch.
run sweep "$S/fig08_preload.toml" --set stop.restitution=0.0 --param excitation.amplitude \
  --from 1.5 --to 6.5 --steps 50 --out "$tmp/fig08_sweep.h5"
run continue "$S/fig08_preload.toml" --set stop.restitution=0.0 --set excitation.amplitude=1.5 \
  --param excitation.amplitude --to 6.5 --out "$tmp/fig08_branch.h5"
run plot "$tmp/fig08_sweep.h5" --overlay "$tmp/fig08_branch.h5"
cp "$tmp/fig08_sweep_sweep.png" "$out/fig08_sweep.png"
ls -1 "$out"
