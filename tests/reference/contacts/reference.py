#!/usr/bin/python3
"""Independent event-driven reference for linear structures with several rigid unilateral contacts.

    M q'' + C q' + K q = b f sin(w t) + sum_j sigma_j w_j lambda_j,
    g_j = sigma_j (w_j^T q - d_j) >= 0,  lambda_j >= 0,  g_j lambda_j = 0,

C = modal damping (M Phi diag(2 zeta_i w_i) Phi^T M), w_j = e_b (a stop on DOF b) or e_b - e_a
(an impact pair, gap on q_b - q_a), sigma_j = +1 (stop below) / -1 (above), Newton restitution
r_j per contact. Written from docs/contacts_reference.md alone, in mpmath (default 40 digits),
sharing no code with vibro's C++.

Every phase (free flight, or sticking on an active set S) is linear with constant coefficients and
harmonic forcing, so it is solved in closed form by a complex eigen-decomposition of its
first-order form; every gap and every reaction is then an exponential sum
F(t0 + s) = F(t0) + Re sum_k A_k (exp(mu_k s) - 1), Re mu_k <= 0, and its p-th derivative is
bounded for all s >= 0 by M_p = sum_k |A_k| |mu_k|^p. Event location steps to the first root of
the cubic lower bound F + F' s + F'' s^2/2 - M_3 s^3/6 (the known zero at a flight's start is
divided out): no root is ever skipped.

Laws: impacts by the generalised Newton law (impact LCP on every contact at zero gap, closing or
resting), entry into sticking by the acceleration LCP, release when a reaction crosses zero
downwards, chattering by following impacts until the accumulation rule (the tail of a geometric
sequence with the first-order correction for a varying reaction) predicts the accumulation time
with an estimated error below `tail_target` * T, then the plastic tail impulse.

Usage: reference.py SCENE.toml [--out events.csv] [--dps 40] [--periods N]
CSV columns: t, kind, contact, v_before, v_after, simultaneous
(v = gap velocity dg_j/dt = sigma_j w_j^T q'; kinds impact, stick, release, accumulation, grazing,
and the rarer leave (a stuck contact pushed off by the acceleration LCP) and liftoff (a resting
contact pushed off by an impulse elsewhere)).
"""
import argparse
import csv
import math
import sys
import tomllib

import mpmath as mp


class SceneError(ValueError):
    pass


class Undetermined(RuntimeError):
    """A situation the laws do not decide (degenerate LCP, two contacts chattering to one point)."""


# ---------------------------------------------------------------------------------------------
# small dense linear algebra on lists of mpf / mpc (mpmath matrices are slow for tiny sizes)


def dot(a, b):
    return mp.fsum(x * y for x, y in zip(a, b))


def cdot(a, b):
    s = mp.mpc(0)
    for x, y in zip(a, b):
        s += x * y
    return s


def matvec(A, x):
    return [dot(row, x) for row in A]


def transpose(A):
    return [list(r) for r in zip(*A)] if A else []


def solve(A, b):
    """Gaussian elimination with partial pivoting (small systems)."""
    n = len(b)
    if n == 0:
        return []
    M = [list(A[i]) + [b[i]] for i in range(n)]
    for c in range(n):
        piv = max(range(c, n), key=lambda i: abs(M[i][c]))
        if M[piv][c] == 0:
            raise ZeroDivisionError("singular matrix")
        M[c], M[piv] = M[piv], M[c]
        for i in range(c + 1, n):
            f = M[i][c] / M[c][c]
            if f:
                for k in range(c, n + 1):
                    M[i][k] -= f * M[c][k]
    x = [0] * n
    for i in reversed(range(n)):
        x[i] = (M[i][n] - sum(M[i][k] * x[k] for k in range(i + 1, n))) / M[i][i]
    return x


def inverse(A):
    n = len(A)
    cols = [solve(A, [1 if i == j else 0 for i in range(n)]) for j in range(n)]
    return transpose(cols)


def em1(z):
    """exp(z) - 1 without cancellation: expm1(x) cos y - 2 sin^2(y/2) + i exp(x) sin y."""
    x, y = z.real, z.imag
    if y == 0:
        return mp.mpc(mp.expm1(x), 0)
    return mp.mpc(mp.expm1(x) * mp.cos(y) - 2 * mp.sin(y / 2) ** 2, mp.exp(x) * mp.sin(y))


def lcp(W, q, tol):
    """Solves w = W z + q, z >= 0, w >= 0, z.w = 0 (W a P-matrix, size <= ~6) by enumerating the
    index sets; returns (z, w, margin) for the set with the largest margin min(z_A, w_notA)."""
    m = len(q)
    best = None
    for mask in range(1 << m):
        A = [i for i in range(m) if mask >> i & 1]
        try:
            zA = solve([[W[i][j] for j in A] for i in A], [-q[i] for i in A])
        except ZeroDivisionError:
            continue
        z = [mp.mpf(0)] * m
        for i, v in zip(A, zA):
            z[i] = v
        w = [dot(W[i], z) + q[i] for i in range(m)]
        margin = min([z[i] for i in A] + [w[i] for i in range(m) if i not in A] + [mp.inf])
        if best is None or margin > best[2]:
            best = (z, w, margin)
    if best is None or best[2] < -tol:
        raise Undetermined(f"LCP without a solution (margin {best[2] if best else None})")
    z, w, _ = best
    # exact complementarity on the chosen set
    return [max(v, mp.mpf(0)) for v in z], [max(v, mp.mpf(0)) for v in w], best[2]


# ---------------------------------------------------------------------------------------------
# scene


class Contact:
    def __init__(self, w, sigma, d, r, label):
        self.w, self.sigma, self.d, self.r, self.label = w, sigma, d, r, label


class Scene:
    """A scene in the physical form (mass, stiffness, forcing_dof, damping_ratios) with [[contact]]
    tables or the [stop] shorthand; the modal form with [stop] is mapped onto an equivalent
    physical system (M = diag(1/T_B), K = diag(w_i^2/T_B), force T_A/T_B, x_B = sum X_i)."""

    def __init__(self, path, text=None):
        if text is None:
            with open(path, "rb") as fh:
                doc = tomllib.load(fh)
        else:
            doc = tomllib.loads(text)
        self.path, self.title = path, doc.get("title", "")
        st = doc.get("structure", {})
        ex = doc.get("excitation", {})
        self.f = mp.mpf(ex["amplitude"])
        self.omega = mp.mpf(ex["frequency"])
        zeta = st.get("damping_ratios")
        if "mass" in st:
            self.M = [[mp.mpf(x) for x in row] for row in st["mass"]]
            self.K = [[mp.mpf(x) for x in row] for row in st["stiffness"]]
            n = len(self.M)
            a = st["forcing_dof"]
            self.b = [mp.mpf(1 if i == a else 0) for i in range(n)]
            self.modal = None
            if "modes" in st and st["modes"] != n:
                raise SceneError("structure.modes (truncation) is not supported by the reference")
        else:
            om = [mp.mpf(x) for x in st["frequencies"]]
            TA = [mp.mpf(x) for x in st["forcing"]]
            TB = [mp.mpf(x) for x in st["contact"]]
            n = len(om)
            self.M = [[1 / TB[i] if i == j else mp.mpf(0) for j in range(n)] for i in range(n)]
            self.K = [[om[i] ** 2 / TB[i] if i == j else mp.mpf(0) for j in range(n)] for i in range(n)]
            self.b = [TA[i] / TB[i] for i in range(n)]
            self.modal = (om, TB)
        self.n = n
        self.zeta = [mp.mpf(z) for z in zeta] if zeta is not None else [mp.mpf(0)] * n
        if len(self.zeta) != n:
            raise SceneError("structure.damping_ratios: one per mode")
        self.contacts = []
        if "contact" in doc and "stop" in doc:
            raise SceneError("[stop] and [[contact]] together")
        if "contact" in doc:
            for j, c in enumerate(doc["contact"]):
                if "modal" in c or self.modal is not None:
                    raise SceneError("[[contact]] in the modal form is not supported by the reference")
                if ("dof" in c) == ("dofs" in c):
                    raise SceneError(f"contact[{j}]: give dof or dofs")
                w = [mp.mpf(0)] * n
                if "dof" in c:
                    w[c["dof"]] = mp.mpf(1)
                else:
                    bb, aa = c["dofs"]
                    if bb == aa:
                        raise SceneError(f"contact[{j}]: a pair on one DOF")
                    w[bb], w[aa] = mp.mpf(1), mp.mpf(-1)
                sigma = {"below": 1, "above": -1}[c["side"]]
                self.contacts.append(Contact(w, sigma, mp.mpf(c["position"]), mp.mpf(c["restitution"]), j))
        else:
            sp = doc["stop"]
            if self.modal is None:
                w = [mp.mpf(1 if i == st["contact_dof"] else 0) for i in range(n)]
            else:
                w = [mp.mpf(1)] * n
            self.contacts.append(Contact(w, 1, mp.mpf(sp["position"]), mp.mpf(sp["restitution"]), 0))
        ini = doc.get("initial", {})
        self.t0 = mp.mpf(ini.get("time", 0))
        self.q0 = [mp.mpf(x) for x in ini["displacement"]] if "displacement" in ini else None
        self.v0 = [mp.mpf(x) for x in ini["velocity"]] if "velocity" in ini else None
        self.periods = int(doc.get("run", {}).get("periods", 200))


# ---------------------------------------------------------------------------------------------
# the model in mass-normalised modal coordinates eta (q = Phi eta, Phi^T M Phi = I)


class Model:
    def __init__(self, sc):
        n = sc.n
        self.sc, self.n, self.m = sc, n, len(sc.contacts)
        if sc.modal is not None:
            om, TB = sc.modal
            Phi = [[mp.sqrt(TB[i]) if i == j else mp.mpf(0) for j in range(n)] for i in range(n)]
            om2 = [x ** 2 for x in om]
        else:
            L = mp.cholesky(mp.matrix(sc.M))
            Li = L ** -1
            A = Li * mp.matrix(sc.K) * Li.T
            A = (A + A.T) / 2
            E, Q = mp.eigsy(A)
            order = sorted(range(n), key=lambda i: E[i])
            PhiM = Li.T * Q
            Phi = [[PhiM[i, k] for k in order] for i in range(n)]
            om2 = [E[k] for k in order]
        self.Phi = Phi
        self.om2 = om2
        self.D = [2 * sc.zeta[i] * mp.sqrt(om2[i]) for i in range(n)]
        PhiT = transpose(Phi)
        self.PhiTM = [matvec(sc.M, col) for col in PhiT]          # rows: phi_i^T M (Phi^-1)
        self.p = matvec(PhiT, sc.b)                               # modal force per unit f
        self.c = [[ct.sigma * x for x in matvec(PhiT, ct.w)] for ct in sc.contacts]
        self.e = [ct.sigma * ct.d for ct in sc.contacts]
        self.r = [ct.r for ct in sc.contacts]
        self.W = [[dot(cj, ck) for ck in self.c] for cj in self.c]  # Delassus matrix
        self.omega, self.f = sc.omega, sc.f
        self.T = 2 * mp.pi / sc.omega
        self._flows = {}

    def to_modal(self, q):
        return [dot(row, q) for row in self.PhiTM]

    def gap(self, j, eta):
        return dot(self.c[j], eta) - self.e[j]

    def gapvel(self, j, etad):
        return dot(self.c[j], etad)

    def free_acc(self, t, eta, etad):
        """Modal accelerations without contact forces."""
        s = mp.sin(self.omega * t) * self.f
        return [self.p[i] * s - self.D[i] * etad[i] - self.om2[i] * eta[i] for i in range(self.n)]

    def flow(self, S):
        S = tuple(sorted(S))
        if S not in self._flows:
            self._flows[S] = Flow(self, S)
        return self._flows[S]

    def project(self, Z, eta, etad, positions=True):
        """Orthogonal (mass-normalised) projection onto g_Z = 0 and dg_Z/dt = 0: the plastic
        impulsive projection; the position part only removes rounding."""
        if not Z:
            return eta, etad, []
        CZ = [self.c[j] for j in Z]
        WZ = [[self.W[j][k] for k in Z] for j in Z]
        Pv = solve(WZ, [-dot(cj, etad) for cj in CZ])
        etad = [etad[i] + sum(Pv[a] * CZ[a][i] for a in range(len(Z))) for i in range(self.n)]
        if positions:
            Pq = solve(WZ, [-(dot(self.c[j], eta) - self.e[j]) for j in Z])
            eta = [eta[i] + sum(Pq[a] * CZ[a][i] for a in range(len(Z))) for i in range(self.n)]
        return eta, etad, Pv


class Flow:
    """Closed-form flow with the contacts S held (S empty: free flight). eta = Xp + N y,
    y'' + N^T D N y' + N^T Omega N y = N^T p f sin(w t) - N^T Omega Xp, in first-order form
    z' = A z + G sin(w t) + H, diagonalised: z = V u."""

    def __init__(self, model, S):
        n = model.n
        self.model, self.S = model, S
        if S:
            CS = [model.c[j] for j in S]
            N = transpose(kernel_basis(CS, n))
            WS = [[model.W[j][k] for k in S] for j in S]
            lam = solve(WS, [model.e[j] for j in S])
            Xp = [sum(CS[a][i] * lam[a] for a in range(len(S))) for i in range(n)]
            self.WSinvCS = matvec_rows(inverse(WS), CS)
        else:
            N = [[mp.mpf(1 if i == k else 0) for k in range(n)] for i in range(n)]
            Xp = [mp.mpf(0)] * n
            self.WSinvCS = []
        self.N, self.Xp = N, Xp
        k = n - len(S)
        if k == 0:
            N = [[] for _ in range(n)]
        self.k = k
        NT = transpose(N)
        KS = [[mp.fsum(NT[a][i] * model.om2[i] * N[i][b] for i in range(n)) for b in range(k)] for a in range(k)]
        DS = [[mp.fsum(NT[a][i] * model.D[i] * N[i][b] for i in range(n)) for b in range(k)] for a in range(k)]
        pS = [dot(NT[a], model.p) * model.f for a in range(k)]
        hS = [-mp.fsum(NT[a][i] * model.om2[i] * Xp[i] for i in range(n)) for a in range(k)]
        # first-order: z = (y, y'), z' = [[0, I], [-KS, -DS]] z + (0, pS) sin + (0, hS)
        if k:
            if all(x == 0 for row in DS for x in row):
                E, Qk = mp.eigsy(mp.matrix(KS))
                mus, cols = [], []
                for a in range(k):
                    nu = mp.sqrt(E[a])
                    vec = [Qk[i, a] for i in range(k)]
                    for sgn in (1, -1):
                        mus.append(mp.mpc(0, sgn * nu))
                        cols.append([mp.mpc(x) for x in vec] + [mp.mpc(0, sgn * nu) * x for x in vec])
                V = transpose(cols)
            else:
                A = mp.matrix(2 * k, 2 * k)
                for a in range(k):
                    A[a, k + a] = 1
                    for b in range(k):
                        A[k + a, b] = -KS[a][b]
                        A[k + a, k + b] = -DS[a][b]
                E, ER = mp.eig(A)
                mus = [mp.mpc(E[a]) for a in range(2 * k)]
                V = [[mp.mpc(ER[i, a]) for a in range(2 * k)] for i in range(2 * k)]
                for mu in mus:
                    if mu.real > 0:
                        raise Undetermined("unstable constrained flow")
            Vm = mp.matrix(V)
            Vinv = Vm ** -1
            self.Vinv = [[Vinv[i, j] for j in range(2 * k)] for i in range(2 * k)]
            self.V = V
            self.mus = mus
            self.Gq = [cdot(self.Vinv[a], [0] * k + pS) for a in range(2 * k)]
            self.Hq = [cdot(self.Vinv[a], [0] * k + hS) for a in range(2 * k)]
            for mu in mus:
                if abs(mu) < mp.mpf(10) ** (-mp.mp.dps // 2):
                    raise Undetermined("constrained flow with a zero eigenvalue (rigid-body motion)")
                if abs(abs(mu.imag) - model.omega) < mp.mpf(10) ** (-mp.mp.dps // 2) and abs(mu.real) < mp.mpf(10) ** (-mp.mp.dps // 2):
                    raise Undetermined("exact resonance")
        else:
            self.V, self.Vinv, self.mus, self.Gq, self.Hq = [], [], [], [], []

    def rowV(self, a, b):
        """For the functional a.eta + b.eta': its coefficients on u (l^T V) and its constant."""
        NT = transpose(self.N)
        l = [dot(NT[x], a) for x in range(self.k)] + [dot(NT[x], b) for x in range(self.k)]
        lV = [cdot(l, [self.V[i][c] for i in range(2 * self.k)]) for c in range(2 * self.k)]
        return lV, dot(a, self.Xp)


def kernel_basis(rows, n):
    """Orthonormal basis of the vectors orthogonal to `rows` (modified Gram-Schmidt, twice)."""
    basis = []

    def orth(v):
        for _ in range(2):
            for b in basis:
                d = dot(b, v)
                v = [x - d * y for x, y in zip(v, b)]
        return v

    for r in rows:
        v = orth(list(r))
        nv = mp.sqrt(dot(v, v))
        if nv < mp.mpf(10) ** (-mp.mp.dps // 2):
            raise Undetermined("dependent contacts in one active set")
        basis.append([x / nv for x in v])
    kern = []
    for i in range(n):
        v = orth([mp.mpf(1 if i == k else 0) for k in range(n)])
        nv = mp.sqrt(dot(v, v))
        if nv > mp.mpf("0.1"):
            v = [x / nv for x in v]
            basis.append(v)
            kern.append(v)
    assert len(kern) == n - len(rows)
    return kern


def matvec_rows(A, rows):
    """A (p x p) times the p x n matrix given by its rows."""
    return [[mp.fsum(A[i][a] * rows[a][c] for a in range(len(rows))) for c in range(len(rows[0]))] for i in range(len(A))]


class Phase:
    """The flow of one active set from the state (t0, eta, etad)."""

    def __init__(self, flow, t0, eta, etad):
        self.flow, self.t0 = flow, t0
        model = flow.model
        self.model = model
        k = flow.k
        NT = transpose(flow.N)
        self.eta0, self.etad0 = eta, etad
        self.y0 = [dot(NT[a], [eta[i] - flow.Xp[i] for i in range(model.n)]) for a in range(k)]
        self.yd0 = [dot(NT[a], etad) for a in range(k)]
        z0 = self.y0 + self.yd0
        iw = mp.mpc(0, model.omega)
        Ew = mp.exp(iw * t0)
        self.Ew = Ew
        self.h, self.alpha, self.beta = [], [], []
        for a in range(2 * k):
            mu = flow.mus[a]
            u0 = cdot(flow.Vinv[a], z0)
            ust = -flow.Hq[a] / mu
            al = flow.Gq[a] / (2j * (iw - mu))
            be = -flow.Gq[a] / (2j * (-iw - mu))
            self.alpha.append(al)
            self.beta.append(be)
            self.h.append(u0 - ust - al * Ew - be / Ew)

    def functional(self, a, b, kappa, const):
        """F = a.eta + b.eta' + kappa sin(w t) + const along this phase."""
        flow, model = self.flow, self.model
        lV, c0 = flow.rowV(a, b)
        terms = {}
        for x in range(2 * flow.k):
            mu = flow.mus[x]
            terms[mu] = terms.get(mu, 0) + lV[x] * self.h[x]
        iw = mp.mpc(0, model.omega)
        Ap = sum((lV[x] * self.alpha[x] for x in range(2 * flow.k)), mp.mpc(0)) * self.Ew
        Am = sum((lV[x] * self.beta[x] for x in range(2 * flow.k)), mp.mpc(0)) / self.Ew
        Ap += mp.mpc(0, -1) * kappa * self.Ew
        terms[iw] = terms.get(iw, 0) + Ap
        terms[-iw] = terms.get(-iw, 0) + Am
        F0 = dot(a, self.eta0) + dot(b, self.etad0) + kappa * mp.sin(model.omega * self.t0) + const
        return ExpSum(F0, [(mu, A) for mu, A in terms.items() if A != 0])

    def gap(self, j):
        return self.functional(self.model.c[j], [0] * self.model.n, 0, -self.model.e[j])

    def reaction(self, idx):
        """lambda of the idx-th contact of S: row of W_SS^-1 C_S (D eta' + Omega eta - p f sin)."""
        model = self.model
        rho = self.flow.WSinvCS[idx]
        a = [model.om2[i] * rho[i] for i in range(model.n)]
        b = [model.D[i] * rho[i] for i in range(model.n)]
        return self.functional(a, b, -dot(rho, model.p) * model.f, 0)

    def state(self, s):
        flow, model, k = self.flow, self.model, self.flow.k
        if k == 0:
            return list(flow.Xp), [mp.mpf(0)] * model.n
        iw = mp.mpc(0, model.omega)
        ep, emn = em1(iw * s), em1(-iw * s)
        coef = [self.h[x] * em1(flow.mus[x] * s) + self.alpha[x] * self.Ew * ep + self.beta[x] / self.Ew * emn
                for x in range(2 * k)]
        z0 = self.y0 + self.yd0
        z = [z0[i] + cdot(flow.V[i], coef).real for i in range(2 * k)]
        y, yd = z[:k], z[k:]
        eta = [flow.Xp[i] + dot(flow.N[i], y) for i in range(model.n)]
        etad = [dot(flow.N[i], yd) for i in range(model.n)]
        return eta, etad


class ExpSum:
    """F(s) = F0 + Re sum A (exp(mu s) - 1), Re mu <= 0."""

    def __init__(self, F0, terms):
        self.F0, self.terms = F0, terms
        self.bound = [mp.fsum(abs(A) * abs(mu) ** p for mu, A in terms) for p in range(5)]

    def derivs(self, s, upto=2):
        """F(s), F'(s), ..., F^(upto)(s)."""
        out = [self.F0]
        ex = []
        for mu, A in self.terms:
            e1 = em1(mu * s) if s else mp.mpc(0)
            out[0] += (A * e1).real
            ex.append((mu, A, e1 + 1))
        for p in range(1, upto + 1):
            out.append(mp.fsum((A * mu ** p * e).real for mu, A, e in ex))
        return out

    def constant(self, scale):
        return self.bound[1] <= scale * mp.mpf(10) ** (-mp.mp.dps + 6)


def first_root_poly(c):
    """First positive root of c[0] + c[1] s + c[2] s^2 + c[3] s^3 (c[0] > 0, c[3] < 0), returned
    from below (the returned s never exceeds the root). Monotone pieces between the critical
    points, each searched by safeguarded Newton."""
    c0, c1, c2, c3 = c
    p = lambda s: ((c3 * s + c2) * s + c1) * s + c0
    dp = lambda s: (3 * c3 * s + 2 * c2) * s + c1
    crit = []
    A, B, C = 3 * c3, 2 * c2, c1
    disc = B * B - 4 * A * C
    if disc > 0:
        sq = mp.sqrt(disc)
        for x in sorted([(-B + sq) / (2 * A), (-B - sq) / (2 * A)]):
            if x > 0:
                crit.append(x)
    lo = mp.mpf(0)
    for hi in crit + [None]:
        if hi is None:
            hi = max(lo * 2, mp.mpf(1))
            while p(hi) > 0:
                hi *= 2
        if p(hi) > 0:
            lo = hi
            continue
        # root in (lo, hi], p(lo) > 0 >= p(hi), p monotone decreasing here: locate it in
        # floating point, then step back by a relative 1e-13 and confirm p > 0 in mpmath
        # (p monotone on the piece: p(s) > 0 means s is below the root).
        fl, fh = float(lo), float(hi)
        fc = [float(x) for x in (c0, c1, c2, c3)]
        fp = lambda s: ((fc[3] * s + fc[2]) * s + fc[1]) * s + fc[0]
        fdp = lambda s: (3 * fc[3] * s + 2 * fc[2]) * s + fc[1]
        x = fl
        for _ in range(100):
            d = fdp(x)
            nx = x - fp(x) / d if d < 0 else 0.5 * (fl + fh)
            if not (fl < nx < fh):
                nx = 0.5 * (fl + fh)
            if fp(nx) > 0:
                fl = nx
            else:
                fh = nx
            if abs(nx - x) <= 1e-15 * abs(nx):
                x = nx
                break
            x = nx
        cand = mp.mpf(x) * (1 - mp.mpf("1e-13"))
        if lo < cand < hi and p(cand) > 0:
            return cand
        for _ in range(400):                      # exact bisection (rare fallback)
            mid = (lo + hi) / 2
            if p(mid) > 0:
                lo = mid
            else:
                hi = mid
            if hi - lo <= hi * mp.mpf(10) ** (-mp.mp.dps + 4):
                break
        return lo
    return lo


def first_root(F, order, smax, tol):
    """First root of F in (0, smax] or None. order = multiplicity of the known zero at s = 0
    (0: F(0) > 0; 1: after an impact, 2: after a zero-velocity departure, 3: after a release)."""
    b = F.bound
    if b[1] == 0:
        return None
    if order:
        d = F.derivs(0, 3)
        # lower bound sum_{i>=order} F_i s^i/i! - M_4 s^4/4!, divided by s^order
        co = [d[i] / math.factorial(i) for i in range(order, 4)] + [-b[4] / 24]
        if co[0] <= 0:
            raise Undetermined(f"a flight that starts into the stop (order {order}, leading {co[0]})")
        if b[4] == 0:
            return None
        if len(co) == 4:
            u = first_root_poly(co)
        elif len(co) == 3:
            c0, c1, c2 = co
            u = (-c1 - mp.sqrt(c1 * c1 - 4 * c2 * c0)) / (2 * c2)
        else:
            u = -co[0] / co[1]
    else:
        u = mp.mpf(0)
    for _ in range(100000):
        if u >= smax:
            return None
        F0, F1, F2 = F.derivs(u, 2)
        if F0 <= 0:
            return u
        step = first_root_poly([F0, F1, F2 / 2, -b[3] / 6]) if b[3] > 0 else (
            -F0 / F1 if F1 < 0 else smax)
        if step <= tol:
            return u + step if u + step <= smax else None
        u += step
    raise Undetermined("root search did not converge")


# ---------------------------------------------------------------------------------------------
# the automaton


class Simulation:
    def __init__(self, scene, dps=40, tail_target=mp.mpf("1e-25")):
        self.sc = scene
        self.model = Model(scene)
        m = self.model
        self.events = []
        self.tol_t = m.T * mp.mpf(10) ** (-(mp.mp.dps - 8))
        self.window = m.T * mp.mpf(10) ** (-(mp.mp.dps - 20))
        self.tail_target = tail_target
        self.vscale = mp.mpf(1)
        self.stats = {"tails": 0, "impacts": 0, "coupled": 0}
        self.last_impact, self.cascade, self.cascade_first = None, 0, {}
        self.tail_damping = True      # False: the tail without its damping term (diagnostics)

    # tolerances
    def vtol(self):
        return self.vscale * mp.mpf(10) ** (-(mp.mp.dps - 12))

    def emit(self, t, kind, j, vb=0, va=0, simultaneous=False):
        self.events.append((t, kind, j, mp.mpf(vb), mp.mpf(va), simultaneous))

    def initial_state(self):
        sc, m = self.sc, self.model
        if sc.q0 is not None:
            q, v = sc.q0, sc.v0 or [mp.mpf(0)] * m.n
            return m.to_modal(q), m.to_modal(v)
        # the origin if admissible, else the static equilibrium of the contact LCP
        eta = [mp.mpf(0)] * m.n
        if all(m.gap(j, eta) >= 0 for j in range(m.m)):
            return eta, [mp.mpf(0)] * m.n
        G = [[mp.fsum(m.c[j][i] * m.c[k][i] / m.om2[i] for i in range(m.n)) for k in range(m.m)] for j in range(m.m)]
        lam, _, _ = lcp(G, [-x for x in m.e], mp.mpf(10) ** (-(mp.mp.dps - 10)))
        eta = [mp.fsum(m.c[j][i] * lam[j] for j in range(m.m)) / m.om2[i] for i in range(m.n)]
        return eta, [mp.mpf(0)] * m.n

    def run(self, periods=None):
        m = self.model
        periods = periods if periods is not None else self.sc.periods
        t = self.sc.t0
        t_end = t + periods * m.T
        eta, etad = self.initial_state()
        self.vscale = 1 + max(abs(x) for x in etad + [mp.mpf(1)])
        orders = {}
        S = set()
        Z0 = []
        gtol = mp.mpf(10) ** (-(mp.mp.dps - 12)) * (1 + max(abs(x) for x in m.e + [mp.mpf(1)]))
        for j in range(m.m):
            g, v = m.gap(j, eta), m.gapvel(j, etad)
            if g < -gtol:
                raise SceneError(f"initial state violates contact {j} (gap {mp.nstr(g, 5)})")
            if abs(g) <= gtol:
                if v > self.vtol():
                    orders[j] = 1
                elif v < -self.vtol():
                    raise SceneError(f"initial state moves into contact {j}")
                else:
                    Z0.append(j)
        if Z0:
            S, orders, eta, etad = self.enter(t, Z0, set(), orders, eta, etad)
        while t < t_end:
            t, eta, etad, S, orders = self.step(t, t_end, eta, etad, S, orders)
        return self.events

    def enter(self, t, Z0, S_old, orders, eta, etad, report=True):
        """Acceleration LCP on the contacts Z0 at zero gap and zero velocity: who sticks."""
        m = self.model
        Z0 = sorted(set(Z0))
        eta, etad, _ = m.project(Z0, eta, etad)
        a0 = m.free_acc(t, eta, etad)
        aZ = [dot(m.c[j], a0) for j in Z0]
        WZ = [[m.W[j][k] for k in Z0] for j in Z0]
        scale = 1 + max(abs(x) for x in aZ)
        lam, acc, margin = lcp(WZ, aZ, scale * mp.mpf(10) ** (-(mp.mp.dps - 12)))
        tiny = scale * mp.mpf(10) ** (-(mp.mp.dps - 15))
        S = set()
        orders = dict(orders)
        for idx, j in enumerate(Z0):
            if lam[idx] > tiny:
                S.add(j)
                orders.pop(j, None)
                if report and j not in S_old:
                    self.emit(t, "stick", j)
            elif acc[idx] > tiny:
                orders[j] = 2
                if report and j in S_old:
                    self.emit(t, "leave", j)
            else:
                raise Undetermined(f"degenerate entry into sticking at contact {j}, t = {mp.nstr(t, 17)}")
        if S:
            eta, etad, _ = m.project(sorted(S), eta, etad)
        return S, orders, eta, etad

    def gtol(self):
        m = self.model
        return mp.mpf(10) ** (-(mp.mp.dps - 12)) * (1 + max(abs(x) for x in m.e + [mp.mpf(1)]))

    def step(self, t, t_end, eta, etad, S, orders):
        m = self.model
        # a free contact at zero gap that no event has classified (e.g. touched by a flight of
        # zero length in a cascade): separating, closing, or resting
        orders = dict(orders)
        for j in range(m.m):
            if j in S or orders.get(j, 0) or m.gap(j, eta) > self.gtol():
                continue
            v = m.gapvel(j, etad)
            if v > self.vtol():
                orders[j] = 1
            elif v < -self.vtol():
                return self.impact(t, t_end, [j], eta, etad, S)
            elif dot(m.c[j], m.free_acc(t, eta, etad)) > 0 and not S:
                orders[j] = 2
            else:
                S2, orders, eta, etad = self.enter(t, sorted(S) + [j], S, orders, eta, etad)
                return t, eta, etad, S2, orders
        flow = m.flow(S)
        ph = Phase(flow, t, eta, etad)
        Sl = sorted(S)
        smax = t_end - t
        cands = []
        for j in range(m.m):
            if j in S:
                F = ph.reaction(Sl.index(j))
                kind = "release"
                order = 0
            else:
                F = ph.gap(j)
                kind = "gap"
                order = orders.get(j, 0)
                if F.constant(1 + abs(F.F0)) and order == 0:
                    continue
                if order == 0 and F.F0 <= 0:
                    raise Undetermined(f"contact {j} penetrated at t = {mp.nstr(t, 17)} (gap {mp.nstr(F.F0, 5)})")
            s = first_root(F, order, smax + self.window, self.tol_t)
            if s is not None:
                cands.append((s, kind, j, F))
                smax = min(smax, s)
        if not cands or min(c[0] for c in cands) > t_end - t:
            eta, etad = ph.state(t_end - t)
            return t_end, eta, etad, S, {}
        s = min(c[0] for c in cands)
        group = [c for c in cands if c[0] <= s + self.window]
        t1 = t + s
        eta, etad = ph.state(s)
        releases = [c for c in group if c[1] == "release"]
        gaps = [c for c in group if c[1] == "gap"]
        if releases and gaps:
            raise Undetermined(f"release coinciding with an impact at t = {mp.nstr(t1, 17)}")
        if releases:
            for _, _, j, F in releases:
                d = F.derivs(s, 1)
                if d[1] >= 0:
                    # tangency of the reaction: not a release; step past it
                    raise Undetermined(f"reaction tangency at contact {j}, t = {mp.nstr(t1, 17)}")
                S = S - {j}
                self.emit(t1, "release", j)
            orders = {c[2]: 3 for c in releases}
            if S:
                eta, etad, _ = m.project(sorted(S), eta, etad)
            return t1, eta, etad, S, orders
        # gap roots: impacts (closing) or tangential touches
        closing, touch = [], []
        for _, _, j, F in gaps:
            v = m.gapvel(j, etad)
            if v < -self.vtol():
                closing.append(j)
            else:
                touch.append(j)
        if not closing:
            # tangential arrival: grazing if the gap curves away, else it enters contact
            enter = []
            for j in touch:
                acc = dot(m.c[j], m.free_acc(t1, eta, etad))
                if acc > 0 and not S:
                    self.emit(t1, "grazing", j, m.gapvel(j, etad), m.gapvel(j, etad))
                else:
                    enter.append(j)
            if enter:
                S, orders, eta, etad = self.enter(t1, sorted(S) + enter, S, {}, eta, etad)
                return t1, eta, etad, S, orders
            return t1, eta, etad, S, {j: 2 for j in touch}
        return self.impact(t1, t_end, closing, eta, etad, S)

    def impact(self, t, t_end, closing, eta, etad, S):
        m = self.model
        # the impact LCP acts on every contact at zero gap that is closing or resting
        resting = [j for j in range(m.m) if j not in S and j not in closing
                   and abs(m.gap(j, eta)) <= self.gtol() and abs(m.gapvel(j, etad)) <= self.vtol()]
        Z = sorted(set(closing) | S | set(resting))
        # alternating impacts of several contacts accumulating at one instant: not decided. An
        # accumulation only once the closing speeds have fallen below half their first value in the
        # cascade (elastic bouncing between two close stops accumulates nowhere)
        last = self.last_impact
        speeds = {j: -m.gapvel(j, etad) for j in closing}
        if last is not None and set(closing) != last[1] and t - last[0] < self.model.T * mp.mpf("1e-9"):
            self.cascade += 1
            for j, v in speeds.items():
                self.cascade_first.setdefault(j, v)
            if self.cascade > 3 and any(v < self.cascade_first[j] / 2 for j, v in speeds.items()):
                raise Undetermined(f"contacts {sorted(set(closing) | last[1])} chattering to one accumulation "
                                   f"point near t = {mp.nstr(t, 17)}")
        else:
            self.cascade, self.cascade_first = 0, dict(speeds)
        self.last_impact = (t, set(closing))
        vm = [m.gapvel(j, etad) for j in Z]
        for idx, j in enumerate(Z):
            if j in S or j in resting:
                vm[idx] = mp.mpf(0)
        WZ = [[m.W[j][k] for k in Z] for j in Z]
        q = [(1 + m.r[j]) * vm[idx] for idx, j in enumerate(Z)]
        P, _, _ = lcp(WZ, q, self.vscale * mp.mpf(10) ** (-(mp.mp.dps - 12)))
        if any(abs(m.W[a][b]) > mp.mpf("1e-20") and P[ia] > 0 and P[ib] > 0 for ia, a in enumerate(Z) for ib, b in enumerate(Z) if a != b):
            self.stats["coupled"] += 1      # an impulse shared by coupled contacts (a true LCP)
        for idx, j in enumerate(Z):
            for i in range(m.n):
                etad[i] += m.c[j][i] * P[idx]
        vp = [m.gapvel(j, etad) for j in Z]
        simultaneous = len(closing) > 1
        for idx, j in enumerate(Z):
            if j in closing:
                self.emit(t, "impact", j, vm[idx], vp[idx], simultaneous)
                self.stats["impacts"] += 1
        orders = {}
        Z0 = []
        newS = set()
        for idx, j in enumerate(Z):
            if abs(vp[idx]) <= self.vtol():
                Z0.append(j)
            elif vp[idx] > 0:
                orders[j] = 1
                if j in S:
                    self.emit(t, "liftoff", j, 0, vp[idx])
            else:
                raise Undetermined(f"contact {j} still closing after the impact LCP")
        if Z0:
            S2, orders2, eta, etad = self.enter(t, Z0, S, orders, eta, etad)
            newS, orders = S2, orders2
        # chattering: a single closing contact bouncing with small velocity while newS is held
        if len(closing) == 1:
            k = closing[0]
            if k not in newS and orders.get(k) == 1 and 0 < m.r[k] < 1:
                out = self.try_tail(t, t_end, k, vm[Z.index(k)], eta, etad, newS, orders)
                if out is not None:
                    return out
        return t, eta, etad, newS, orders

    def try_tail(self, t, t_end, k, v_arrival, eta, etad, S, orders):
        """The accumulation rule: predict the accumulation point of the chattering of contact k
        (S held) if the estimated error is below tail_target * T; else return None (the next
        impact is followed explicitly)."""
        m = self.model
        r = m.r[k]
        ph = Phase(m.flow(S), t, eta, etad)
        G = ph.gap(k)
        d = G.derivs(0, 3)
        a, adot = d[2], d[3]
        if a >= 0:
            return None
        D0 = 2 * r * abs(v_arrival) / ((1 - r) * abs(a))
        eps = adot * D0 / abs(a)
        if abs(eps) > mp.mpf("0.1") or mp.mpf("0.3") * eps ** 2 * D0 > self.tail_target * m.T:
            return None
        # the reactions of S + {k} at rest must all be positive
        Zk = sorted(S | {k})
        e2, ed2, _ = m.project(Zk, list(eta), list(etad))
        a0 = m.free_acc(t, e2, ed2)
        WZ = [[m.W[i][j] for j in Zk] for i in Zk]
        lam = solve(WZ, [-dot(m.c[i], a0) for i in Zk])
        if min(lam) <= 0:
            return None
        # damping: each impact reverses the gap velocity and with it the damping force on the
        # gap, g'' = A - beta g' (beta = u.D u / c_k.u, u = N N^T c_k the direction of the
        # impulse with S held); summed over the tail this shortens it by r beta D0^2 / 2 beyond
        # what eps (computed from the third derivative at the impact, which contains -beta a) holds
        if ph.flow.k:
            Nt = transpose(ph.flow.N)
            u = [dot(row, [dot(col, m.c[k]) for col in Nt]) for row in ph.flow.N]
        else:
            u = [mp.mpf(0)] * m.n
        cu = dot(m.c[k], u)
        beta = mp.fsum(m.D[i] * u[i] ** 2 for i in range(m.n)) / cu if cu else mp.mpf(0)
        if beta * D0 > mp.mpf("0.1"):
            return None
        Dinf = D0 * (1 + eps / 3) - (r * beta * D0 ** 2 / 2 if self.tail_damping else 0)
        if t + 4 * Dinf >= t_end:
            return None
        # every other gap and every reaction of S certified free of roots on [t, t + 4 Dinf]
        Sl = sorted(S)
        for j in range(m.m):
            if j == k:
                continue
            F = ph.reaction(Sl.index(j)) if j in S else ph.gap(j)
            if j not in S and F.constant(1 + abs(F.F0)) and not orders.get(j):
                continue
            if first_root(F, 0 if j in S else orders.get(j, 0), 4 * Dinf, self.tol_t) is not None:
                return None
        eta, etad = ph.state(Dinf)
        t1 = t + Dinf
        vb = m.gapvel(k, etad)
        eta, etad, _ = m.project(Zk, eta, etad)
        self.emit(t1, "accumulation", k, vb, 0)
        self.stats["tails"] += 1
        S2, orders2, eta, etad = self.enter(t1, Zk, S, {}, eta, etad)
        if k not in S2:
            raise Undetermined(f"accumulation at contact {k} without sticking, t = {mp.nstr(t1, 17)}")
        return t1, eta, etad, S2, orders2


def write_csv(events, path, digits=25):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["t", "kind", "contact", "v_before", "v_after", "simultaneous"])
        for t, kind, j, vb, va, sim in events:
            w.writerow([mp.nstr(t, digits, strip_zeros=False), kind, j, mp.nstr(vb, digits), mp.nstr(va, digits), int(sim)])


def read_csv(path):
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    return [(float(r["t"]), r["kind"], int(r["contact"]), float(r["v_before"]), float(r["v_after"]),
             bool(int(r["simultaneous"]))) for r in rows]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--out", default="-")
    ap.add_argument("--dps", type=int, default=40)
    ap.add_argument("--periods", type=int, default=None)
    ap.add_argument("--tail-target", default="1e-25",
                    help="accumulation rule: largest estimated error of a predicted accumulation time, / T")
    ap.add_argument("--tail-without-damping", action="store_true",
                    help="diagnostics: leave the damping term out of the accumulation tail")
    args = ap.parse_args(argv)
    mp.mp.dps = args.dps
    try:
        sim = Simulation(Scene(args.scene), tail_target=mp.mpf(args.tail_target))
        sim.tail_damping = not args.tail_without_damping
        events = sim.run(args.periods)
    except (SceneError, KeyError) as e:
        print(f"{args.scene}: {e}", file=sys.stderr)
        return 2
    except Undetermined as e:
        print(f"{args.scene}: undetermined: {e}", file=sys.stderr)
        return 3
    if args.out == "-":
        write_csv(events, "/dev/stdout")
    else:
        write_csv(events, args.out)
    print(f"{len(events)} events, {sim.stats['impacts']} impacts, {sim.stats['tails']} accumulation tails, "
          f"{sim.stats['coupled']} impacts with impulses on coupled contacts", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
