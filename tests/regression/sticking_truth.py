"""An independent truth for sticking orbits held on one stop, at 50 digits (docs/prove.md "Sticking
orbits of several modes"). Written in physical coordinates from the scene's matrices, without
vibro's modal data, closed forms or sources: the state y = (x, v) of M ẍ + C ẋ + K x = a f sin ωt
(C = M Φ diag(2ζ_kω_k) Φᵀ M, modal damping) and its flight by the matrix exponential of the
augmented linear system z = (x, v, sin ωt, cos ωt) (mpmath's expm at 50 digits). Held at the stop
(DOF c at x0, v_c = 0), the other DOFs F obey M_FF ẍ_F + C_FF ẋ_F + K_FF x_F = a_F f sin ωt − K_Fc x0, and
the stop's reaction is R = M_cF ẍ_F + C_cF ẋ_F + K_cF x_F + K_cc x0 − a_c f sin ωt. A plastic landing
takes the impulse P e_c that brings v_c to 0 (M Δv = P e_c). The orbit: release (R = 0, falling),
flight to the landing (x_c = x0), R > 0 there, held until R = 0 again one period later; Newton at
50 digits (mpmath.findroot) on (t_r, x_F, v_F). The nontrivial multipliers are the eigenvalues of
the release-to-release map's Jacobian (central differences, h = 1e-20)."""
from mpmath import mp, mpf, matrix, expm, sin, cos, pi, findroot, eig, eigsy, sqrt

mp.dps = 50


class StickTruth:
    def __init__(self, M, K, forcing_dof, contact_dof, x0, f, w, zeta=None, side=1, q=1):
        self.N = N = len(M)
        self.M, self.K = matrix(M), matrix(K)
        self.a = matrix(N, 1)
        self.a[forcing_dof] = 1
        self.cd, self.x0, self.f, self.w = contact_dof, mpf(x0), mpf(f), mpf(w)
        self.T = q * 2 * pi / self.w  # the orbit's period, q forcing periods
        C = matrix(N, N)
        if zeta is not None:
            # Modal damping: M^{-1/2} K M^{-1/2} = Q Λ Qᵀ, Φ = M^{-1/2} Q (mass-normalised), C = M Φ diag(2ζω) Φᵀ M.
            Mh = matrix(N, N)
            for i in range(N):
                Mh[i, i] = 1 / sqrt(self.M[i, i])  # the tests' M are diagonal
            lam, Q = eigsy(Mh * self.K * Mh)
            order = sorted(range(N), key=lambda k: lam[k])
            Phi = Mh * Q
            D = matrix(N, N)
            for r, k in enumerate(order):
                D[k, k] = 2 * mpf(zeta[r]) * sqrt(lam[k])
            C = self.M * Phi * D * Phi.T * self.M
        self.C = C
        Minv = self.M ** -1
        A = matrix(2 * N + 2, 2 * N + 2)
        for i in range(N):
            A[i, N + i] = 1
        MK, MC, Ma = Minv * self.K, Minv * C, Minv * self.a * self.f
        for i in range(N):
            for j in range(N):
                A[N + i, j] = -MK[i, j]
                A[N + i, N + j] = -MC[i, j]
            A[N + i, 2 * N] = Ma[i]
        A[2 * N, 2 * N + 1] = self.w
        A[2 * N + 1, 2 * N] = -self.w
        self.A = A
        # Held: the free DOFs F with x_c = x0: z_h = (x_F, v_F, sin, cos, 1).
        F = [i for i in range(N) if i != contact_dof]
        self.F = F
        n = len(F)
        MFF = matrix(n, n)
        for p, i in enumerate(F):
            for q, j in enumerate(F):
                MFF[p, q] = self.M[i, j]
        MFi = MFF ** -1
        H = matrix(2 * n + 3, 2 * n + 3)
        for p in range(n):
            H[p, n + p] = 1
        for p, i in enumerate(F):
            for q in range(n):
                s_k = sum(MFi[p, r] * self.K[F[r], F[q]] for r in range(n))
                s_c = sum(MFi[p, r] * C[F[r], F[q]] for r in range(n))
                H[n + p, q] = -s_k
                H[n + p, n + q] = -s_c
            H[n + p, 2 * n] = sum(MFi[p, r] * self.a[F[r]] for r in range(n)) * self.f
            H[n + p, 2 * n + 2] = -sum(MFi[p, r] * self.K[F[r], contact_dof] for r in range(n)) * self.x0
        H[2 * n, 2 * n + 1] = self.w
        H[2 * n + 1, 2 * n] = -self.w
        self.H = H
        self.n = n

    # Free flight of the full state.
    def free(self, t0, x, v, s):
        z = matrix(list(x) + list(v) + [sin(self.w * t0), cos(self.w * t0)])
        e = expm(self.A * s) * z
        return [e[i] for i in range(self.N)], [e[self.N + i] for i in range(self.N)]

    def held(self, t0, xF, vF, s):
        z = matrix(list(xF) + list(vF) + [sin(self.w * t0), cos(self.w * t0), 1])
        e = expm(self.H * s) * z
        return [e[i] for i in range(self.n)], [e[self.n + i] for i in range(self.n)]

    def full(self, xF, vF):
        x, v = [mpf(0)] * self.N, [mpf(0)] * self.N
        for p, i in enumerate(self.F):
            x[i], v[i] = xF[p], vF[p]
        x[self.cd] = self.x0
        return x, v

    def reaction(self, t, xF, vF):
        """R = (M ẍ + C ẋ + K x − a f sin ωt)_c with ẍ_F from the held equations, ẍ_c = 0."""
        n, cd = self.n, self.cd
        z = matrix(list(xF) + list(vF) + [sin(self.w * t), cos(self.w * t), 1])
        acc = self.H * z
        x, v = self.full(xF, vF)
        R = -self.a[cd] * self.f * sin(self.w * t)
        for j in range(self.N):
            R += self.K[cd, j] * x[j] + self.C[cd, j] * v[j]
        for p, j in enumerate(self.F):
            R += self.M[cd, j] * acc[n + p]
        return R

    def landing(self, t0, x, v, s_guess):
        g = lambda s: self.free(t0, x, v, s)[0][self.cd] - self.x0  # noqa: E731
        return findroot(g, mpf(s_guess))

    def plastic(self, v):
        """M Δv = P e_c with (v + Δv)_c = 0."""
        Minv = self.M ** -1
        col = [Minv[i, self.cd] for i in range(self.N)]
        P = -v[self.cd] / col[self.cd]
        return [v[i] + P * col[i] for i in range(self.N)]

    def _landed(self):
        return self.lands[-1][3], self.lands[-1][4]

    def flights(self, tr, x, v, guess):
        """From the release: each flight to its plastic landing; every landing but the last departs
        at once (R < 0 there, checked by the caller). [(t_L, ẋ_c⁻, R, x_F, v_F after)]."""
        out, t = [], tr
        for k, sg in enumerate(guess["flights"]):
            sL = self.landing(t, x, v, sg)
            xL, vL = self.free(t, x, v, sL)
            vP = self.plastic(vL)
            xLF, vLF = [xL[i] for i in self.F], [vP[i] for i in self.F]
            tL = t + sL
            out.append((tL, vL[self.cd], self.reaction(tL, xLF, vLF), xLF, vLF))
            t, x, v = tL, xL, vP
            x[self.cd] = self.x0
        return out

    def cycle(self, tr, xF, vF, guess):
        """From a release: the landings, and the state at tr + T after the held phase."""
        x, v = self.full(xF, vF)
        lands = self.flights(tr, x, v, guess)
        tL, _, _, xLF, vLF = lands[-1]
        xe, ve = self.held(tL, xLF, vLF, tr + self.T - tL)
        return lands, xe, ve

    def solve(self, tr, xF, vF, flights):
        guess = {"flights": flights if isinstance(flights, list) else [flights]}
        n = self.n

        def F(*u):
            tr_, xF_, vF_ = u[0], list(u[1:1 + n]), list(u[1 + n:])
            _, xe, ve = self.cycle(tr_, xF_, vF_, guess)
            out = [xe[p] - xF_[p] for p in range(n)] + [ve[p] - vF_[p] for p in range(n)]
            out.append(self.reaction(tr_, xF_, vF_))
            return out
        u = findroot(F, [mpf(tr)] + [mpf(x) for x in xF] + [mpf(x) for x in vF])
        u = [u[k] for k in range(2 * n + 1)]
        self.tr, self.xF, self.vF = u[0], u[1:1 + n], u[1 + n:]
        self.lands, _, _ = self.cycle(self.tr, self.xF, self.vF, guess)
        self.tL, self.vminus, self.RL = self.lands[-1][:3]
        self.guess = guess
        return self

    def strobe_map(self, xF, vF):
        """The stroboscopic map on the held states at t_s, mid-way through the sticking phase:
        held to the release (R = 0), the flight, the plastic landing, held on to t_s + T."""
        ts = self.ts

        def R_along(s):
            xs, vs = self.held(ts, xF, vF, s)
            return self.reaction(ts + s, xs, vs)
        sr = findroot(R_along, self.tr + self.T - ts)
        xr, vr = self.held(ts, xF, vF, sr)
        tr = ts + sr
        x, v = self.full(xr, vr)
        tL, _, _, xLF, vLF = self.flights(tr, x, v, self.guess)[-1]
        xs, vs = self.held(tL, xLF, vLF, ts + self.T - tL)
        return xs + vs

    def multipliers(self):
        n, h = self.n, mpf("1e-20")
        # t_s mid-way through the sticking phase [t_L, t_r + T], and the held state there.
        self.ts = (self.tL + self.tr + self.T) / 2
        xs, vs = self.held(self.tL, *self._landed(), self.ts - self.tL)
        base = xs + vs
        J = matrix(2 * n, 2 * n)
        for k in range(2 * n):
            up, dn = list(base), list(base)
            up[k] += h
            dn[k] -= h
            a = self.strobe_map(up[:n], up[n:])
            b = self.strobe_map(dn[:n], dn[n:])
            for i in range(2 * n):
                J[i, k] = (a[i] - b[i]) / (2 * h)
        ev = eig(J, left=False, right=False)
        return [complex(e) if False else e for e in ev]
