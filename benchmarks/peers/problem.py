#!/usr/bin/python3
"""The impact oscillator of a vibro scene, in modal coordinates, for the peers (docs/model.md §1, §7).

Built from what `vibro model --json SCENE` prints (ω_i, T_A, T_B, ζ_i in the paper's scaling) and
the scene's stop, excitation and run.periods:

    free:     Ẍ + D Ẋ + Ω X = T_A f sin ωt,        x_B = 1ᵀX ≥ x0,   D = diag(2ζ_iω_i)
    contact:  ... + T_B R,  R = (Σ_i(ω_i² X_i + 2ζ_iω_i Ẋ_i) − s_A f sin ωt)/s_B  (keeps ẍ_B = 0)
    impact:   Ẋ⁺ = Ẋ⁻ − (1 + r) T_B ẋ_B⁻/s_B

Equivalently, a Lagrangian system with the modal masses m_i = 1/T_B,i: M = diag(1/T_B),
K = diag(ω_i²/T_B,i), C = diag(2ζ_iω_i/T_B,i), force (T_A,i/T_B,i) f sin ωt and the unilateral
constraint 1ᵀX − x0 ≥ 0 whose multiplier enters as 1·λ (then Ẍ gets T_B λ), which is how the
Siconos peers see it. The initial state is vibro's default: the static preload equilibrium on the
stop, X_i = x0 (T_B,i/ω_i²)/Σ_j(T_B,j/ω_j²), for x0 > 0, the origin at rest otherwise.
"""
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from bench_common import scene_values, vibro_model  # noqa: E402


class Problem:
    def __init__(self, vibro, scene, label=None, periods=None):
        model = vibro_model(vibro, scene)
        values = scene_values(scene)
        if "initial" in values:
            raise ValueError(f"{scene}: the peers start from vibro's default initial state only")
        if not all(model.get("contact_modes", [True] * len(model["frequencies"]))):
            raise ValueError(f"{scene}: modes with a node at B are not supported by the peers")
        self.scene, self.label = scene, label or scene
        self.w = np.array(model["frequencies"], dtype=float)
        self.TA = np.array(model["forcing"], dtype=float)
        self.TB = np.array(model["contact"], dtype=float)
        self.zeta = np.array(model.get("damping_ratios", [0.0] * len(self.w)), dtype=float)
        self.n = len(self.w)
        self.sA, self.sB = float(self.TA.sum()), float(self.TB.sum())
        self.x0 = float(values["stop"]["position"])
        self.r = float(values["stop"]["restitution"])
        self.f = float(values["excitation"]["amplitude"])
        self.omega = float(values["excitation"]["frequency"])
        self.T = 2 * math.pi / self.omega
        self.periods = int(periods or values.get("run", {}).get("periods", 200))
        self.t_end = self.periods * self.T
        self.D = 2 * self.zeta * self.w
        if self.x0 > 0:
            flex = self.TB / self.w ** 2
            self.X0 = self.x0 * flex / flex.sum()
        else:
            self.X0 = np.zeros(self.n)
        self.V0 = np.zeros(self.n)
        self.damped = bool(np.any(self.zeta > 0))

    # --- free dynamics and the contact quantities ------------------------------------------
    def force(self, t):
        return self.f * math.sin(self.omega * t)

    def acc_free(self, t, X, V):
        return -self.w ** 2 * X - self.D * V + self.TA * self.force(t)

    def gap(self, X):
        return float(X.sum()) - self.x0

    def reaction(self, t, X, V):
        """The reaction that keeps ẍ_B = 0 (the paper's (5); docs/model.md §7)."""
        return (float(np.dot(self.w ** 2, X) + np.dot(self.D, V)) - self.sA * self.force(t)) / self.sB

    def acc_stuck(self, t, X, V):
        a = self.acc_free(t, X, V)
        return a - self.TB * (a.sum() / self.sB)

    def impact(self, V, r):
        """Velocities after an impact with restitution r (the paper's (12))."""
        return V - (1.0 + r) * self.TB * (V.sum() / self.sB)

    def onto_stop(self, X):
        """X moved along T_B so that x_B = x0 exactly (the impulsive direction)."""
        return X + self.TB * ((self.x0 - X.sum()) / self.sB)

    # --- the same system as Lagrangian matrices (modal masses 1/T_B,i) ----------------------
    def lagrangian(self):
        m = 1.0 / self.TB
        return np.diag(m), np.diag(self.w ** 2 * m), np.diag(self.D * m), self.TA * m


class PeerResult:
    """What a peer run gives back: stick/release milestones (kinds 3/4 as vibro's HDF5), the
    state at t_end (None when the run did not get there), a status, impacts, CPU seconds."""

    def __init__(self):
        self.times, self.kinds = [], []
        self.end = None
        self.status = "ok"
        self.impacts = 0
        self.cpu = float("nan")
        self.t_reached = 0.0

    def stick(self, t):
        self.times.append(t)
        self.kinds.append(3)

    def release(self, t):
        self.times.append(t)
        self.kinds.append(4)
