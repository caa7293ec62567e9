#!/usr/bin/python3
"""Seeded random multi-contact scenes for the quad-against-double test (docs/contacts_reference.md).

    random_scenes.py OUTDIR [--count 240] [--seed 1] [--periods 4] [--reference N]

Writes OUTDIR/random_NNN.toml: 1-3 DOF (lumped chains with random masses and springs, so M and K
are symmetric positive definite), 1-4 contacts drawn among stops below / above a DOF and impact
pairs between two DOFs, with preload (the spring's rest position violates a stop below) and
clearance, restitutions in [0, 0.95) (a quarter plastic), damped (modal ratios up to 5 %) and
undamped. Every scene is admissible for the [[contact]] rules: no pair on one DOF, no two
contacts with the same DOFs and side, a two-sided clearance on one coordinate has lower < upper,
and the initial state (given explicitly, in free flight) is at least 1e-3 inside every gap.
With --reference N, also runs reference.py on the first N scenes (OUTDIR/random_NNN.csv).
Deterministic: the same seed gives the same files, byte for byte.
"""
import argparse
import os
import random
import sys


def chain(rng, n):
    """Lumped chain ground - k0 - m0 - k1 - m1 ... with an extra spring to ground at each mass
    (so that the stiffness is positive definite whatever the pairs do)."""
    m = [round(rng.uniform(0.5, 2.0), 3) for _ in range(n)]
    k_series = [round(rng.uniform(0.5, 3.0), 3) for _ in range(n)]
    k_ground = [round(rng.uniform(0.0, 0.5), 3) for _ in range(n)]
    K = [[0.0] * n for _ in range(n)]
    for i in range(n):
        K[i][i] += k_series[i] + k_ground[i]
        if i > 0:
            K[i][i - 1] -= k_series[i]
            K[i - 1][i] -= k_series[i]
            K[i - 1][i - 1] += k_series[i]
    M = [[m[i] if i == j else 0.0 for j in range(n)] for i in range(n)]
    return M, K


def fmt_matrix(A):
    return "[" + ", ".join("[" + ", ".join(repr(round(x, 6)) for x in row) + "]" for row in A) + "]"


def contacts(rng, n, count):
    """Draws `count` distinct contacts; returns tables (dofs, side, position, restitution)."""
    out, keys = [], set()
    tries = 0
    while len(out) < count and tries < 200:
        tries += 1
        if n >= 2 and rng.random() < 0.3:
            b, a = rng.sample(range(n), 2)
            dofs = (b, a)
        else:
            dofs = (rng.randrange(n),)
        side = rng.choice(["below", "above"])
        key = (tuple(sorted(dofs)) if len(dofs) == 2 else dofs, side if len(dofs) == 1 or dofs[0] < dofs[1] else
               {"below": "above", "above": "below"}[side])
        if key in keys:
            continue
        # preload (a stop below with position > 0, i.e. the rest position violates it) in a
        # third of the one-DOF stops, else a clearance
        if len(dofs) == 1 and rng.random() < 0.33:
            mag = rng.uniform(0.05, 0.8)
            position = mag if side == "below" else -mag
        else:
            gap = rng.uniform(0.05, 1.0)
            position = -gap if side == "below" else gap
        r = 0.0 if rng.random() < 0.25 else rng.uniform(0.0, 0.95)
        out.append((dofs, side, round(position, 4), round(r, 3)))
        keys.add(key)
    # a two-sided clearance on one coordinate needs lower < upper
    coords = {}
    for dofs, side, pos, r in out:
        coord = dofs if len(dofs) == 1 or dofs[0] < dofs[1] else (dofs[1], dofs[0])
        sign = 1 if len(dofs) == 1 or dofs[0] < dofs[1] else -1
        lo_hi = coords.setdefault(coord, [None, None])
        s = side if sign == 1 else {"below": "above", "above": "below"}[side]
        lo_hi[0 if s == "below" else 1] = pos * sign
    for lo, hi in coords.values():
        if lo is not None and hi is not None and not lo + 0.05 < hi:
            return None
    return out


def gaps_ok(cs, q, margin=1e-3):
    for dofs, side, pos, r in cs:
        x = q[dofs[0]] - (q[dofs[1]] if len(dofs) == 2 else 0.0)
        g = x - pos if side == "below" else pos - x
        if g < margin:
            return False
    return True


def scene(rng, index, periods):
    while True:
        n = rng.randint(1, 3)
        M, K = chain(rng, n)
        cs = contacts(rng, n, rng.randint(1, 4))
        if not cs:
            continue
        # an initial state inside every gap (rejection sampling in a box)
        for _ in range(500):
            q = [round(rng.uniform(-1.5, 1.5), 4) for _ in range(n)]
            if gaps_ok(cs, q):
                break
        else:
            continue
        v = [round(rng.uniform(-0.5, 0.5), 4) for _ in range(n)]
        damped = rng.random() < 0.5
        zeta = [round(rng.uniform(0.0, 0.05), 4) for _ in range(n)] if damped else None
        f = round(rng.uniform(0.2, 3.0), 3)
        omega = round(rng.uniform(0.3, 4.0), 3)
        lines = [f"# random multi-contact scene {index} (tests/reference/contacts/random_scenes.py)",
                 f'title = "random {index}: {n} DOF, {len(cs)} contacts{", damped" if damped else ""}"',
                 "", "[structure]", f"mass        = {fmt_matrix(M)}", f"stiffness   = {fmt_matrix(K)}",
                 f"forcing_dof = {rng.randrange(n)}"]
        if zeta:
            lines.append(f"damping_ratios = {zeta!r}")
        for dofs, side, pos, r in cs:
            lines += ["", "[[contact]]",
                      (f"dof         = {dofs[0]}" if len(dofs) == 1 else f"dofs        = [{dofs[0]}, {dofs[1]}]"),
                      f'side        = "{side}"', f"position    = {pos!r}", f"restitution = {r!r}"]
        lines += ["", "[excitation]", f"amplitude = {f!r}", f"frequency = {omega!r}",
                  "", "[initial]", f"displacement = {q!r}", f"velocity     = {v!r}",
                  "", "[run]", f"periods = {periods}", ""]
        return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir")
    ap.add_argument("--count", type=int, default=240)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--periods", type=int, default=4)
    ap.add_argument("--reference", type=int, default=0, help="also run reference.py on the first N scenes")
    args = ap.parse_args(argv)
    os.makedirs(args.outdir, exist_ok=True)
    rng = random.Random(args.seed)
    paths = []
    for i in range(args.count):
        path = os.path.join(args.outdir, f"random_{i:03d}.toml")
        with open(path, "w") as fh:
            fh.write(scene(rng, i, args.periods))
        paths.append(path)
    print(f"{len(paths)} scenes in {args.outdir}")
    if args.reference:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import reference
        for path in paths[:args.reference]:
            code = reference.main([path, "--out", path.replace(".toml", ".csv")])
            print(f"{os.path.basename(path)}: reference exit {code}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
