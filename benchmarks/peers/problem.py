#!/usr/bin/python3
"""The impact oscillator of a vibro scene, in modal coordinates, for the peers (docs/model.md §1,
§7; several contacts: docs/contacts.md "The modal form").

Built from what `vibro model --json SCENE` prints (ω_i, T_A, T_B, ζ_i in the paper's scaling, and
the mode shapes ψ_i of a physical scene) and the scene's contacts, excitation and initial state:

    Ẍ + D Ẋ + Ω X = T_A f sin ωt + Σ_j T_j λ_j,    g_j = c_jᵀX − e_j ≥ 0,  λ_j ≥ 0,  g_j λ_j = 0
    D = diag(2ζ_iω_i),  T_j = c_j ∘ T_B (modal masses μ_i = 1/T_B,i),  W_jk = c_jᵀT_k (Delassus)

A `[stop]` is the one contact c = 1 (x_B = 1ᵀX, the paper's scaling), e = x0. A `[[contact]]` j
of a physical scene has c_j,i = σ_j w_jᵀψ_i (w_j = e_b for `dof = b`, e_b − e_a for
`dofs = [b, a]`; σ = +1 below, −1 above) and e_j = σ_j d_j; of a modal scene c_j = σ_j·modal_j
(contact 0: c = 1). Impacts follow the generalised Newton law (an LCP on the contacts at zero
gap, docs/contacts.md), sticking the constrained flow with W_SS λ_S = −C_S(a + ...) that keeps
g̈_S = 0.

The same system for Siconos is a LagrangianLinearTIDS with M = diag(1/T_B), K = diag(ω²/T_B),
C = diag(2ζω/T_B), force (T_A/T_B) f sin ωt and one LagrangianLinearTIR y_j = c_jᵀX − e_j per
contact (its multiplier enters M Ẍ as c_j λ_j, so Ẍ gets T_j λ_j).

The initial state is the scene's ([initial], modal X or physical q = ΦX), else vibro's default:
the static preload equilibrium on the stop, X_i = x0 (T_B,i/ω_i²)/Σ_j(T_B,j/ω_j²), for x0 > 0,
the origin at rest otherwise.

A Problem is plain data (to_dict/from_dict): run_all.py builds it once from vibro and hands it to
each peer process as JSON, so the peers' processes do not run vibro.
"""
import itertools
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


class Problem:
    FIELDS = ("scene", "label", "w", "TA", "TB", "zeta", "C", "e", "r", "f", "omega", "periods", "X0", "V0")

    @classmethod
    def from_vibro(cls, vibro, scene, label=None, periods=None):
        from bench_common import scene_values, vibro_model  # noqa: PLC0415
        model = vibro_model(vibro, scene)
        values = scene_values(scene)
        if not all(model.get("contact_modes", [True] * len(model["frequencies"]))):
            raise ValueError(f"{scene}: modes with a node at the first contact are not supported by the peers")
        p = cls()
        p.scene, p.label = scene, label or scene
        p.w = np.array(model["frequencies"], dtype=float)
        p.TA = np.array(model["forcing"], dtype=float)
        p.TB = np.array(model["contact"], dtype=float)
        p.zeta = np.array(model.get("damping_ratios") or [0.0] * len(p.w), dtype=float)
        n = len(p.w)
        physical = "mode_shapes" in model
        phi = np.array(model["mode_shapes"], dtype=float).T if physical else None  # columns ψ_i
        if "stop" in values:
            p.C, p.e = np.ones((1, n)), np.array([float(values["stop"]["position"])])
            p.r = np.array([float(values["stop"]["restitution"])])
        else:
            rows, e, r = [], [], []
            for j, c in enumerate(values["contact"]):
                sigma = 1.0 if c.get("side", "below") == "below" else -1.0
                if physical:
                    wv = np.zeros(phi.shape[0])
                    if "dof" in c:
                        wv[c["dof"]] = 1.0
                    else:
                        b, a = c["dofs"]
                        wv[b], wv[a] = 1.0, -1.0
                    rows.append(sigma * (wv @ phi))
                else:
                    rows.append(np.ones(n) if j == 0 else sigma * np.array(c["modal"], dtype=float)[:n])
                e.append(sigma * float(c["position"]))
                r.append(float(c["restitution"]))
            p.C, p.e, p.r = np.array(rows), np.array(e), np.array(r)
            if np.max(np.abs(p.C[0] - 1.0)) > 1e-9:
                raise ValueError(f"{scene}: contact 0 does not see every mode with unit weight: {p.C[0]}")
        p.f = float(values["excitation"]["amplitude"])
        p.omega = float(values["excitation"]["frequency"])
        p.periods = int(periods or values.get("run", {}).get("periods", 200))
        if "initial" in values:
            q0 = np.array(values["initial"]["displacement"], dtype=float)
            v0 = np.array(values["initial"].get("velocity", [0.0] * len(q0)), dtype=float)
            if physical:
                if phi.shape[0] != phi.shape[1]:
                    raise ValueError(f"{scene}: a physical initial state with truncated modes")
                p.X0, p.V0 = np.linalg.solve(phi, q0), np.linalg.solve(phi, v0)
            else:
                p.X0, p.V0 = q0, v0
        else:
            x0 = float(p.e[0])
            if x0 > 0:
                flex = p.TB / p.w ** 2
                p.X0 = x0 * flex / flex.sum()
            else:
                p.X0 = np.zeros(n)
            p.V0 = np.zeros(n)
        p._derive()
        return p

    def to_dict(self):
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in
                ((k, getattr(self, k)) for k in self.FIELDS)}

    @classmethod
    def from_dict(cls, d):
        p = cls()
        for k in cls.FIELDS:
            v = d[k]
            setattr(p, k, np.array(v, dtype=float) if isinstance(v, list) else v)
        p._derive()
        return p

    def _derive(self):
        self.n, self.m = len(self.w), len(self.e)
        self.T = 2 * math.pi / self.omega
        self.t_end = self.periods * self.T
        self.D = 2 * self.zeta * self.w
        self.Tc = self.C * self.TB  # rows T_j = c_j ∘ T_B
        self.W = self.C @ self.Tc.T  # Delassus matrix
        self.damped = bool(np.any(self.zeta > 0))
        self.sA = float(self.TA.sum())
        self.w2 = self.w ** 2

    # --- free dynamics and the contact quantities ------------------------------------------
    def force(self, t):
        return self.f * math.sin(self.omega * t)

    def acc_free(self, t, X, V):
        return -self.w2 * X - self.D * V + self.TA * self.force(t)

    def gaps(self, X):
        return self.C @ X - self.e

    def reactions(self, S, t, X, V):
        """λ_S that keeps g̈_j = 0 for j in S (a list): W_SS λ = −C_S a."""
        a = self.acc_free(t, X, V)
        return np.linalg.solve(self.W[np.ix_(S, S)], -(self.C[S] @ a))

    def acc_held(self, S, t, X, V):
        a = self.acc_free(t, X, V)
        if not S:
            return a
        lam = np.linalg.solve(self.W[np.ix_(S, S)], -(self.C[S] @ a))
        return a + self.Tc[S].T @ lam

    def held_operators(self, S):
        """For a held set S (a list): (R, P) with λ_S = R a and the held acceleration a + P a, R = −W_SS⁻¹ C_S
        and P = T_Sᵀ R: what reactions() and acc_held() compute, factored once per held set rather than
        at every right-hand side."""
        R = -np.linalg.solve(self.W[np.ix_(S, S)], self.C[S])
        return R, self.Tc[S].T @ R

    def onto_stops(self, X, Z):
        """X moved along the T_j of Z so that g_j = 0 exactly for j in Z (the impulsive directions)."""
        if not Z:
            return X
        g = self.C[Z] @ X - self.e[Z]
        return X - self.Tc[Z].T @ np.linalg.solve(self.W[np.ix_(Z, Z)], g)

    # --- the same system as Lagrangian matrices (modal masses 1/T_B,i) ----------------------
    def lagrangian(self):
        m = 1.0 / self.TB
        return np.diag(m), np.diag(self.w ** 2 * m), np.diag(self.D * m), self.TA * m


def solve_lcp(M, q):
    """The solution z of the LCP w = M z + q, z ≥ 0, w ≥ 0, zᵀw = 0 for a small P-matrix M, by
    enumerating the index sets (exact at working precision; unique for a P-matrix)."""
    k = len(q)
    best = None
    for size in range(k + 1):
        for active in itertools.combinations(range(k), size):
            z = np.zeros(k)
            if active:
                idx = list(active)
                z[idx] = np.linalg.solve(M[np.ix_(idx, idx)], -q[idx])
            w = M @ z + q
            viol = max(0.0, -z.min(initial=0.0), -w.min(initial=0.0))
            if viol <= 1e-14 * (1.0 + np.abs(q).max()):
                return z
            if best is None or viol < best[0]:
                best = (viol, z)
    return best[1]


class PeerResult:
    """What a peer run gives back: stick/release milestones (kinds 3/4 as vibro's HDF5) with their
    contacts, the state at t_end (None when the run did not get there), a status, impacts, CPU."""

    def __init__(self):
        self.times, self.kinds, self.contacts = [], [], []
        self.end = None
        self.status = "ok"
        self.impacts = 0
        self.cpu = float("nan")
        self.t_reached = 0.0
        self.sp_steps = float("nan")

    def stick(self, t, j=0):
        self.times.append(t)
        self.kinds.append(3)
        self.contacts.append(j)

    def release(self, t, j=0):
        self.times.append(t)
        self.kinds.append(4)
        self.contacts.append(j)

    def to_dict(self):
        return {"times": self.times, "kinds": self.kinds, "contacts": self.contacts,
                "end": None if self.end is None else [np.asarray(self.end[0]).tolist(), np.asarray(self.end[1]).tolist()],
                "status": self.status, "impacts": self.impacts, "cpu": self.cpu, "t_reached": self.t_reached,
                "sp_steps": self.sp_steps}
