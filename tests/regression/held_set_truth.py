"""An independent truth for sticking orbits held on sets of contacts, at 50 digits (docs/prove.md
"Sticking orbits held on sets of contacts"). Written in physical coordinates from the scene's
matrices, without vibro's modal data or sources: M q̈ + C q̇ + K q = a f sin ωt + G_Sᵀλ while the
contacts of S are held (G_S: the rows σ_j w_jᵀ, w_j = e_dof − e_partner; G_S q̈ = 0 gives
λ = −(G_S M⁻¹ G_Sᵀ)⁻¹ G_S M⁻¹ (a f sin ωt − Kq − Cq̇)), a linear system in y = (q, q̇, sin ωt, cos ωt)
whose flow is mpmath's expm at 50 digits. A plastic landing of j beside the held set H takes the
impulses that bring the velocities of Z = H ∪ {j} to zero (q̇ ← q̇ − M⁻¹G_Zᵀ(G_Z M⁻¹ G_Zᵀ)⁻¹G_Z q̇).
C = M Φ diag(2ζ_kω_k) Φᵀ M (modal damping, Φ mass-normalised). The orbit: Newton (mpmath.findroot)
on the multiple-shooting map of its segments (each segment's start time and state; the end event a
gap = 0 or a force = 0). The multipliers: eigenvalues of the Jacobian of the return map on the
states held at a section inside the longest held phase (central differences, h = 1e-20), each
event of the perturbed orbit a root found by findroot."""
from mpmath import mp, mpf, matrix, expm, sin, cos, pi, findroot, eig, eigsy, sqrt

mp.dps = 50


class SetTruth:
    def __init__(self, M, K, forcing_dof, contacts, f, w, zeta=None, q=1):
        """contacts: [(dof, partner, side ("below"/"above"), position)]."""
        self.N = N = len(M)
        self.M, self.K = matrix(M), matrix(K)
        self.a = matrix(N, 1)
        self.a[forcing_dof] = 1
        self.f, self.w, self.q = mpf(f), mpf(w), q
        self.T = 2 * pi / self.w
        self.qT = q * self.T
        self.contacts = []
        for d, p, side, pos in contacts:
            s = 1 if side == "below" else -1
            g = matrix(1, N)
            g[d] = s
            if p >= 0:
                g[p] = -s
            self.contacts.append((g, s * mpf(pos)))  # gap = g q − s·pos
        C = matrix(N, N)
        if zeta is not None:
            Mh = matrix(N, N)
            for i in range(N):
                Mh[i, i] = 1 / sqrt(self.M[i, i])  # the tests' M are diagonal
            lam, Q = eigsy(Mh * self.K * Mh)
            order = sorted(range(N), key=lambda k: lam[k])
            Phi = Mh * Q
            Dm = matrix(N, N)
            for r, k in enumerate(order):
                Dm[k, k] = 2 * mpf(zeta[r]) * sqrt(lam[k])
            C = self.M * Phi * Dm * Phi.T * self.M
        self.C = C
        self.Minv = self.M ** -1
        self._flows = {}

    def G(self, S):
        G = matrix(len(S), self.N)
        for r, j in enumerate(S):
            for i in range(self.N):
                G[r, i] = self.contacts[j][0][i]
        return G

    def flow(self, S):
        """(B, L): ẏ = B y, λ = L y (rows in the order of S) for the held set S (a tuple)."""
        if S in self._flows:
            return self._flows[S]
        N = self.N
        # F y = a f sin − K q − C q̇ as an N × (2N + 2) matrix.
        F = matrix(N, 2 * N + 2)
        for i in range(N):
            for j in range(N):
                F[i, j] = -self.K[i, j]
                F[i, N + j] = -self.C[i, j]
            F[i, 2 * N] = self.a[i] * self.f
        Acc = self.Minv * F
        L = None
        if S:
            G = self.G(S)
            L = -((G * self.Minv * G.T) ** -1) * G * Acc
            Acc = Acc + self.Minv * G.T * L
        B = matrix(2 * N + 2, 2 * N + 2)
        for i in range(N):
            B[i, N + i] = 1
            for j in range(2 * N + 2):
                B[N + i, j] = Acc[i, j]
        B[2 * N, 2 * N + 1] = self.w
        B[2 * N + 1, 2 * N] = -self.w
        self._flows[S] = (B, L)
        return B, L

    def y(self, t, q, v):
        return matrix(list(q) + list(v) + [sin(self.w * t), cos(self.w * t)])

    def advance(self, S, t, q, v, s):
        B, _ = self.flow(S)
        e = expm(B * s) * self.y(t, q, v)
        return [e[i] for i in range(self.N)], [e[self.N + i] for i in range(self.N)]

    def gap(self, j, q):
        g, e = self.contacts[j]
        return sum(g[i] * q[i] for i in range(self.N)) - e

    def force(self, S, j, t, q, v):
        _, L = self.flow(S)
        y = self.y(t, q, v)
        r = S.index(j)
        return sum(L[r, k] * y[k] for k in range(2 * self.N + 2))

    def project(self, Z, v):
        G = self.G(Z)
        vv = matrix(list(v))
        out = vv - self.Minv * G.T * ((G * self.Minv * G.T) ** -1) * G * vv
        return [out[i] for i in range(self.N)]

    def end_value(self, seg, t, q, v, s):
        """The end event's function of a segment (held, landing?, contact, sticks) after s."""
        S, landing, c, _ = seg
        qe, ve = self.advance(S, t, q, v, s)
        return (self.gap(c, qe) if landing else self.force(S, c, t + s, qe, ve)), qe, ve

    def jump(self, seg, v):
        S, landing, c, _ = seg
        return self.project(tuple(sorted(S + (c,))), v) if landing else v

    def solve(self, segs, times, qs, vs):
        """segs: [(held tuple, landing, contact, sticks)]; times/qs/vs: starts of the segments."""
        m, N = len(segs), self.N
        self.segs = segs

        def unpack(u):
            return [(u[k * (2 * N + 1)], list(u[k * (2 * N + 1) + 1:k * (2 * N + 1) + 1 + N]),
                     list(u[k * (2 * N + 1) + 1 + N:(k + 1) * (2 * N + 1)])) for k in range(m)]

        def F(*u):
            st = unpack(u)
            out = []
            for k in range(m):
                t, q, v = st[k]
                tn = st[(k + 1) % m][0] + (self.qT if k == m - 1 else 0)
                val, qe, ve = self.end_value(segs[k], t, q, v, tn - t)
                vp = self.jump(segs[k], ve)
                nq, nv = st[(k + 1) % m][1], st[(k + 1) % m][2]
                out += [val] + [qe[i] - nq[i] for i in range(N)] + [vp[i] - nv[i] for i in range(N)]
            return out
        u0 = []
        for k in range(m):
            u0 += [mpf(times[k])] + [mpf(x) for x in qs[k]] + [mpf(x) for x in vs[k]]
        u = findroot(F, u0)
        u = [u[k] for k in range(len(u0))]
        self.starts = unpack(u)
        self.residual = max(abs(x) for x in F(*u))
        return self

    def events(self):
        """[(kind, contact, time, gap velocity before)] over one period, from the release at t_0."""
        m, N = len(self.segs), self.N
        out = [("release", self.segs[-1][2], self.starts[0][0], mpf(0))]
        for k in range(m - 1):
            t, q, v = self.starts[k]
            tn = self.starts[k + 1][0]
            S, landing, c, sticks = self.segs[k]
            qe, ve = self.advance(S, t, q, v, tn - t)
            if landing:
                vm = sum(self.contacts[c][0][i] * ve[i] for i in range(N))
                out.append(("impact", c, tn, vm))
                out.append(("stick" if sticks else "departure", c, tn, vm if sticks else mpf(0)))
            else:
                out.append(("release", c, tn, mpf(0)))
        return out

    def forces_at_starts(self):
        """λ of every held contact at each segment's start (all > 0 but at a release)."""
        out = []
        for k, (S, _, _, _) in enumerate(self.segs):
            t, q, v = self.starts[k]
            out.append([self.force(S, j, t, q, v) for j in S])
        return out

    def multipliers(self):
        """Eigenvalues of the return map on the held states at a section mid-way through the longest
        segment with a held set (its free coordinates: the DOFs no held contact fixes)."""
        m, N = len(self.segs), self.N
        dur = []
        for k in range(m):
            tn = self.starts[(k + 1) % m][0] + (self.qT if k == m - 1 else 0)
            dur.append(tn - self.starts[k][0])
        K = max((k for k in range(m) if self.segs[k][0]), key=lambda k: dur[k])
        S = self.segs[K][0]
        fixed = {int([i for i in range(N) if self.contacts[j][0][i] != 0][0]) for j in S}  # single-DOF stops
        free = [i for i in range(N) if i not in fixed]
        if not free:
            return []
        ts = self.starts[K][0] + dur[K] / 2
        qs, vs = self.advance(S, *self.starts[K], dur[K] / 2)

        def ret(y):
            q, v = list(qs), list(vs)
            for p, i in enumerate(free):
                q[i], v[i] = y[p], y[len(free) + p]
            t = ts
            for step in range(m + 1):
                k = (K + step) % m
                if step == m:  # back in segment K: up to ts + qT
                    q, v = self.advance(self.segs[K][0], t, q, v, ts + self.qT - t)
                    return [q[i] for i in free] + [v[i] for i in free]
                kn = (k + 1) % m
                # The nominal end time of segment k after the section, mapped past t.
                t_nom = self.starts[kn][0]
                while t_nom <= t - self.T / 1000:
                    t_nom += self.qT
                s = findroot(lambda s_: self.end_value(self.segs[k], t, q, v, s_)[0], t_nom - t)
                _, qe, ve = self.end_value(self.segs[k], t, q, v, s)
                t, q, v = t + s, qe, self.jump(self.segs[k], ve)
        h = mpf("1e-20")
        base = [qs[i] for i in free] + [vs[i] for i in free]
        P = len(base)
        J = matrix(P, P)
        for c in range(P):
            up, dn = list(base), list(base)
            up[c] += h
            dn[c] -= h
            a, b = ret(up), ret(dn)
            for r in range(P):
                J[r, c] = (a[r] - b[r]) / (2 * h)
        return list(eig(J, left=False, right=False))
