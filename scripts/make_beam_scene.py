#!/usr/bin/python3
"""Writes data/scenes/large/beam50.toml: a simply supported Euler–Bernoulli beam discretised by finite
differences into 50 interior nodes (unit lumped masses, K = (EI/h³) D2ᵀ D2 with D2 the second
difference, pinned ends), modal damping, forced at node 26 and hitting a stop at node 19.

    scripts/make_beam_scene.py [--out data/scenes/large/beam50.toml]

Its modes are the discrete sines φ_k(j) = sin(kπ j/51) with ω_k ∝ 4 sin²(kπ/102): neither node 19
nor node 26 (1-based) is a node of any of the 50 modes (51 = 3·17 divides neither 19k nor 26k), so
the contact sees every mode. EI/h³ is set so that ω_1 = 1: ω_50/ω_1 ≈ 1054.
"""
import argparse
import math
import os

N = 50
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def stiffness():
    # D2: (N x N) second difference with pinned ends (w_0 = w_{N+1} = 0, moment zero at the ends).
    d2 = [[0.0] * N for _ in range(N)]
    for i in range(N):
        d2[i][i] = -2.0
        if i > 0:
            d2[i][i - 1] = 1.0
        if i < N - 1:
            d2[i][i + 1] = 1.0
    # K = c D2ᵀ D2 with c such that ω_1² = c (2 − 2 cos(π/51))² = 1.
    c = 1.0 / (2.0 - 2.0 * math.cos(math.pi / (N + 1))) ** 2
    return [[c * sum(d2[k][i] * d2[k][j] for k in range(N)) for j in range(N)] for i in range(N)]


def row(values):
    return "[" + ", ".join(f"{v:.17g}" for v in values) + "]"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "data", "scenes", "large", "beam50.toml"))
    a = ap.parse_args()
    K = stiffness()
    lines = [
        "# A simply supported beam discretised into 50 interior nodes (finite differences, unit lumped",
        "# masses), 2 % modal damping, forced at node 26 and hitting a stop at node 19 (1-based; the",
        "# 0-based indices below); the stop is 0.05 below node 19 at rest (clearance). Written by",
        "# scripts/make_beam_scene.py: omega_1 = 1, omega_50 = 1054.",
        "# The cost per event against the number of modes kept (structure.modes) is on",
        "# docs/performance.md.",
        'title = "50-node beam, stop at an interior node, 2 % modal damping"',
        "",
        "[structure]",
        "mass = [" + ", ".join(row([1.0 if i == j else 0.0 for j in range(N)]) for i in range(N)) + "]",
        "stiffness = [" + ", ".join(row(K[i]) for i in range(N)) + "]",
        "forcing_dof = 25",
        "contact_dof = 18",
        "damping_ratios = " + row([0.02] * N),
        "",
        "[stop]",
        "position    = -0.05",
        "restitution = 0.7",
        "",
        "[excitation]",
        "amplitude = 1.0",
        "frequency = 0.8",
        "",
        "[run]",
        "periods = 50",
        "",
    ]
    with open(a.out, "w") as f:
        f.write("\n".join(lines))


if __name__ == "__main__":
    main()
