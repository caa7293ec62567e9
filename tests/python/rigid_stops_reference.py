"""An independent reference for the rigid model of a physical multi-DOF structure between rigid stops,
written without vibro's code (numpy only), for tests/python/test_compliant_continue.py.

The model (docs/model.md §1, §3, §7; docs/harmonics.md; docs/contacts.md), in physical coordinates:

    M q̈ + C q̇ + K q = Σ_h f_h v sin(ω_h t + ψ_h),   C = M Φ diag(2 ζ_i ω_i) Φᵀ M  (Φᵀ M Φ = I),

contact j with the gap g_j = w_jᵀ q − o_j ≥ 0; where a gap closes (g_j = 0, ġ_j < 0) the velocities
jump along M⁻¹ w_j with Newton's law of restitution e_j on the gap's rate,

    q̇⁺ = q̇⁻ − (1 + e_j) (w_jᵀ q̇⁻) / W_jj · M⁻¹ w_j,   W_jj = w_jᵀ M⁻¹ w_j,

so that ġ_j⁺ = −e_j ġ_j⁻ and the displacements are continuous.

Between impacts the flow is exact: z = (q, q̇), ż = A z + b(t), solved as the eigen-decomposition of A
(homogeneous part) plus one particular solution Im(Z_h e^{i(ω_h t + ψ_h)}) per harmonic,
(iω_h − A) Z_h = (0, M⁻¹ v f_h). Impacts are located on that exact flow: every gap is evaluated on a
grid of step `h` (a sign change of g, or a local minimum of g below zero between two grid points,
found from ġ's sign change, brackets the first root), then bisected to the last bit. Whether the grid
is fine enough is checked by the caller by refining it (`Rigid(..., h=...)`): the same impacts to the
bit.

The stroboscopic map P: z(t0) ↦ z(t0 + q T) and its fixed points by Newton, the Jacobian by central
differences (the fixed point's accuracy is the residual's, not the Jacobian's).

`restitution_force_rule(zeta)` is the isolated impact's restitution of a spring–dashpot contact that
lets go where its force returns to zero (docs/compliant.md, "The two separation rules"), computed
here from the contact phase's closed form x(t) = −(v/ω_d) e^{−ζω₀t} sin ω_d t by bisection on
λ = −k x − c ẋ, not from the docs' formula (which the test compares with it).
"""
import math

import numpy as np


def restitution_force_rule(zeta):
    """e of an isolated impact on a spring–dashpot (unit mass, ω₀ = 1, entering at unit speed), the
    body leaving where λ = −x − 2ζẋ returns to zero: e = |ẋ(t_c)|."""
    wd = math.sqrt(1 - zeta * zeta)

    def x(t):
        return -math.exp(-zeta * t) * math.sin(wd * t) / wd

    def v(t):
        return -math.exp(-zeta * t) * (wd * math.cos(wd * t) - zeta * math.sin(wd * t)) / wd

    def lam(t):
        return -x(t) - 2 * zeta * v(t)

    # λ(0+) = 2ζ > 0 at the entry; λ < 0 by t = π/ω_d (x = 0 there, ẋ > 0): the first sign change.
    a, b = 1e-9, math.pi / wd
    assert lam(a) > 0 > lam(b)
    while True:
        m = 0.5 * (a + b)
        if m in (a, b):
            break
        if lam(m) > 0:
            a = m
        else:
            b = m
    return abs(v(a)), a


class Rigid:
    """The rigid structure: `mass`, `stiffness` (n×n), modal `damping_ratios`, the forcing vector
    `force` (n), the harmonics (amplitudes, multiples n_h of the base pulsation, phases), the base
    pulsation `omega`, and `contacts`: a list of (w, o, e) with the gap g = wᵀq − o."""

    def __init__(self, mass, stiffness, damping_ratios, force, amplitudes, multiples, phases, omega, contacts,
                 h=None):
        M = np.array(mass, float)
        K = np.array(stiffness, float)
        n = len(M)
        self.n = n
        # Mass-normalized modes: M^{-1/2} K M^{-1/2} (M diagonal or not: through Cholesky).
        L = np.linalg.cholesky(M)
        Li = np.linalg.inv(L)
        w2, U = np.linalg.eigh(Li @ K @ Li.T)
        Phi = Li.T @ U  # Φᵀ M Φ = I, Φᵀ K Φ = diag(ω²)
        self.modal_frequencies = np.sqrt(w2)
        self.Phi = Phi
        C = M @ Phi @ np.diag(2 * np.array(damping_ratios, float) * np.sqrt(w2)) @ Phi.T @ M
        Mi = np.linalg.inv(M)
        self.Mi = Mi
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = -Mi @ K
        A[n:, n:] = -Mi @ C
        self.A = A
        lam, V = np.linalg.eig(A)
        self.lam, self.V, self.Vi = lam, V, np.linalg.inv(V)
        self.omega = float(omega)
        self.T = 2 * math.pi / self.omega
        self.harm = []
        for f, k, psi in zip(amplitudes, multiples, phases):
            wh = k * self.omega
            rhs = np.zeros(2 * n, complex)
            rhs[n:] = Mi @ np.array(force, float) * f
            Z = np.linalg.solve(1j * wh * np.eye(2 * n) - A, rhs)
            self.harm.append((wh, float(psi), Z))
        self.contacts = [(np.array(w, float), float(o), float(e)) for w, o, e in contacts]
        self.h = h if h is not None else self.T / 2048

    # -- the exact flow --------------------------------------------------------------------------
    def particular(self, t):
        """z_p(t) (t an array: shape (len(t), 2n))."""
        t = np.atleast_1d(np.asarray(t, float))
        out = np.zeros((len(t), 2 * self.n))
        for wh, psi, Z in self.harm:
            out += np.imag(np.exp(1j * (wh * t + psi))[:, None] * Z[None, :])
        return out

    def flow(self, ts, zs, t):
        """The free flow from (ts, zs) at the times t (array): shape (len(t), 2n)."""
        t = np.atleast_1d(np.asarray(t, float))
        c = self.Vi @ (zs - self.particular(ts)[0])
        hom = np.real((np.exp(np.outer(t - ts, self.lam)) * c[None, :]) @ self.V.T)
        return self.particular(t) + hom

    def gaps(self, z):
        """Each contact's gap and its rate for the states z (rows): shapes (len(z), contacts)."""
        n = self.n
        W = np.array([w for w, _, _ in self.contacts])
        o = np.array([o for _, o, _ in self.contacts])
        return z[:, :n] @ W.T - o[None, :], z[:, n:] @ W.T

    # -- impacts ---------------------------------------------------------------------------------
    def _bisect(self, f, a, b):
        """The sign change of f in [a, b] (f(a) and f(b) of opposite signs, or f(b) = 0), to the
        last bit: (a, b) adjacent doubles with f(a) on a's side."""
        fa = f(a) > 0
        while True:
            m = 0.5 * (a + b)
            if m <= a or m >= b:
                return a, b
            if (f(m) > 0) == fa:
                a = m
            else:
                b = m

    def next_impact(self, ts, zs, t_end, skip=None, window=256):
        """The first impact of the free flight from (ts, zs) in (ts, t_end]: (t, contact) or None.
        `skip`: the contact whose impact is at ts (its gap is 0 there and opening). The grid is
        evaluated `window` steps at a time (the flight usually ends in the first window)."""
        N = max(2, int(math.ceil((t_end - ts) / self.h)) + 1)
        grid = np.linspace(ts, t_end, N)
        for lo in range(0, N - 1, window):
            t = grid[lo:lo + window + 1]
            hit = self._first_root(ts, zs, t, skip if lo == 0 else None, check_start=(lo == 0))
            if hit is not None:
                return hit
        return None

    def _first_root(self, ts, zs, t, skip, check_start):
        N = len(t)
        g, gd = self.gaps(self.flow(ts, zs, t))
        best = None
        for j in range(len(self.contacts)):
            gj, gdj = g[:, j], gd[:, j]
            if check_start:
                if skip != j:
                    assert gj[0] > -1e-12, ("the flight starts inside contact", j, float(gj[0]))
                else:
                    assert gdj[0] > 0, ("a flight from an impact that does not open", j, float(gdj[0]))

            def gap(s, j=j):
                return self.gaps(self.flow(ts, zs, [s]))[0][0, j]

            def rate(s, j=j):
                return self.gaps(self.flow(ts, zs, [s]))[1][0, j]

            hit = None
            closed = np.nonzero(gj[1:] <= 0)[0]
            first = closed[0] + 1 if len(closed) else N
            # A local minimum of g strictly inside a step, with g > 0 at both ends: a root before it
            # if g is not positive there (a grazing pair within one step). Over a step h the gap
            # departs from its chord by at most max|g''| h²/8, so only steps with g small are looked at.
            mins = np.nonzero((gdj[:-1] < 0) & (gdj[1:] > 0) & (np.minimum(gj[:-1], gj[1:]) < 1e-3))[0] + 1
            for i in mins:
                if i >= first:
                    break
                a, _ = self._bisect(lambda s: -rate(s), t[i - 1], t[i])
                if gap(a) <= 0:
                    hit = (t[i - 1], a)
                    break
            if hit is None and first < N:
                hit = (t[first - 1], t[first])
            if hit is None:
                continue
            _, root = self._bisect(gap, hit[0], hit[1])  # the first instant on the closed side
            if best is None or root < best[0]:
                best = (root, j)
        return best

    def impact(self, z, j):
        w, _, e = self.contacts[j]
        n = self.n
        q, v = z[:n], z[n:]
        rate = w @ v
        W = w @ self.Mi @ w
        return np.concatenate([q, v - (1 + e) * rate / W * (self.Mi @ w)]), rate

    def run(self, t0, z0, t_end):
        """The trajectory from (t0, z0) to t_end: the list of impacts (t, contact, ġ⁻) and the
        segments [(ts, zs)] (each the start of a free flight), and the state at t_end."""
        ts, zs, skip = float(t0), np.array(z0, float), None
        impacts, segments = [], []
        while True:
            segments.append((ts, zs))
            nxt = self.next_impact(ts, zs, t_end, skip)
            if nxt is None:
                return impacts, segments, self.flow(ts, zs, [t_end])[0]
            ti, j = nxt
            zi = self.flow(ts, zs, [ti])[0]
            zs, rate = self.impact(zi, j)
            assert rate < 0, ("an impact without a closing velocity", ti, j, rate)
            impacts.append((ti, j, rate))
            ts, skip = ti, j
            if len(impacts) > 1000:
                raise RuntimeError("more than 1000 impacts: chattering is not handled by this reference")

    def states_at(self, segments, t):
        """The trajectory of `run`'s segments at the times t (sorted)."""
        t = np.asarray(t, float)
        starts = np.array([s for s, _ in segments])
        idx = np.searchsorted(starts, t, side="right") - 1
        out = np.empty((len(t), 2 * self.n))
        for k in np.unique(idx):
            sel = idx == k
            out[sel] = self.flow(segments[k][0], segments[k][1], t[sel])
        return out

    # -- periodic orbits -------------------------------------------------------------------------
    def strobe(self, t0, z0, periods):
        return self.run(t0, z0, t0 + periods * self.T)[2]

    def newton(self, t0, z0, periods, tol=1e-12, max_iter=40, fd=1e-7):
        """A fixed point of P^periods from z0: (z, residual) or (None, reason). The step is halved
        until the new section state is a free one (every gap open by more than the differences'
        step); the Jacobian by central differences."""
        z = np.array(z0, float)
        m = 2 * self.n
        res = math.inf
        for _ in range(max_iter):
            try:
                r = self.strobe(t0, z, periods) - z
                res = np.abs(r).max()
                if res <= tol * (1 + np.abs(z).max()):
                    return z, res
                J = np.empty((m, m))
                for k in range(m):
                    dz = np.zeros(m)
                    dz[k] = fd
                    J[:, k] = (self.strobe(t0, z + dz, periods) - self.strobe(t0, z - dz, periods)) / (2 * fd)
            except (AssertionError, RuntimeError) as e:
                return None, f"the map failed: {e}"
            step = np.linalg.solve(J - np.eye(m), -r)
            lam = 1.0
            for _ in range(30):
                nxt = z + lam * step
                if (self.gaps(nxt[None, :])[0] > 10 * fd).all():  # the differences' states free too
                    break
                lam *= 0.5
            z = nxt
        return None, f"no convergence (residual {res:.3g})"

    def orbits_from(self, t0, starts, periods, transient=60, max_iter=12):
        """The distinct fixed points of P^periods (section time t0) reached from `starts`: Newton
        from each start and from the end of a `transient` of the rigid flow from it (the attractor it
        reaches), and every orbit's images under P, P², …, P^(periods−1) (the same closed curve
        through the section at another forcing period: a fixed point of P^periods too). Returns a
        list of (z, residual)."""
        found = []

        def add(z, res):
            if not any(np.abs(z - y).max() <= 1e-8 * (1 + np.abs(z).max()) for y, _ in found):
                found.append((z, res))

        for z0 in starts:
            tries = [np.array(z0, float)]
            try:
                tries.append(self.strobe(t0, tries[0], transient))
            except (AssertionError, RuntimeError):
                pass
            for z1 in tries:
                z, res = self.newton(t0, z1, periods, max_iter=max_iter)
                if z is None:
                    continue
                add(z, res)
        for z, _ in list(found):
            zk = z
            for _ in range(periods - 1):
                zk = self.strobe(t0, zk, 1)
                res = np.abs(self.strobe(t0, zk, periods) - zk).max()
                add(zk, res)
        return found
