#!/usr/bin/env python3
"""Independent checker of a `vibro prove` certificate (docs/prove.md).

Re-verifies every inequality of the certificate from the certificate alone, with mpmath's interval
arithmetic (mpmath.iv, 128 bits). It shares no code with the C++ prover: the closed forms of the
flight, the impact law and the reaction, the Krawczyk operator, the positivity of the gap and of
the reaction, and the monodromy are written again here from the model (the paper's eqs (5),
(10)-(14); docs/model.md §2-§5).

    vibro_check_proof.py CERT.json [--json]

CERT.json holds one certificate, or {"certificates": [...]} (`vibro prove --branch --out`): each
is checked.

Exit 0: the certificate proves what it claims. Exit 1: it does not (the first failure is printed).
Exit 2: the file is not a certificate.
"""
import json
import sys

from mpmath import iv, mp, mpf

iv.prec = 128
mp.prec = 128


class Rejected(Exception):
    pass


def lo(x):
    return mpf(x._mpi_[0])


def hi(x):
    return mpf(x._mpi_[1])


def ilo(x):
    return iv.mpf(lo(x))


def ihi(x):
    return iv.mpf(hi(x))


def positive(x):
    return (x > 0) is True


def negative(x):
    return (x < 0) is True


def point(v):
    return iv.mpf(float(v))  # a double of the certificate, exactly


def hull(a, b):
    return iv.mpf([float(a), float(b)])


def pair(p):
    return hull(p[0], p[1])


def overlaps(x, p):
    """The certificate's enclosure p = [lo, hi] meets the checker's x."""
    return not (hi(x) < mpf(float(p[0])) or lo(x) > mpf(float(p[1])))


# ---- Forward differentiation over intervals (the Krawczyk test needs J over the whole box) ----

class D:
    """A value and its gradient, both intervals; an empty gradient is a constant."""

    def __init__(self, v, g=None):
        self.v = v if isinstance(v, type(iv.mpf(0))) else iv.mpf(v)
        self.g = g or {}

    @staticmethod
    def lift(x):
        return x if isinstance(x, D) else D(x)

    def __add__(self, o):
        o = D.lift(o)
        g = dict(self.g)
        for k, d in o.g.items():
            g[k] = g[k] + d if k in g else d
        return D(self.v + o.v, g)

    __radd__ = __add__

    def __neg__(self):
        return D(-self.v, {k: -d for k, d in self.g.items()})

    def __sub__(self, o):
        return self + (-D.lift(o))

    def __rsub__(self, o):
        return D.lift(o) - self

    def __mul__(self, o):
        o = D.lift(o)
        g = {k: d * o.v for k, d in self.g.items()}
        for k, d in o.g.items():
            g[k] = g[k] + self.v * d if k in g else self.v * d
        return D(self.v * o.v, g)

    __rmul__ = __mul__

    def __truediv__(self, o):
        o = D.lift(o)
        inv = 1 / o.v
        return self * D(inv, {k: -d * inv * inv for k, d in o.g.items()})

    def __rtruediv__(self, o):
        return D.lift(o) / self


def dsin(x):
    if isinstance(x, D):
        c = iv.cos(x.v)
        return D(iv.sin(x.v), {k: c * d for k, d in x.g.items()})
    return iv.sin(x)


def dcos(x):
    if isinstance(x, D):
        s = -iv.sin(x.v)
        return D(iv.cos(x.v), {k: s * d for k, d in x.g.items()})
    return iv.cos(x)


# ---- The model ---------------------------------------------------------------------------------

def parameter(text):
    """A decimal ("1.1"), or "[a, b]": every number between two decimals (a parameter interval of
    validated continuation)."""
    if not isinstance(text, str):
        raise TypeError(f"a parameter is a decimal text, got {text!r}")
    if text.startswith("[") and text.endswith("]"):
        a, b = (iv.mpf(x.strip()) for x in text[1:-1].split(","))
        return iv.mpf([lo(a), hi(b)])
    if not text or any(ch not in "0123456789.eE+-" for ch in text):
        raise ValueError(f"not a decimal: {text!r}")
    return iv.mpf(text)


class Model:
    def __init__(self, m):
        try:
            self.w_i = [parameter(t) for t in m["frequencies"]]
            self.TA = [parameter(t) for t in m["forcing"]]
            self.TB = [parameter(t) for t in m["contact"]]
            self.c = [parameter(t) for t in m["shape"]]
            self.x0 = parameter(m["stop"])
            self.r = parameter(m["restitution"])
            self.f = parameter(m["amplitude"])
            self.w = parameter(m["frequency"])
        except (KeyError, TypeError, ValueError) as e:
            raise Rejected(f"model: {e}")
        self.n = len(self.w_i)
        self.sA = sum((ci * ti for ci, ti in zip(self.c, self.TA)), iv.mpf(0))
        self.sB = sum((ci * ti for ci, ti in zip(self.c, self.TB)), iv.mpf(0))
        self.T = 2 * iv.pi / self.w

    def flight(self, t0, X, V, s):
        """Closed-form free flight from (t0, X, V) over s (eqs (13)-(14)) in the cancellation-free form
        (docs/model.md §2): X(t0+s) = X cos ω_i s + V sin(ω_i s)/ω_i + T_A f K(s), with
        K = [sin ωt0 (cos ωs − cos ω_i s) + cos ωt0 (sin ωs − (ω/ω_i) sin ω_i s)]/(ω_i² − ω²),
        cos x − 1 = −2 sin²(x/2). Returns X(t0+s), V(t0+s) as D."""
        L = D.lift
        t0, s, X, V = L(t0), L(s), [L(x) for x in X], [L(v) for v in V]
        w = L(self.w)
        sin0, cos0 = dsin(w * t0), dcos(w * t0)
        sw, hw = dsin(w * s), dsin(L(iv.mpf(0.5)) * w * s)
        cw_m1 = -(L(2) * hw * hw)
        Xo, Vo = [], []
        for i in range(self.n):
            wi = L(self.w_i[i])
            den = L(self.w_i[i] ** 2 - self.w ** 2)
            kappa = L(self.TA[i] * self.f)
            sn, hi_ = dsin(wi * s), dsin(L(iv.mpf(0.5)) * wi * s)
            c_m1 = -(L(2) * hi_ * hi_)
            dcos_ = cw_m1 - c_m1
            dsin_ = sw - (w / wi) * sn
            K = (sin0 * dcos_ + cos0 * dsin_) / den
            Kp = (sin0 * (wi * sn - w * sw) + w * cos0 * dcos_) / den
            Xo.append(X[i] + X[i] * c_m1 + V[i] * sn / wi + kappa * K)
            Vo.append(V[i] + V[i] * c_m1 - X[i] * wi * sn + kappa * Kp)
        return Xo, Vo

    def contact(self, X):
        out = D(0)
        for ci, xi in zip(self.c, X):
            out = D.lift(xi) * D(ci) + out
        return out

    def impact(self, V):
        p = self.contact(V) * D(-(1 + self.r) / self.sB)
        return [D.lift(V[i]) + p * D(self.TB[i]) for i in range(self.n)]

    def contact_acceleration(self, t, X):
        a = self.sA * self.f * iv.sin(self.w * t)
        for i in range(self.n):
            a = a - self.c[i] * self.w_i[i] ** 2 * X[i]
        return a

    def derivative_bound(self, t0, X, V, order):
        """max |d^order/ds^order of c.X(t0+s)|: sum of amplitudes times pulsation^order."""
        total, forced = iv.mpf(0), iv.mpf(0)
        for i in range(self.n):
            wi = self.w_i[i]
            amp = self.TA[i] * self.f / (wi * wi - self.w * self.w)
            A = X[i] - amp * iv.sin(self.w * t0)
            B = (V[i] - amp * self.w * iv.cos(self.w * t0)) / wi
            total += abs(self.c[i]) * wi ** order * iv.sqrt(A * A + B * B)
            forced += self.c[i] * amp
        return total + abs(forced) * self.w ** order


# ---- Bookkeeping: every inequality the certificate lists must be recomputed here ---------------

class Book:
    def __init__(self, cert):
        self.listed = {}
        for e in cert.get("inequalities", []):
            self.listed.setdefault((e["name"], e["where"]), []).append(e)
        self.done = set()

    def check(self, holds, name, where, x):
        key = (name, where)
        if key not in self.listed:
            raise Rejected(f"the certificate does not list '{name}' at {where}")
        for e in self.listed[key]:
            if not overlaps(x, e["enclosure"]):
                raise Rejected(f"{name} at {where}: the certificate's enclosure {e['enclosure']} misses the checker's {x}")
            if not e.get("holds", False):
                raise Rejected(f"{name} at {where}: the certificate itself says it fails")
        if not holds:
            raise Rejected(f"{name} at {where} does not hold: checker's enclosure {x}")
        self.done.add(key)

    def finish(self):
        missing = [k for k in self.listed if k not in self.done]
        if missing:
            raise Rejected(f"inequalities the checker could not recompute: {missing[:3]}")


def positive_pieces(pieces, a, b, value, slope, what):
    """f > 0 on [a, b]: the pieces are contiguous, cover [a, b], and on each the mean-value form
    f(c) + f'(I)(I - c) lies above 0."""
    if not pieces:
        raise Rejected(f"{what}: no pieces")
    if mpf(float(pieces[0][0])) > a:
        raise Rejected(f"{what}: the pieces start after {a}")
    if mpf(float(pieces[-1][1])) < b:
        raise Rejected(f"{what}: the pieces end before {b}")
    for k, (p0, p1) in enumerate(pieces):
        if k > 0 and float(pieces[k - 1][1]) != float(p0):
            raise Rejected(f"{what}: a hole between pieces {k - 1} and {k}")
        if not float(p0) < float(p1):
            raise Rejected(f"{what}: piece {k} is empty")
        c = point((float(p0) + float(p1)) / 2)
        I = hull(p0, p1)
        f = value(c) + slope(I) * (I - c)
        if not positive(f):
            raise Rejected(f"{what}: not positive on [{p0}, {p1}]: {f}")


# ---- Impacting orbits --------------------------------------------------------------------------

def check_impact(cert, m, book):
    q = int(cert["period"])
    names = cert["unknowns"]
    u = [float(x) for x in cert["midpoint"]]
    box = cert["box"]
    C = cert["preconditioner"]
    N = len(u)
    n = m.n
    if N % (2 * n + 1) or len(box) != N or len(C) != N or any(len(r) != N for r in C):
        raise Rejected("the box, midpoint and preconditioner do not fit the model")
    count = N // (2 * n + 1)
    qT = q * m.T

    def unpack(vec, j):
        b = j * (2 * n + 1)
        return vec[b], vec[b + 1:b + 1 + n], vec[b + 1 + n:b + 1 + 2 * n]

    def residual(vec):
        out = []
        for j in range(count):
            k = (j + 1) % count
            t, X, V = unpack(vec, j)
            tn, Xn, Vn = unpack(vec, k)
            if j == count - 1:
                tn = tn + qT
            Xe, Ve = m.flight(t, X, V, tn - t)
            Vp = m.impact(Ve)
            out.append(m.contact(X) - m.x0)
            out += [Xe[i] - Xn[i] for i in range(n)]
            out += [Vp[i] - Vn[i] for i in range(n)]
        return out

    # Krawczyk: K = u - C F(u) + (I - C J(U))(U - u) inside the open box.
    lo_, hi_ = [float(b[0]) for b in box], [float(b[1]) for b in box]
    if any(not (lo_[p] < u[p] < hi_[p]) for p in range(N)):
        raise Rejected("the midpoint is not inside the box")
    U = [hull(lo_[p], hi_[p]) for p in range(N)]
    F = [r.v for r in residual([point(x) for x in u])]
    R = residual([D(U[p], {p: iv.mpf(1)}) for p in range(N)])
    J = [[r.g.get(l, iv.mpf(0)) for l in range(N)] for r in R]
    for p in range(N):
        k = point(u[p])
        for l in range(N):
            k -= point(C[p][l]) * F[l]
            row = iv.mpf(1 if p == l else 0)
            for j in range(N):
                row -= point(C[p][j]) * J[j][l]
            k += row * (U[l] - point(u[l]))
        inside = lo(k) > lo_[p] and hi(k) < hi_[p]
        book.check(inside, "krawczyk", names[p], k)

    # No contact between the impacts; the monodromy along the way.
    flights = cert["flights"]
    if len(flights) != count:
        raise Rejected("one flight per impact expected")
    M = [[iv.mpf(1 if i == j else 0) for j in range(2 * n)] for i in range(2 * n)]
    for j in range(count):
        k = (j + 1) % count
        t, X, V = unpack(U, j)
        tn = unpack(U, k)[0] + (qT if j == count - 1 else 0)
        S = tn - t
        Xe, Ve = m.flight(t, X, V, S)
        a, vm = m.contact(V).v, m.contact(Ve).v
        M2 = m.derivative_bound(t, X, V, 2)
        where = f"flight {j} (impact {j} to impact {k})"
        book.check(positive(S), "duration", where, S)
        book.check(positive(a), "contact velocity after impact", where, a)
        book.check(negative(vm), "contact velocity before impact", where, vm)
        book.check(hi(M2) < mpf("inf"), "second-derivative bound", where, M2)
        fl = flights[j]
        ws, we = point(fl["start_window"]), point(fl["end_window"])
        a_low, b_low = point(fl["velocity_after_lower"]), point(fl["speed_before_lower"])
        if not (hi(a_low) <= lo(a) and hi(b_low) <= lo(-vm)):
            raise Rejected(f"{where}: the certificate's velocity bounds are not below the checker's enclosures")
        start = a_low - M2 * ws / 2   # g(s) >= s (a - M2 s/2) on (0, ws]
        end = b_low - M2 * we / 2     # g(S - σ) >= σ (b - M2 σ/2) on (0, we]
        book.check(positive(start) and positive(ws), "start window a - M2 ws/2", where, start)
        book.check(positive(end) and positive(we), "end window b - M2 we/2", where, end)
        top = hi(ihi(S) - we)
        if lo(ws) < top:
            positive_pieces(fl["pieces"], lo(ws), top,
                            lambda s: m.contact(m.flight(t, X, V, s)[0]).v - m.x0,
                            lambda s: m.contact(m.flight(t, X, V, s)[1]).v, f"gap on {where}")
        # Flight and saltation matrices (docs/model.md §5.6).
        Phi = [[iv.mpf(0)] * (2 * n) for _ in range(2 * n)]
        for i in range(n):
            c, s = iv.cos(m.w_i[i] * S), iv.sin(m.w_i[i] * S)
            Phi[i][i], Phi[i][n + i], Phi[n + i][i], Phi[n + i][n + i] = c, s / m.w_i[i], -m.w_i[i] * s, c
        aB = m.contact_acceleration(tn, [x.v for x in Xe])
        Sal = [[iv.mpf(0)] * (2 * n) for _ in range(2 * n)]
        for i in range(n):
            for l in range(n):
                pr = (1 if i == l else 0) - (1 + m.r) * m.TB[i] * m.c[l] / m.sB
                Sal[i][l] = pr
                Sal[n + i][n + l] = pr
                Sal[n + i][l] = (1 + m.r) * aB * m.TB[i] * m.c[l] / (m.sB * vm)
        M = matmul(Sal, matmul(Phi, M))
    check_spectrum(cert, M)


def matmul(A, B):
    return [[sum((A[i][k] * B[k][j] for k in range(len(B))), iv.mpf(0)) for j in range(len(B[0]))] for i in range(len(A))]


def check_spectrum(cert, M):
    claim = cert["summary"].get("stability", "undecided")
    listed = cert["summary"].get("multipliers", [])
    for i, row in enumerate(cert.get("monodromy", [])):
        for j, e in enumerate(row):
            if not overlaps(M[i][j], e):
                raise Rejected(f"monodromy[{i}][{j}]: the certificate's {e} misses the checker's {M[i][j]}")
    if claim == "undecided":
        return
    if len(M) != 2:
        return check_spectrum_general(claim, listed, M)
    tr, det = M[0][0] + M[1][1], M[0][0] * M[1][1] - M[0][1] * M[1][0]
    disc = tr * tr - 4 * det
    if positive(disc):
        r = iv.sqrt(disc)
        mods = [((tr + r) / 2) ** 2, ((tr - r) / 2) ** 2]
        found = [((tr + r) / 2, iv.mpf(0)), ((tr - r) / 2, iv.mpf(0))]
    elif negative(disc):
        mods = [det, det]
        im = iv.sqrt(-disc) / 2
        found = [(tr / 2, im), (tr / 2, -im)]
    else:
        # Real or complex: both lie in tr/2 + [-1, 1] sqrt(disc+)/2 + i [-1, 1] sqrt(disc-)/2.
        zero = mpf(0)
        pos = iv.mpf([zero, max(hi(disc), zero)])
        neg = iv.mpf([zero, max(-lo(disc), zero)])
        re = tr / 2 + iv.mpf([-1, 1]) * iv.sqrt(pos) / 2
        im = iv.mpf([-1, 1]) * iv.sqrt(neg) / 2
        mods = [re * re + im * im] * 2
        found = [(re, im), (re, im)]
    for (re, im), e in zip(found, listed):
        if not (overlaps(re, e["re"]) and overlaps(im, e["im"])):
            raise Rejected(f"multiplier {e} misses the checker's {re} + i {im}")
    if claim == "stable" and not all(hi(x) < 1 for x in mods):
        raise Rejected(f"'stable' claimed, |multiplier|^2 in {mods}")
    if claim == "unstable" and not any(lo(x) > 1 for x in mods):
        raise Rejected(f"'unstable' claimed, |multiplier|^2 in {mods}")


def check_spectrum_general(claim, listed, M):
    """Every eigenvalue of every matrix in the interval matrix M, each enclosed by Krawczyk's test on
    the eigenpair equations (A − λ)v = 0, v_k = 1 (real form, λ = a + ib, v = x + iy), around the
    approximate eigenpairs (numpy, not part of the proof). Disjoint boxes, as many as the dimension:
    all eigenvalues are enclosed."""
    import numpy as np
    n = len(M)
    mid = np.array([[float(mp.mpf((lo(x) + hi(x)) / 2)) for x in row] for row in M])
    values, vectors = np.linalg.eig(mid)
    boxes = []
    for e in range(n):
        lam, vec = values[e], vectors[:, e]
        k = int(np.argmax(np.abs(vec)))
        vec = vec / vec[k]
        free = [j for j in range(n) if j != k]
        z0 = [lam.real, lam.imag] + [vec[j].real for j in free] + [vec[j].imag for j in free]
        size = len(z0)

        def unpack(z):
            x = [iv.mpf(1) if j == k else None for j in range(n)]
            y = [iv.mpf(0) if j == k else None for j in range(n)]
            for i, j in enumerate(free):
                x[j], y[j] = z[2 + i], z[2 + len(free) + i]
            return z[0], z[1], x, y

        def F(z):
            a, b, x, y = unpack(z)
            re = [sum((M[i][j] * x[j] for j in range(n)), iv.mpf(0)) - a * x[i] + b * y[i] for i in range(n)]
            im = [sum((M[i][j] * y[j] for j in range(n)), iv.mpf(0)) - a * y[i] - b * x[i] for i in range(n)]
            return re + im

        def J(z):
            a, b, x, y = unpack(z)
            rows = []
            for part in (0, 1):
                for i in range(n):
                    row = [-x[i], y[i]] if part == 0 else [-y[i], -x[i]]
                    for j in free:  # d/dx_j
                        row.append((M[i][j] - (a if i == j else 0)) if part == 0 else (-b if i == j else iv.mpf(0)))
                    for j in free:  # d/dy_j
                        row.append((b if i == j else iv.mpf(0)) if part == 0 else (M[i][j] - (a if i == j else 0)))
                    rows.append(row)
            return rows

        Fz = F([iv.mpf(v) for v in z0])
        for scale in (1e-9, 1e-7, 1e-5, 1e-3):  # boxes from tight to wide, as the enclosure of M allows
            rad = [scale * (1 + abs(v)) for v in z0]
            Z = [iv.mpf([z0[p] - rad[p], z0[p] + rad[p]]) for p in range(size)]
            Jz = J(Z)
            C = np.linalg.inv(np.array([[float(mp.mpf((lo(x) + hi(x)) / 2)) for x in row] for row in Jz]))
            inside = True
            for p in range(size):
                kz = iv.mpf(z0[p])
                for l in range(size):
                    kz -= iv.mpf(float(C[p][l])) * Fz[l]
                    row = iv.mpf(1 if p == l else 0)
                    for j in range(size):
                        row -= iv.mpf(float(C[p][j])) * Jz[j][l]
                    kz += row * (Z[l] - iv.mpf(z0[l]))
                inside = inside and lo(kz) > lo(Z[p]) and hi(kz) < hi(Z[p])
            if inside:
                break
        if not inside:
            raise Rejected(f"stability '{claim}': the eigenvalue near {lam} could not be enclosed")
        boxes.append((Z[0], Z[1]))
    for i in range(n):
        for j in range(i):
            apart = hi(boxes[i][0]) < lo(boxes[j][0]) or hi(boxes[j][0]) < lo(boxes[i][0]) or \
                hi(boxes[i][1]) < lo(boxes[j][1]) or hi(boxes[j][1]) < lo(boxes[i][1])
            if not apart:
                raise Rejected(f"stability '{claim}': two eigenvalue enclosures overlap")
    mods = [a * a + b * b for a, b in boxes]
    for e in listed:
        if not any(overlaps(a, e["re"]) and overlaps(b, e["im"]) for a, b in boxes):
            raise Rejected(f"multiplier {e} is not one of the checker's enclosures")
    if claim == "stable" and not all(hi(x) < 1 for x in mods):
        raise Rejected(f"'stable' claimed, |multiplier|^2 in {mods}")
    if claim == "unstable" and not any(lo(x) > 1 for x in mods):
        raise Rejected(f"'unstable' claimed, |multiplier|^2 in {mods}")


# ---- One-DOF sticking orbits with r = 0 --------------------------------------------------------

def check_sticking(cert, m, book):
    if m.n != 1 or not (lo(m.r) >= 0 and hi(m.r) < 1):
        raise Rejected("a sticking certificate needs one mode and 0 <= r < 1")
    plastic = lo(m.r) == 0 and hi(m.r) == 0
    w, w1s, kappa, TB, x0 = m.w, m.w_i[0] ** 2, m.TA[0] * m.f, m.TB[0], m.x0
    rel = "release"
    ratio = w1s * x0 / kappa
    book.check(positive(kappa) or negative(kappa), "forcing T_A f", rel, kappa)
    book.check(positive(1 - abs(ratio)), "1 - |omega_1^2 x0/(T_A f)|", rel, 1 - abs(ratio))
    # phi1 from the certificate's enclosure P: sin is monotonic on P and sin(P) brackets the ratio.
    P = pair(cert["release"]["phase"])
    half = iv.pi / 2
    if positive(kappa):
        ok = lo(P) > hi(-half) and hi(P) < lo(half) and hi(iv.sin(lo(P))) < lo(ratio) and lo(iv.sin(hi(P))) > hi(ratio)
    else:
        ok = lo(P) > hi(half) and hi(P) < lo(3 * half) and lo(iv.sin(lo(P))) > hi(ratio) and hi(iv.sin(hi(P))) < lo(ratio)
    if not ok:
        raise Rejected(f"the release phase {P} does not enclose the root of the reaction")
    # A tighter enclosure of the same root (the certificate's is rounded to doubles; a chattering
    # sequence amplifies the width of the release time), verified the same way.
    r_mid = (lo(ratio) + hi(ratio)) / 2
    phi = mp.asin(r_mid) if positive(kappa) else mp.pi - mp.asin(r_mid)
    eps = mpf(2) ** -100
    T_ = iv.mpf([phi - eps, phi + eps])
    if positive(kappa):
        tight = hi(iv.sin(lo(T_))) < lo(ratio) and lo(iv.sin(hi(T_))) > hi(ratio)
    else:
        tight = lo(iv.sin(lo(T_))) > hi(ratio) and hi(iv.sin(hi(T_))) < lo(ratio)
    if tight and lo(T_) >= lo(P) and hi(T_) <= hi(P):
        P = T_
    tr = P / w
    rate = -(kappa * w * iv.cos(P)) / TB
    book.check(negative(rate), "reaction rate", rel, rate)
    reaction = lambda t: (w1s * x0 - kappa * iv.sin(w * t)) / TB
    X0 = [x0]
    flights = cert["flights"]
    if not flights:
        raise Rejected("no flight")
    t, tL, vplus = tr, None, None
    for k, flight in enumerate(flights):
        fl, land = f"flight {k}", f"landing {k}"
        V0 = [iv.mpf(0)] if vplus is None else [vplus]
        gap = lambda s, t=t, V0=V0: m.contact(m.flight(t, X0, V0, s)[0]).v - x0
        slope = lambda s, t=t, V0=V0: m.contact(m.flight(t, X0, V0, s)[1]).v
        ws = point(flight["start_window"])
        if vplus is not None:
            if flight.get("start") != "impact":
                raise Rejected(f"{fl} starts at an impact")
            M2 = m.derivative_bound(t, X0, V0, 2)
            book.check(positive(vplus), "contact velocity after impact", fl, vplus)
            book.check(hi(M2) < mpf("inf"), "second-derivative bound", fl, M2)
            a_low = point(flight["velocity_after_lower"])
            if not hi(a_low) <= lo(vplus):
                raise Rejected(f"{fl}: the certificate's bound on the speed after impact is not below the checker's enclosure")
            margin = a_low - M2 * ws / 2   # g(s) >= s (a - M2 s/2) on (0, ws]
            book.check(positive(margin) and positive(ws), "start window a - M2 ws/2", fl, margin)
        elif k == 0:
            if flight.get("start") != "release":
                raise Rejected("the first flight starts at the release")
            g3 = kappa * w * iv.cos(w * t)   # third derivative of x at rest on the stop
            M4 = m.derivative_bound(t, X0, V0, 4)
            book.check(positive(g3), "third derivative of the gap", fl, g3)
            book.check(hi(M4) < mpf("inf"), "fourth-derivative bound", fl, M4)
            g3_low = point(flight["third_derivative_lower"])
            if not hi(g3_low) <= lo(g3):
                raise Rejected(f"{fl}: the certificate's bound on g''' is not below the checker's enclosure")
            margin = g3_low / 6 - M4 * ws / 24   # g(s)/s^3 >= g'''/6 - M4 s/24 on (0, ws]
            book.check(positive(margin) and positive(ws), "start window g'''/6 - M4 ws/24", fl, margin)
        else:
            if flight.get("start") != "departure":
                raise Rejected(f"{fl} starts at a departure")
            g2 = kappa * iv.sin(w * t) - w1s * x0   # x'' at rest on the stop = -T_B R > 0
            M3 = m.derivative_bound(t, X0, V0, 3)
            book.check(positive(g2), "second derivative of the gap", fl, g2)
            book.check(hi(M3) < mpf("inf"), "third-derivative bound", fl, M3)
            g2_low = point(flight["second_derivative_lower"])
            if not hi(g2_low) <= lo(g2):
                raise Rejected(f"{fl}: the certificate's bound on g'' is not below the checker's enclosure")
            margin = g2_low / 2 - M3 * ws / 6    # g(s)/s^2 >= g''/2 - M3 s/6 on (0, ws]
            book.check(positive(margin) and positive(ws), "start window g''/2 - M3 ws/6", fl, margin)
        s0 = float(flight["landing_center"])
        Slo, Shi = (float(x) for x in flight["landing_box"])
        S = hull(Slo, Shi)
        gp = slope(S)
        Nw = point(s0) - gap(point(s0)) / gp
        book.check(negative(gp), "contact velocity at the landing", land, gp)
        book.check(lo(Nw) > Slo and hi(Nw) < Shi, "interval Newton", land, Nw)
        book.check(positive(S.a - ws), "landing after the start window", land, S.a - ws)
        positive_pieces(flight["pieces"], lo(ws), mpf(Slo), gap, slope, f"gap on {fl}")
        tL = t + Nw
        R_land = reaction(tL)
        if not plastic:
            # r > 0: the body bounces, x'+ = -r x'- (the speed from the tight enclosure of the landing).
            vminus = slope(Nw)
            if vplus is not None:
                # Centred form of the landing as a function of the flight's start (t, v): the value
                # at the centre plus the derivatives over the box times the offsets (mean-value
                # theorem; s(t, v) stays in Nw over the box).
                tc, vc = mp.mpf((lo(t) + hi(t)) / 2), mp.mpf((lo(vplus) + hi(vplus)) / 2)
                Tc, Vc = iv.mpf(tc), iv.mpf(vc)
                gap_c = lambda s_, Tc=Tc, Vc=Vc: m.contact(m.flight(Tc, X0, [Vc], s_)[0]).v - x0
                slope_c = lambda s_, Tc=Tc, Vc=Vc: m.contact(m.flight(Tc, X0, [Vc], s_)[1]).v
                Nc = point(s0) - gap_c(point(s0)) / slope_c(S)
                Xe, Ve = m.flight(D(t, {0: iv.mpf(1)}), [D(x0)], [D(vplus, {1: iv.mpf(1)})], D(Nw, {2: iv.mpf(1)}))
                g, vel = m.contact(Xe), m.contact(Ve)
                zero = iv.mpf(0)
                gt, gv, gs = g.g.get(0, zero), g.g.get(1, zero), g.g.get(2, zero)
                vt, vv, vs = vel.g.get(0, zero), vel.g.get(1, zero), vel.g.get(2, zero)
                ds_dt, ds_dv = -gt / gs, -gv / gs
                dT, dV = t - Tc, vplus - Vc
                if lo(Nc) > Slo and hi(Nc) < Shi:
                    t_cent = Tc + Nc + (1 + ds_dt) * dT + ds_dv * dV
                    v_cent = slope_c(Nc) + (vt + vs * ds_dt) * dT + (vv + vs * ds_dv) * dV
                    if hi(t_cent) - lo(t_cent) < hi(tL) - lo(tL):
                        tL = t_cent
                    if hi(v_cent) - lo(v_cent) < hi(vminus) - lo(vminus):
                        vminus = v_cent
            book.check(negative(vminus), "contact velocity before impact", land, vminus)
            vplus = -m.r * vminus
            landing_low = Slo + (t - tr)
            t = tL
            continue
        if k == len(flights) - 1:
            book.check(positive(R_land), "reaction at the landing", land, R_land)
            landing_low = Slo + (t - tr)  # the sticking phase starts in this box (as t - t_r)
        else:
            book.check(negative(R_land), "reaction at the landing", land, R_land)
            t = tL
    t_end = tL
    if not plastic:
        # The rest of the chattering sequence, bounded (docs/prove.md): on W = [t, t + L] with
        # T_B R in [A_lo, A_hi], A_lo > 0, every flight from speed v lasts at most 2v/A_lo and lands
        # at most r sqrt(a_hi/A_lo) v, a_hi = A_hi + w1^2 v^2/(2 A_lo); the impacts accumulate before
        # t + 2v/(A_lo (1 - rho)).
        tail = cert.get("tail")
        if tail is None or int(tail["after_flight"]) != len(flights) - 1:
            raise Rejected("a chattering certificate needs the tail after its last flight")
        tl = "chattering tail"
        v, L = point(tail["speed_upper"]), point(tail["window"])
        if not hi(vplus) <= lo(v):
            raise Rejected("the tail's speed bound is not above the checker's speed after the last impact")
        A = TB * reaction(iv.mpf([lo(tL), hi(ihi(tL) + L)]))
        A_low, A_high = point(tail["reaction_lower"]), point(tail["reaction_upper"])
        if not (hi(A_low) <= lo(A) and hi(A) <= lo(A_high)):
            raise Rejected("the tail's reaction bounds do not enclose the checker's reaction over the window")
        book.check(positive(A), "tail reaction T_B R over the window", tl, A)
        a_hi = A_high + w1s * v * v / (2 * A_low)
        rho = m.r * iv.sqrt(a_hi / A_low)
        book.check(positive(1 - rho), "tail contraction 1 - rho", tl, 1 - rho)
        Tmax = 2 * v / (A_low * (1 - rho))
        book.check(positive(L - Tmax), "tail window L - Tmax", tl, L - Tmax)
        # From below: each flight lasts at least 2v/a_hi and lands at least v sqrt(A_lo/a_hi) fast.
        v_low = point(tail["speed_lower"])
        if not (hi(v_low) <= lo(vplus) and positive(v_low)):
            raise Rejected("the tail's lower speed bound is not below the checker's speed after the last impact")
        rho_low = m.r * iv.sqrt(A_low / a_hi)
        Tmin = 2 * v_low / (a_hi * (1 - rho_low))
        t_end = iv.mpf([lo(ilo(tL) + Tmin), hi(ihi(tL) + Tmax)])
    turns = (t_end - tr) / m.T
    st = cert["sticking"]
    k = int(st["periods"])
    book.check(lo(turns) > k - 1 and hi(turns) < k, "landing time / T", "sticking phase", turns)
    if int(cert["period"]) != k:
        raise Rejected("the period is not the number of turns to the next release")
    M2R = abs(kappa) * w * w / TB
    we = point(st["end_window"])
    rate_low = point(st["rate_lower"])
    if not hi(rate_low) <= lo(-rate):
        raise Rejected("the certificate's bound on -R' is not below the checker's enclosure")
    end = rate_low - M2R * we / 2
    book.check(positive(end) and positive(we), "end window b - M2 we/2", "sticking phase", end)
    top = hi(ihi(k * m.T) - we)
    if lo(landing_low) < top:
        positive_pieces(st["pieces"], lo(landing_low), top,
                        lambda tau: reaction(tr + tau),
                        lambda tau: -(kappa * w * iv.cos(w * (tr + tau))) / TB, "reaction over the sticking phase")


def check(cert):
    if cert.get("format") != "vibro-proof-certificate/1":
        raise ValueError("not a vibro proof certificate (format)")
    if cert.get("verdict") != "proven":
        raise Rejected("the certificate claims no proof (verdict: %s)" % cert.get("verdict"))
    m = Model(cert["model"])
    book = Book(cert)
    kind = cert.get("kind")
    if kind == "impact":
        check_impact(cert, m, book)
    elif kind == "sticking":
        check_sticking(cert, m, book)
    else:
        raise Rejected(f"unknown kind {kind!r}")
    book.finish()
    return len(book.done)


def main(argv):
    args = [a for a in argv[1:] if a != "--json"]
    as_json = "--json" in argv[1:]
    if len(args) != 1:
        print(__doc__, file=sys.stderr)
        return 2
    try:
        with open(args[0]) as fh:
            cert = json.load(fh)
        if isinstance(cert, dict) and "certificates" in cert:  # `vibro prove --branch --out`: one per point
            count = 0
            for k, c in enumerate(cert["certificates"]):
                try:
                    count += check(c)
                except Rejected as e:
                    raise Rejected(f"point {k}: {e}")
            verdict, reason = "confirmed", f"{len(cert['certificates'])} certificates, {count} inequalities recomputed and verified"
        else:
            count = check(cert)
            verdict, reason = "confirmed", f"{count} inequalities recomputed and verified"
        code = 0
    except (OSError, ValueError) as e:
        print(f"vibro_check_proof: {args[0]}: {e}", file=sys.stderr)
        return 2
    except (Rejected, KeyError, TypeError, IndexError, ZeroDivisionError) as e:
        verdict, reason, code = "rejected", f"{type(e).__name__}: {e}" if not isinstance(e, Rejected) else str(e), 1
    if as_json:
        print(json.dumps({"verdict": verdict, "reason": reason}))
    else:
        print(f"{verdict}: {reason}")
    return code


if __name__ == "__main__":
    sys.exit(main(sys.argv))
