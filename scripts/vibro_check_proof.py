#!/usr/bin/python3
"""Independent checker of a `vibro prove` certificate (docs/prove.md, "What the checker checks").

    vibro_check_proof.py CERT.json [--json]

CERT.json holds one certificate, or {"branch": ..., "certificates": [...]} (`vibro prove --branch
--out`): each is checked.

Every claim the certificate makes is recomputed from the certificate alone, with mpmath's interval
arithmetic (mpmath.iv, 192 bits), and accepted only when the checker's own enclosure E of the true
value lies inside the claimed interval C (E ⊆ C, so the truth lies in C): the verdict, the kind,
the period (the orbit's least period), the sequence, every event's kind, contact, time, phase and
velocity, the section state, the multipliers and the stability, the box width, the reason, the
model's data, and every inequality the proof lists with its enclosure. The checker shares no code
with the C++ prover: the flight, the impact law, the reaction, Krawczyk's operator, the positivity
of the gap and of the reaction, the monodromy and the eigenvalue enclosures are written again here
from the model (the paper's eqs (5), (10)-(14); docs/model.md §2-§5). Its enclosures of the true
orbit are contracted far below the prover's widths (a Krawczyk test of its own on a box of relative
width ~1e-36 around a 192-bit Newton point inside the certificate's box), so a claim that excludes
the truth by one unit in the last place of a double is found.

One line is printed, and the exit code is
  0  "confirmed: ..."          every claim checked and true;
  1  "not confirmed: ..."      a claim that the checker's enclosures do not confirm (which, values);
  2  "not a certificate: ..."  the file is not a well-formed certificate (what, where).
"""
import copy
import json
import os
import re
import sys

from mpmath import iv, mp
from mpmath.libmp import libmpi, from_int

PREC = 192
iv.prec = PREC
mp.prec = PREC

# Bounds on what a certificate may hold (`vibro prove` stays within them, docs/prove.md).
MAX_BYTES = 64 << 20
MAX_UNKNOWNS = 128
MAX_MODES = 32
MAX_FLIGHTS = 1000
MAX_PIECES = 1_000_000
MAX_CERTIFICATES = 10_000
MAX_TEXT = 4096
FORMAT = "vibro-proof-certificate/1"
# The pieces of a parameter interval over which the true values are enclosed (check_impact).
PARAMETER_PIECES = 8


class NotACertificate(Exception):
    """Exit 2: malformed (what, where)."""


class NotConfirmed(Exception):
    """Exit 1: a claim the checker does not confirm (which claim, which values)."""


# ---- Intervals --------------------------------------------------------------------------------

ZERO, ONE = iv.mpf(0), iv.mpf(1)
_RAW_ZERO, _RAW_ONE = ZERO._mpi_, ONE._mpi_
IV = type(ZERO)


def lo(x):
    return mp.make_mpf(x._mpi_[0])


def hi(x):
    return mp.make_mpf(x._mpi_[1])


def finite(x):
    return mp.isfinite(lo(x)) and mp.isfinite(hi(x))


def positive(x):
    return finite(x) and lo(x) > 0


def negative(x):
    return finite(x) and hi(x) < 0


def excludes_zero(x):
    return positive(x) or negative(x)


def meet(a, b):
    """a ∩ b (both enclose the same value; None when they do not meet)."""
    l, h = max(lo(a), lo(b)), min(hi(a), hi(b))
    return iv.mpf([l, h]) if l <= h else None


def mid(x):
    return (lo(x) + hi(x)) / 2


def inside(small, big):
    return lo(big) <= lo(small) and hi(small) <= hi(big)


def show(x):
    """An mpf as a short decimal (17 digits)."""
    return mp.nstr(x, 17, min_fixed=-4, max_fixed=6)


def show_iv(x):
    return f"[{show(lo(x))}, {show(hi(x))}]"


def show_pair(p):
    return f"[{p[0]!r}, {p[1]!r}]"


# ---- Reading: every access typed and located ---------------------------------------------------

class Node:
    """A JSON value and where it is in the file ("summary.events[0].phase")."""
    __slots__ = ("v", "path")

    def __init__(self, v, path=""):
        self.v, self.path = v, path

    def fail(self, what):
        raise NotACertificate(f"{self.path or 'the file'}: {what}")

    def _child(self, key):
        if isinstance(key, int):
            return f"{self.path}[{key}]"
        return f"{self.path}.{key}" if self.path else key

    def obj(self, required, optional=()):
        if not isinstance(self.v, dict):
            self.fail(f"expected an object, got {kind_of(self.v)}")
        for k in required:
            if k not in self.v:
                self.fail(f"no '{k}'")
        for k in self.v:
            if k not in required and k not in optional:
                self.fail(f"unknown key '{k}'")
        return self

    def has(self, key):
        return isinstance(self.v, dict) and key in self.v

    def __getitem__(self, key):
        if isinstance(key, int):
            return Node(self.v[key], self._child(key))
        if not isinstance(self.v, dict) or key not in self.v:
            self.fail(f"no '{key}'")
        return Node(self.v[key], self._child(key))

    def items(self, at_least=0, at_most=None, exactly=None):
        if not isinstance(self.v, list):
            self.fail(f"expected a list, got {kind_of(self.v)}")
        n = len(self.v)
        if exactly is not None and n != exactly:
            self.fail(f"{n} entries, expected {exactly}")
        if n < at_least:
            self.fail(f"{n} entries, expected at least {at_least}")
        if at_most is not None and n > at_most:
            self.fail(f"{n} entries, more than the {at_most} a certificate may have")
        return [Node(x, self._child(k)) for k, x in enumerate(self.v)]

    def num(self):
        """A finite number, exactly (a double of the certificate, or an integer)."""
        x = self.v
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            self.fail(f"expected a number, got {kind_of(x)}")
        if isinstance(x, float) and x != x:
            self.fail("nan")
        if isinstance(x, int) and abs(x) > 2 ** 1024:
            self.fail("an integer beyond the range of doubles")
        if isinstance(x, float) and x in (float("inf"), float("-inf")):
            self.fail(f"{x} (bounds must be finite)")
        return mp.mpf(x)

    def point(self):
        return iv.mpf(self.num())

    def integer(self, least, most):
        x = self.v
        if isinstance(x, bool) or not isinstance(x, int):
            self.fail(f"expected an integer, got {kind_of(x)}")
        if not least <= x <= most:
            self.fail(f"{x}, expected an integer in [{least}, {most}]")
        return x

    def text(self, choices=None):
        x = self.v
        if not isinstance(x, str):
            self.fail(f"expected a text, got {kind_of(x)}")
        if len(x) > MAX_TEXT:
            self.fail(f"a text of {len(x)} characters")
        if choices is not None and x not in choices:
            self.fail(f"'{x}', expected one of {', '.join(repr(c) for c in choices)}")
        return x

    def boolean(self):
        if not isinstance(self.v, bool):
            self.fail(f"expected true or false, got {kind_of(self.v)}")
        return self.v

    def pair(self):
        """[lo, hi]: two finite numbers with lo <= hi, as an interval."""
        if not isinstance(self.v, list) or len(self.v) != 2:
            self.fail(f"expected [lo, hi], got {kind_of(self.v)}")
        a, b = self[0].num(), self[1].num()
        if not a <= b:
            self.fail(f"[{self.v[0]!r}, {self.v[1]!r}] has lo > hi")
        return iv.mpf([a, b])


def kind_of(x):
    if isinstance(x, bool):
        return f"{str(x).lower()}"
    if isinstance(x, (int, float)):
        return f"the number {x!r}"
    if isinstance(x, str):
        return f"the text {x[:40]!r}"
    if isinstance(x, list):
        return f"a list of {len(x)}"
    if isinstance(x, dict):
        return "an object"
    return "null" if x is None else type(x).__name__


DECIMAL = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d{1,4})?")


def decimal(node, text=None):
    """A decimal text ("1.1"), or "[a, b]": every number between two decimals (a parameter
    interval of validated continuation)."""
    t = node.text() if text is None else text
    if t.startswith("[") and t.endswith("]") and t.count(",") == 1:
        a, b = (s.strip() for s in t[1:-1].split(","))
        x, y = decimal(node, a), decimal(node, b)
        if not lo(x) <= hi(y):
            node.fail(f"'{t}' has lo > hi")
        return iv.mpf([lo(x), hi(y)])
    g = DECIMAL.fullmatch(t)
    if not g or (g.group(2) and abs(int(g.group(2)[1:])) > 400):
        node.fail(f"'{t}' is not a finite decimal")
    return iv.mpf(t)


# ---- Forward differentiation over intervals (Jacobians over a box) -----------------------------

class D:
    """A value and its gradient (a sparse dict index -> interval), both intervals."""
    __slots__ = ("v", "g")

    def __init__(self, v, g=None):
        self.v = v if isinstance(v, IV) else iv.mpf(v)
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


def dexp(x):
    if isinstance(x, D):
        e = iv.exp(x.v)
        return D(e, {k: e * d for k, d in x.g.items()})
    return iv.exp(x)


class J2:
    """A univariate second-order Taylor jet (value, first and second derivative), each an mpmath
    interval: forward differentiation to second order in one variable, for the Taylor form of a
    frequency segment (check_tangent). Over an interval of the variable, d2 encloses the second
    derivative there."""

    def __init__(self, v, d1=None, d2=None):
        self.v, self.d1, self.d2 = v, ZERO if d1 is None else d1, ZERO if d2 is None else d2

    @staticmethod
    def lift(x):
        return x if isinstance(x, J2) else J2(x)

    def __add__(self, o):
        o = J2.lift(o)
        return J2(self.v + o.v, self.d1 + o.d1, self.d2 + o.d2)

    __radd__ = __add__

    def __neg__(self):
        return J2(-self.v, -self.d1, -self.d2)

    def __sub__(self, o):
        return self + (-J2.lift(o))

    def __rsub__(self, o):
        return J2.lift(o) - self

    def __mul__(self, o):
        o = J2.lift(o)
        return J2(self.v * o.v, self.d1 * o.v + self.v * o.d1, self.d2 * o.v + 2 * self.d1 * o.d1 + self.v * o.d2)

    __rmul__ = __mul__

    def __truediv__(self, o):
        o = J2.lift(o)
        inv = 1 / o.v
        return self * J2(inv, -o.d1 * inv * inv, 2 * o.d1 * o.d1 * inv * inv * inv - o.d2 * inv * inv)

    def __rtruediv__(self, o):
        return J2.lift(o) / self

    def apply(self, f, f1, f2):
        """f(self) from f, f' and f'' at the value: (f∘x)'' = f''(x) x'² + f'(x) x''."""
        return J2(f, f1 * self.d1, f2 * self.d1 * self.d1 + f1 * self.d2)


_dsin, _dcos, _dexp = dsin, dcos, dexp


def dsin(x):  # noqa: F811
    if isinstance(x, J2):
        s, c = iv.sin(x.v), iv.cos(x.v)
        return x.apply(s, c, -s)
    return _dsin(x)


def dcos(x):  # noqa: F811
    if isinstance(x, J2):
        s, c = iv.sin(x.v), iv.cos(x.v)
        return x.apply(c, -s, -c)
    return _dcos(x)


def dexp(x):  # noqa: F811
    if isinstance(x, J2):
        e = iv.exp(x.v)
        return x.apply(e, e, e)
    return _dexp(x)


def value(x):
    return x.v if isinstance(x, D) else x


def variable(x, k):
    return D(x, {k: ONE})


# ---- The model ---------------------------------------------------------------------------------

MODEL_KEYS = ("frequencies", "forcing", "contact", "shape", "stop", "restitution", "amplitude", "frequency")


# How many flights the checker remembers (Model.flight) before it forgets them all (a few KB each).
FLIGHT_MEMO = 20_000
_FLIGHTS = {}


class Model:
    """The modal model of docs/model.md with exact decimal parameters: undamped, or with the modal
    damping ratios ζ_i of docs/model.md §7 ("damping", one per mode)."""

    def __init__(self, node):
        node.obj(MODEL_KEYS, ("damping", "more_contacts"))
        lists = {k: node[k].items(at_least=1, at_most=MAX_MODES) for k in MODEL_KEYS[:4]}
        n = len(lists["frequencies"])
        for k in MODEL_KEYS[1:4]:
            if len(lists[k]) != n:
                node[k].fail(f"{len(lists[k])} entries, model.frequencies has {n} (one per mode)")
        self.n = n
        self.w_i = [decimal(x) for x in lists["frequencies"]]
        self.TA = [decimal(x) for x in lists["forcing"]]
        self.TB = [decimal(x) for x in lists["contact"]]
        self.c = [decimal(x) for x in lists["shape"]]
        self.x0 = decimal(node["stop"])
        self.r = decimal(node["restitution"])
        self.f = decimal(node["amplitude"])
        self.w = decimal(node["frequency"])
        self.texts = {k: node[k].v for k in MODEL_KEYS}
        for k, w in enumerate(self.w_i):
            if not lo(w) > 0:
                lists["frequencies"][k].fail("a modal frequency must be > 0")
        if not lo(self.w) > 0:
            node["frequency"].fail("the forcing frequency must be > 0")
        if not (lo(self.r) >= 0 and hi(self.r) <= 1):
            node["restitution"].fail("the restitution must lie in [0, 1]")
        self.point = not any(isinstance(t, str) and t.startswith("[") for t in
                             [self.texts["stop"], self.texts["restitution"], self.texts["amplitude"],
                              self.texts["frequency"]] + [t for k in MODEL_KEYS[:4] for t in self.texts[k]])
        self.zeta = None
        if node.has("damping"):
            items = node["damping"].items(exactly=n)
            self.zeta = [decimal(x) for x in items]
            for k, z in enumerate(self.zeta):
                if not (lo(z) >= 0 and hi(z) < 1):
                    items[k].fail("a damping ratio must lie in [0, 1)")
            self.texts["damping"] = node["damping"].v
            self.point = self.point and not any(isinstance(t, str) and t.startswith("[") for t in node["damping"].v)
        self.sA = sum((ci * ti for ci, ti in zip(self.c, self.TA)), ZERO)
        self.sB = sum((ci * ti for ci, ti in zip(self.c, self.TB)), ZERO)
        # Every contact as (c_j, T_j, e_j, r_j, W_jj = c_j·T_j): the gap c_j·X − e_j ≥ 0 (docs/contacts.md).
        self.contacts = [(self.c, self.TB, self.x0, self.r, self.sB)]
        if node.has("more_contacts"):
            for k, cn in enumerate(node["more_contacts"].items(at_least=1, at_most=MAX_MODES)):
                cn.obj(("shape", "contact", "stop", "restitution"))
                c = [decimal(x) for x in cn["shape"].items(exactly=n)]
                T = [decimal(x) for x in cn["contact"].items(exactly=n)]
                e, r = decimal(cn["stop"]), decimal(cn["restitution"])
                if not (lo(r) >= 0 and hi(r) <= 1):
                    cn["restitution"].fail("the restitution must lie in [0, 1]")
                W = sum((ci * ti for ci, ti in zip(c, T)), ZERO)
                if not positive(W):
                    cn.fail("the contact's inverse effective mass shape·contact must be > 0")
                self.point = self.point and not any(isinstance(t, str) and t.startswith("[") for t in
                                                    cn.v["shape"] + cn.v["contact"] + [cn.v["stop"], cn.v["restitution"]])
                self.contacts.append((c, T, e, r, W))
        self.T = 2 * iv.pi / self.w
        # A parameter interval "[a, b]" of validated continuation: its two ends, as decimals.
        self.ends = {}
        for k in ("stop", "restitution", "amplitude", "frequency"):
            t = self.texts[k]
            if t.startswith("["):
                self.ends[k] = tuple(decimal(node[k], e.strip()) for e in t[1:-1].split(","))
        # Every parameter a point or an interval of relative width < 2^-100 (a physical scene's
        # enclosed modal data).
        every = self.w_i + self.TA + self.TB + self.c + [self.x0, self.r, self.f, self.w] + (self.zeta or []) + \
            [x for c_, T_, e_, r_, _ in self.contacts[1:] for x in c_ + T_ + [e_, r_]]
        self.thin = all(hi(x) - lo(x) <= mp.mpf(2) ** -100 * (1 + abs(mid(x))) for x in every)

    def affine_parameter(self):
        """The one parameter interval of the model (a segment of a branch) when the shooting
        residual below depends on it affinely: the amplitude f (the flight is linear in f: T_A f K,
        or the forced response P, Q ∝ f), contact 0's stop x0 (only in c·X − x0) or its restitution r
        (only in the impact law's factor (1 + r)). None otherwise (no interval, the forcing
        frequency, or more than one)."""
        if len(self.ends) == 1 and next(iter(self.ends)) in ("amplitude", "stop", "restitution"):
            return next(iter(self.ends))
        return None

    def frequency_interval(self):
        """True when the model's one parameter interval is the forcing frequency (a segment of a branch
        in ω): the residual is not affine in it, and Krawczyk's constant term takes the mean-value
        form in ω (frequency_slope)."""
        return len(self.ends) == 1 and "frequency" in self.ends

    def with_parameter(self, name, x):
        """This model with the parameter `name` (amplitude, stop, restitution, frequency) equal to x."""
        m = copy.copy(self)
        if name == "frequency":
            m.w = x
            m.T = 2 * iv.pi / x
            return m
        if name == "amplitude":
            m.f = x
        elif name == "stop":
            m.x0 = x
        else:
            m.r = x
        c, T, e, r, W = self.contacts[0]
        m.contacts = [(c, T, m.x0, m.r, W)] + self.contacts[1:]
        return m

    def damped_flight(self, t0, X, V, s):
        """The damped free flight (docs/model.md §7), written directly: per mode the forced response
        U = P sin ωt + Q cos ωt solving Ü + 2σU̇ + ω_i²U = T_A f sin ωt (σ = ζω_i), plus the free decay
        e^{−σs}(a cos ω_d s + b sin ω_d s), ω_d = ω_i√(1 − ζ²), matching X and V at t0."""
        dual = any(isinstance(z, D) for z in (t0, s, *X, *V))
        L = D.lift if dual else (lambda z: z)
        t0, s, X, V = L(t0), L(s), [L(x) for x in X], [L(v) for v in V]
        Xo, Vo = [], []
        for i in range(self.n):
            wi, w = self.w_i[i], self.w
            sg = self.zeta[i] * wi
            wd = wi * iv.sqrt(1 - self.zeta[i] ** 2)
            det, damp = wi * wi - w * w, 2 * sg * w
            P = L(self.TA[i] * self.f * det / (det * det + damp * damp))
            Q = L(-self.TA[i] * self.f * damp / (det * det + damp * damp))
            w, sg, wd = L(w), L(sg), L(wd)
            U = lambda t: P * dsin(w * t) + Q * dcos(w * t)  # noqa: E731
            Ud = lambda t: w * (P * dcos(w * t) - Q * dsin(w * t))  # noqa: E731
            a = X[i] - U(t0)
            b = (V[i] - Ud(t0) + a * sg) / wd
            e, cd, sd = dexp(-(s * sg)), dcos(s * wd), dsin(s * wd)
            Xo.append(U(t0 + s) + e * (a * cd + b * sd))
            Vo.append(Ud(t0 + s) + e * ((b * wd - a * sg) * cd - (a * wd + b * sg) * sd))
        return Xo, Vo

    def acceleration(self, t, X, V):
        """The free modal accelerations Ẍ_i = T_A,i f sin ωt − ω_i² X_i − 2ζ_iω_i Ẋ_i."""
        load = self.f * iv.sin(self.w * t)
        z = self.zeta or [ZERO] * self.n
        return [self.TA[i] * load - self.w_i[i] ** 2 * X[i] - 2 * z[i] * self.w_i[i] * V[i] for i in range(self.n)]

    def flight(self, t0, X, V, s):
        """The closed-form free flight from (t0, X, V) over s (eqs (13)-(14)) in the cancellation-free
        form of docs/model.md §2: X(t0+s) = X cos ω_i s + V sin(ω_i s)/ω_i + T_A f K(s),
        K = [sin ωt0 (cos ωs − cos ω_i s) + cos ωt0 (sin ωs − (ω/ω_i) sin ω_i s)]/(ω_i² − ω²),
        cos x − 1 = −2 sin²(x/2). Works on intervals and on D. Damped: damped_flight.
        On intervals the result is remembered by the exact endpoints of every input (the model's
        parameters, t0, X, V, s) and the precision: a pure function, computed once for each (the
        checker run on many edits of one certificate recomputes the same flights, FLIGHT_MEMO); so
        are flights of D (value and gradient), which nothing changes in place."""
        key = self._flight_key(t0, X, V, s)
        if key is not None:
            hit = _FLIGHTS.get(key)
            if hit is None:
                if len(_FLIGHTS) >= FLIGHT_MEMO:
                    _FLIGHTS.clear()
                hit = _FLIGHTS[key] = tuple(tuple(z) for z in self._flight(t0, X, V, s))
            return list(hit[0]), list(hit[1])
        return self._flight(t0, X, V, s)

    def _flight_key(self, t0, X, V, s):
        """The memo's key: the endpoints of every input, an interval or a D (its value and gradient,
        D is never changed in place), and of the model's parameters; None for anything else."""
        params = (self.f, self.w, *self.w_i, *self.TA, *(self.zeta or ()))
        if len(X) != self.n or len(V) != self.n or any(type(z) is not IV for z in params):
            return None
        key = [iv.prec, self.n, self.zeta is not None] + [z._mpi_ for z in params]
        for z in (t0, s, *X, *V):
            if type(z) is IV:
                key.append(z._mpi_)
            elif type(z) is D and type(z.v) is IV and all(type(d) is IV and type(k) is int for k, d in z.g.items()):
                key.append((z.v._mpi_, tuple(sorted((k, d._mpi_) for k, d in z.g.items()))))
            else:
                return None
        return tuple(key)

    def _flight(self, t0, X, V, s):
        if self.zeta is not None:
            return self.damped_flight(t0, X, V, s)
        if any(isinstance(z, D) for z in (t0, s, *X, *V)):
            L = D.lift
            t0, s, X, V = L(t0), L(s), [L(x) for x in X], [L(v) for v in V]
            w, half, two = L(self.w), L(iv.mpf(0.5)), L(iv.mpf(2))
        else:
            L = lambda z: z  # noqa: E731
            w, half, two = self.w, iv.mpf(0.5), iv.mpf(2)
        sin0, cos0 = dsin(w * t0), dcos(w * t0)
        sw, hw = dsin(w * s), dsin(half * w * s)
        cw_m1 = -(two * hw * hw)
        Xo, Vo = [], []
        for i in range(self.n):
            wi = L(self.w_i[i])
            den = L(self.w_i[i] ** 2 - self.w ** 2)
            kappa = L(self.TA[i] * self.f)
            sn, hn = dsin(wi * s), dsin(half * wi * s)
            c_m1 = -(two * hn * hn)
            K = (sin0 * (cw_m1 - c_m1) + cos0 * (sw - (w / wi) * sn)) / den
            Kp = (sin0 * (wi * sn - w * sw) + w * cos0 * (cw_m1 - c_m1)) / den
            Xo.append(X[i] + X[i] * c_m1 + V[i] * sn / wi + kappa * K)
            Vo.append(V[i] + V[i] * c_m1 - X[i] * wi * sn + kappa * Kp)
        return Xo, Vo

    def contact_of(self, X, j=0):
        """c_j·X (x_B, or ẋ_B of velocities; contact j's gap plus e_j, or its gap velocity)."""
        out = ZERO
        for ci, xi in zip(self.contacts[j][0], X):
            out = xi * ci + out if not isinstance(xi, D) else xi * D(ci) + out
        return out

    def impact(self, V, j=0):
        """The restitution law (10)-(12) at contact j: Ẋ⁺ = Ẋ⁻ − (1+r_j) T_j c_j·Ẋ⁻/W_jj."""
        c, T, e, r, W = self.contacts[j]
        p = self.contact_of(V, j) * (-(1 + r) / W)
        return [V[i] + p * T[i] if not isinstance(p, D) else D.lift(V[i]) + p * D(T[i])
                for i in range(self.n)]

    def contact_acceleration(self, t, X, j=0):
        c = self.contacts[j][0]
        a = sum((ci * ti for ci, ti in zip(c, self.TA)), ZERO) * self.f * iv.sin(self.w * t)
        for i in range(self.n):
            a = a - c[i] * self.w_i[i] ** 2 * X[i]
        return a

    def derivative_bound(self, t0, X, V, order, j=0):
        """max over s of |d^order/ds^order c·X(t0+s)|: the sum of the amplitudes times pulsation^order.
        Damped: a mode's free part e^{−σs}(a cos ω_d s + b sin ω_d s) is Re((a − ib) e^{(−σ+iω_d)s}),
        |−σ + iω_d| = ω_i, so for s ≥ 0 its derivatives are at most √(a² + b²) ω_i^order."""
        cj = self.contacts[j][0]
        if self.zeta is not None:
            total, fs, fc = ZERO, ZERO, ZERO
            for i in range(self.n):
                wi, w = self.w_i[i], self.w
                sg = self.zeta[i] * wi
                wd = wi * iv.sqrt(1 - self.zeta[i] ** 2)
                det, damp = wi * wi - w * w, 2 * sg * w
                P = self.TA[i] * self.f * det / (det * det + damp * damp)
                Q = -self.TA[i] * self.f * damp / (det * det + damp * damp)
                A = X[i] - P * iv.sin(w * t0) - Q * iv.cos(w * t0)
                B = (V[i] - w * (P * iv.cos(w * t0) - Q * iv.sin(w * t0)) + sg * A) / wd
                total += abs(cj[i]) * wi ** order * iv.sqrt(A * A + B * B)
                fs += cj[i] * P
                fc += cj[i] * Q
            return total + iv.sqrt(fs * fs + fc * fc) * self.w ** order
        total, forced = ZERO, ZERO
        for i in range(self.n):
            wi = self.w_i[i]
            amp = self.TA[i] * self.f / (wi * wi - self.w * self.w)
            A = X[i] - amp * iv.sin(self.w * t0)
            B = (V[i] - amp * self.w * iv.cos(self.w * t0)) / wi
            total += abs(cj[i]) * wi ** order * iv.sqrt(A * A + B * B)
            forced += cj[i] * amp
        return total + abs(forced) * self.w ** order

    def phase(self, t):
        """ωt reduced by the whole turns of its midpoint (the certificate's phase convention)."""
        wt = self.w * t
        turns = mp.floor(mid(wt) / (2 * mp.pi))
        return wt - iv.mpf(turns) * 2 * iv.pi


def flight_in_frequency(m, w, t0, X, V, s):
    """The free flight with the forcing frequency w a differentiation variable (a D or a J2; t0, X,
    V, s constants or of the same type): per mode the forced response U = P sin wt + Q cos wt of
    Ü + 2σU̇ + ω_i²U = T_A f sin wt, plus the free part e^{−σs}(a cos ω_d s + b sin ω_d s) matching X
    and V at t0 (σ = ζω_i, ω_d = ω_i√(1 − ζ²); undamped σ = 0, ω_d = ω_i). Written here in the plain
    form (docs/model.md §2 and §7), for ∂F/∂ω of a frequency segment only."""
    L = type(w).lift
    t0, s = L(t0), L(s)
    Xo, Vo = [], []
    for i in range(m.n):
        z = m.zeta[i] if m.zeta is not None else ZERO
        wi = L(m.w_i[i])
        sg, wd = L(z * m.w_i[i]), L(m.w_i[i] * iv.sqrt(1 - z * z))
        det = wi * wi - w * w
        damp = L(iv.mpf(2)) * sg * w
        den = det * det + damp * damp
        load = L(m.TA[i] * m.f)
        P, Q = load * det / den, -(load * damp / den)
        U = lambda t: P * dsin(w * t) + Q * dcos(w * t)  # noqa: E731
        Ud = lambda t: w * (P * dcos(w * t) - Q * dsin(w * t))  # noqa: E731
        a = L(X[i]) - U(t0)
        b = (L(V[i]) - Ud(t0) + a * sg) / wd
        e, cd, sd = dexp(-(s * sg)), dcos(s * wd), dsin(s * wd)
        Xo.append(U(t0 + s) + e * (a * cd + b * sd))
        Vo.append(Ud(t0 + s) + e * ((b * wd - a * sg) * cd - (a * wd + b * sg) * sd))
    return Xo, Vo


# ---- Claims ------------------------------------------------------------------------------------

def claim_contains(node, E, what):
    """The claim at `node`, [lo, hi], must contain the checker's enclosure E of the true value."""
    C = node.pair()
    if not inside(E, C):
        raise NotConfirmed(f"{node.path} = {show_pair(node.v)} does not contain {what}, which the checker "
                           f"encloses in {show_iv(E)}")
    return C


def claim_phase(node, E_time, model, what):
    """A phase claim: ωt reduced to [0, 2π) (the representative whose interval meets [0, 2π])."""
    C = node.pair()
    raw = model.w * E_time
    k = mp.nint((mid(raw) - mid(C)) / (2 * mp.pi))
    E = raw - iv.mpf(k) * 2 * iv.pi
    if not inside(E, C):
        raise NotConfirmed(f"{node.path} = {show_pair(node.v)} does not contain {what}, which the checker "
                           f"encloses in {show_iv(E)} (mod 2π)")
    if hi(C) < 0 or lo(C) >= 2 * mp.pi:
        raise NotConfirmed(f"{node.path} = {show_pair(node.v)} is not a phase in [0, 2π)")


def claim_upper(node, E, what):
    """A number claimed to bound the true value from above."""
    x = node.num()
    if not hi(E) <= x:
        raise NotConfirmed(f"{node.path} = {node.v!r} is not above {what}, which the checker encloses in {show_iv(E)}")


def claim_lower(node, E, what):
    x = node.num()
    if not x <= lo(E):
        raise NotConfirmed(f"{node.path} = {node.v!r} is not below {what}, which the checker encloses in {show_iv(E)}")


def holds(relation, x, box=None):
    if relation == "> 0":
        return positive(x)
    if relation == "< 0":
        return negative(x)
    if relation == "!= 0":
        return excludes_zero(x)
    if relation == ">= 0":
        return finite(x) and lo(x) >= 0
    if relation == "finite":
        return finite(x)
    if relation == "inside the box":
        return finite(x) and lo(x) > lo(box) and hi(x) < hi(box)
    m = re.fullmatch(r"inside \((-?\d+), (-?\d+)\)", relation)
    if m:
        return finite(x) and lo(x) > int(m.group(1)) and hi(x) < int(m.group(2))
    raise AssertionError(relation)


class Ledger:
    """The certificate's inequalities: each one recomputed here, once. For each: the checker's
    enclosure over the proof's domain must satisfy the relation (the proof), the record must say
    it holds, its own enclosure must satisfy the relation, and contain the checker's enclosure of
    the quantity's true value."""

    def __init__(self, node):
        self.records = {}
        for r in node.items(at_most=100 * MAX_FLIGHTS + MAX_UNKNOWNS):
            r.obj(("name", "where", "enclosure", "relation", "holds"))
            key = (r["name"].text(), r["where"].text())
            if key in self.records:
                r.fail(f"'{key[0]}' at {key[1]} listed twice")
            self.records[key] = r
        self.done = set()

    def check(self, name, where, relation, proof, truth, box=None):
        key = (name, where)
        r = self.records.get(key)
        if r is None:
            raise NotConfirmed(f"the certificate does not list the inequality '{name}' at {where}, which the "
                               f"proof needs")
        if r["relation"].text() != relation:
            raise NotConfirmed(f"{r.path}.relation: '{r['relation'].v}', the inequality '{name}' is '{relation}'")
        if not r["holds"].boolean():
            raise NotConfirmed(f"{r.path}: '{name}' at {where} does not hold, the certificate says")
        if not holds(relation, proof, box):
            raise NotConfirmed(f"'{name} {relation}' at {where} is not verified: the checker's enclosure is "
                               f"{show_iv(proof)}")
        C = r["enclosure"].pair()
        if not holds(relation, C, box):
            raise NotConfirmed(f"{r.path}.enclosure = {show_pair(r['enclosure'].v)} does not satisfy '{relation}'")
        claim_contains(r["enclosure"], truth, f"the value of '{name}' at {where}")
        self.done.add(key)

    def finish(self):
        missing = [k for k in self.records if k not in self.done]
        if missing:
            name, where = missing[0]
            raise NotConfirmed(f"the certificate lists {len(missing)} inequalities that the proof does not use, "
                               f"e.g. '{name}' at {where}")
        return len(self.done)


def positive_pieces(node, a, b, f_value, f_slope, what, budget):
    """f > 0 on [a, b]: the pieces are contiguous, cover [a, b], and on each the mean-value form
    f(c) + f'(I)(I - c) lies above 0."""
    pieces = node.items(at_least=1, at_most=MAX_PIECES)
    budget[0] -= len(pieces)
    if budget[0] < 0:
        node.fail(f"more than {MAX_PIECES} pieces in the certificate")
    vals = [(lo(x), hi(x)) for x in (p.pair() for p in pieces)]
    if vals[0][0] > a:
        raise NotConfirmed(f"{what}: the pieces start at {show(vals[0][0])}, after {show(a)}")
    if vals[-1][1] < b:
        raise NotConfirmed(f"{what}: the pieces end at {show(vals[-1][1])}, before {show(b)}")
    for k, (p0, p1) in enumerate(vals):
        if k > 0 and vals[k - 1][1] != p0:
            raise NotConfirmed(f"{what}: a hole or an overlap between pieces {k - 1} and {k}")
        if not p0 < p1:
            raise NotConfirmed(f"{node.path}[{k}]: an empty piece")
        c = iv.mpf((p0 + p1) / 2)
        I = iv.mpf([p0, p1])
        f = f_value(c) + f_slope(I) * (I - c)
        if not positive(f):
            raise NotConfirmed(f"{what}: not positive on {node.path}[{k}] = [{show(p0)}, {show(p1)}] ({show_iv(f)})")


# ---- Eigenvalues of an interval matrix ---------------------------------------------------------

def eigenvalues(M):
    """Every eigenvalue of every matrix in the interval matrix M, enclosed: disjoint boxes
    (re, im), one per eigenvalue; None when the checker cannot separate them."""
    n = len(M)
    if n == 2:
        tr, det = M[0][0] + M[1][1], M[0][0] * M[1][1] - M[0][1] * M[1][0]
        disc = tr * tr - 4 * det
        if positive(disc):
            r = iv.sqrt(disc)
            return [((tr + r) / 2, ZERO), ((tr - r) / 2, ZERO)]
        if negative(disc):
            im = iv.sqrt(-disc) / 2
            return [(tr / 2, im), (tr / 2, -im)]
        # Real or complex: both lie in tr/2 + [-1, 1] sqrt(disc+)/2 + i [-1, 1] sqrt(disc-)/2.
        pos = iv.mpf([0, max(hi(disc), 0)])
        neg = iv.mpf([0, max(-lo(disc), 0)])
        re = tr / 2 + iv.mpf([-1, 1]) * iv.sqrt(pos) / 2
        im = iv.mpf([-1, 1]) * iv.sqrt(neg) / 2
        return [(re, im), (re, im)]
    return eigenvalues_general(M)


def piecewise_eigenvalues(monodromies):
    """The multipliers over a parameter interval cut into pieces, from the monodromy of each piece:
    the eigenvalue boxes of each piece (disjoint, one eigenvalue of every matrix of the piece in each),
    each paired with the nearest box of the first piece, one-to-one, and the hull of each pairing.
    Whatever the pairing, for every parameter value each hull holds an eigenvalue of its monodromy,
    a different one in each; None when a piece's eigenvalues cannot be separated."""
    first = eigenvalues(monodromies[0])
    if first is None:
        return None
    hulls = [[re, im] for re, im in first]
    for M in monodromies[1:]:
        boxes = eigenvalues(M)
        if boxes is None:
            return None
        free = list(range(len(hulls)))
        for re, im in boxes:
            k = min(free, key=lambda h: abs(mid(re) - mid(first[h][0])) + abs(mid(im) - mid(first[h][1])))
            free.remove(k)
            hulls[k] = [hull_tree([hulls[k][0], re]), hull_tree([hulls[k][1], im])]
    return [tuple(h) for h in hulls]


def eigenvalues_general(M):
    """Krawczyk's test on the eigenpair equations (A − λ)v = 0, v_k = 1 (real form, λ = a + ib,
    v = x + iy) around approximate eigenpairs of the midpoint matrix (mpmath's eig, not part of the
    proof). Disjoint boxes, as many as the dimension: every eigenvalue is enclosed."""
    n = len(M)
    A = mp.matrix([[mid(x) for x in row] for row in M])
    values, vectors = mp.eig(A)
    width = max(hi(x) - lo(x) for row in M for x in row)
    boxes = []
    for e in range(n):
        lam = values[e]
        vec = [vectors[i, e] for i in range(n)]
        k = max(range(n), key=lambda i: abs(vec[i]))
        vec = [v / vec[k] for v in vec]
        free = [j for j in range(n) if j != k]
        z0 = [mp.re(lam), mp.im(lam)] + [mp.re(vec[j]) for j in free] + [mp.im(vec[j]) for j in free]
        size = len(z0)

        def unpack(z):
            x = [ONE if j == k else None for j in range(n)]
            y = [ZERO if j == k else None for j in range(n)]
            for i, j in enumerate(free):
                x[j], y[j] = z[2 + i], z[2 + len(free) + i]
            return z[0], z[1], x, y

        def F(z):
            a, b, x, y = unpack(z)
            re = [sum((M[i][j] * x[j] for j in range(n)), ZERO) - a * x[i] + b * y[i] for i in range(n)]
            im = [sum((M[i][j] * y[j] for j in range(n)), ZERO) - a * y[i] - b * x[i] for i in range(n)]
            return re + im

        def J(z):
            a, b, x, y = unpack(z)
            rows = []
            for part in (0, 1):
                for i in range(n):
                    row = [-x[i], y[i]] if part == 0 else [-y[i], -x[i]]
                    for j in free:
                        row.append((M[i][j] - (a if i == j else 0)) if part == 0 else (-b if i == j else ZERO))
                    for j in free:
                        row.append((b if i == j else ZERO) if part == 0 else (M[i][j] - (a if i == j else 0)))
                    rows.append(row)
            return rows

        Fz = F([iv.mpf(v) for v in z0])
        found = None
        scale = max(mp.mpf(2) ** (16 - PREC), 4 * width)
        while scale < 1e-2 and found is None:
            rad = [scale * (1 + abs(v)) for v in z0]
            Z = [iv.mpf([z0[p] - rad[p], z0[p] + rad[p]]) for p in range(size)]
            Jz = J(Z)
            try:
                Cm = mp.inverse(mp.matrix([[mid(x) for x in row] for row in Jz]))
            except ZeroDivisionError:
                return None
            C = [[iv.mpf(Cm[p, l]) for l in range(size)] for p in range(size)]
            ok = True
            for p in range(size):
                kz = iv.mpf(z0[p])
                for l in range(size):
                    kz -= C[p][l] * Fz[l]
                    row = ONE if p == l else ZERO
                    for j in range(size):
                        row -= C[p][j] * Jz[j][l]
                    kz += row * (Z[l] - z0[l])
                if not (lo(kz) > lo(Z[p]) and hi(kz) < hi(Z[p])):
                    ok = False
                    break
            if ok:
                found = (Z[0], Z[1])
            scale *= 1000
        if found is None:
            return None
        boxes.append(found)
    for i in range(n):
        for j in range(i):
            (a, b), (c, d) = boxes[i], boxes[j]
            if not (hi(a) < lo(c) or hi(c) < lo(a) or hi(b) < lo(d) or hi(d) < lo(b)):
                return None
    return boxes


def match(claims, boxes):
    """A one-to-one assignment of the checker's eigenvalue enclosures to the claims that contain
    them (augmenting paths); the index of an enclosure left without a claim, or None."""
    owner = [None] * len(claims)

    def fits(e, c):
        (re, im), (cre, cim) = boxes[e], claims[c]
        return inside(re, cre) and inside(im, cim)

    def assign(e, seen):
        for c in range(len(claims)):
            if c not in seen and fits(e, c):
                seen.add(c)
                if owner[c] is None or assign(owner[c], seen):
                    owner[c] = e
                    return True
        return False

    for e in range(len(boxes)):
        if not assign(e, set()):
            return e
    return None


# ---- What a proof establishes: the truth, enclosed ---------------------------------------------

class Truth:
    """The checker's enclosures of the true orbit, against which the summary's claims are checked."""

    def __init__(self):
        self.kind = None
        self.period = None
        self.sequence = []
        self.events = []        # (kind, time, velocity_before) with intervals; velocity None: exactly 0
        self.section = None     # (time, [X], [V], at)
        self.multipliers = None  # list of (re, im); "zero" for the superstable sticking orbit
        self.not_enclosed = False  # the multipliers could not be enclosed (no stability can be claimed)
        self.min_box_width = mp.mpf(0)
        self.reason = None      # a function of the reason text that raises NotConfirmed
        self.contacts = None    # the contact of each event (None: all at contact 0)
        self.held_note = False  # a sticking orbit of several modes (the held note is about it)
        self.set_note = False   # a sticking orbit held on sets of contacts
        self.radius_below_one = False  # a frequency segment's spectral_bound, verified (check_spectral_bound)


def prime_factors(q):
    out, d = [], 2
    while d * d <= q:
        if q % d == 0:
            out.append(d)
            while q % d == 0:
                q //= d
        d += 1
    return out + ([q] if q > 1 else [])


# ---- Impacting orbits --------------------------------------------------------------------------

def check_impact(cert, m, ledger):
    """Krawczyk's test on the multiple-shooting map, the exclusion of any other contact on every
    flight, the monodromy and the multipliers (docs/prove.md "Impacting orbits")."""
    q = cert["period"].integer(1, 1 << 20)
    n = m.n
    per = 2 * n + 1
    names_node = cert["unknowns"]
    N = len(names_node.items(at_least=per, at_most=MAX_UNKNOWNS))
    if N % per:
        names_node.fail(f"{N} unknowns: not a multiple of 2n + 1 = {per} (n = {n} modes)")
    count = N // per
    expected = []
    for j in range(count):
        expected += [f"t_{j}"] + [f"X_{j}[{i}]" for i in range(n)] + [f"V_{j}[{i}]" for i in range(n)]
    names = [x.text() for x in names_node.items()]
    if names != expected:
        k = next(p for p in range(N) if names[p] != expected[p])
        names_node[k].fail(f"'{names[k]}', expected '{expected[k]}'")
    u_mid = [x.num() for x in cert["midpoint"].items(exactly=N)]
    box_nodes = cert["box"].items(exactly=N)
    U = [b.pair() for b in box_nodes]
    for p in range(N):
        if not lo(U[p]) < u_mid[p] < hi(U[p]):
            cert["midpoint"][p].fail(f"{u_mid[p]} is not inside the box {show_pair(box_nodes[p].v)}")
    C = [[iv.mpf(x.num()) for x in row.items(exactly=N)] for row in cert["preconditioner"].items(exactly=N)]
    kr_nodes = cert["krawczyk"].items(exactly=N)
    flights = cert["flights"].items(exactly=count)
    # The contact of each impact: listed for a model of several contacts, 0 otherwise.
    several = len(m.contacts) > 1
    if several:
        hits = [x.integer(0, len(m.contacts) - 1) for x in cert["impact_contacts"].items(exactly=count)]
    else:
        if cert.has("impact_contacts"):
            cert["impact_contacts"].fail("a model of one contact has no 'impact_contacts'")
        hits = [0] * count
    mono_nodes = [row.items(exactly=2 * n) for row in cert["monodromy"].items(exactly=2 * n)]
    qT = q * m.T

    def unpack(vec, j):
        b = j * per
        return vec[b], vec[b + 1:b + 1 + n], vec[b + 1 + n:b + per]

    def residual(vec, m=m, w=None):
        """The shooting residual F(vec) of the model m; with w (the forcing frequency a
        differentiation variable: a D with vec constants, or a J2 with vec of J2) by
        flight_in_frequency."""
        out = []
        for j in range(count):
            k = (j + 1) % count
            t, X, V = unpack(vec, j)
            tn, Xn, Vn = unpack(vec, k)
            if j == count - 1:
                tn = tn + q * m.T if w is None else type(w).lift(tn) + type(w).lift(2 * q * iv.pi) / w
            Xe, Ve = m.flight(t, X, V, tn - t) if w is None else flight_in_frequency(m, w, t, X, V, tn - t)
            Vp = m.impact(Ve, hits[k])
            out.append(m.contact_of(X, hits[j]) - m.contacts[hits[j]][2])
            out += [Xe[i] - Xn[i] for i in range(n)]
            out += [Vp[i] - Vn[i] for i in range(n)]
        return out

    # Over a parameter interval P on which the residual depends affinely (Model.affine_parameter),
    # ũ − C F(ũ, p) is affine in p: its range over P is the hull of its values at the two ends of P
    # (the centred form ũ − C F(ũ, p̃) − (C ∂F/∂p)(P − p̃), exact for an affine parameter). Evaluated
    # for the whole of P at once, F(ũ, P) loses the correlation of its components, and C F(ũ, P)
    # comes out far wider than the orbits' spread over P (several modes: wider than the box).
    affine = m.affine_parameter()
    # Over an interval P of the forcing frequency the residual is not affine: the mean-value form
    # ũ − C F(ũ, ω̃) − (C ∂F/∂ω(ũ, P))(P − ω̃), ω̃ the middle of P, ∂F/∂ω over P at the point ũ by
    # forward differentiation of flight_in_frequency (docs/prove.md "Along a branch").
    in_frequency = m.frequency_interval()
    swept = affine or ("frequency" if in_frequency else None)

    def krawczyk_over(model, ends):
        """Krawczyk's operator for every parameter of `model`; `ends`: the models at the two ends
        of its affine parameter interval (or [model]; a frequency interval: [model])."""
        def constant(center):
            """ũ − C F(ũ, p) for every p of the model's parameters, enclosed."""
            if in_frequency:
                P = model.w
                wc = iv.mpf(mid(P))
                u = [iv.mpf(x) for x in center]
                F = [value(r) for r in residual(u, model.with_parameter("frequency", wc))]
                dF = [r.g.get(0, ZERO) if isinstance(r, D) else ZERO
                      for r in residual(u, model, variable(P, 0))]
                return [iv.mpf(center[p]) - sum((C[p][j] * F[j] for j in range(N)), ZERO)
                        - sum((C[p][j] * dF[j] for j in range(N)), ZERO) * (P - wc) for p in range(N)]
            parts = []
            for end in ends:
                F = [value(r) for r in residual([iv.mpf(x) for x in center], end)]
                parts.append([iv.mpf(center[p]) - sum((C[p][j] * F[j] for j in range(N)), ZERO) for p in range(N)])
            return [iv.mpf([min(lo(x[p]) for x in parts), max(hi(x[p]) for x in parts)]) for p in range(N)]

        def krawczyk(center, box):
            """K(box) = ũ − C F(ũ) + (I − C J(box))(box − ũ) with the sparse Jacobian over the box."""
            const = constant(center)
            J = [r.g if isinstance(r, D) else {} for r in residual([variable(box[p], p) for p in range(N)], model)]
            diff = [box[l] - center[l] for l in range(N)]
            K = []
            for p in range(N):
                row = C[p]
                k = const[p]
                acc = {}
                for j in range(N):
                    c = row[j]
                    for l, d in J[j].items():
                        acc[l] = acc[l] + c * d if l in acc else c * d
                for l in range(N):
                    k += ((ONE if l == p else ZERO) - acc.get(l, ZERO)) * diff[l]
                K.append(k)
            return K
        return krawczyk

    krawczyk = krawczyk_over(m, [m.with_parameter(affine, e) for e in m.ends[affine]] if affine else [m])

    # 1. Existence and uniqueness in the certificate's box. A frequency segment: in the tube along
    # the family's tangent (check_tangent), K of the tube mapped to u.
    if cert.has("tangent") != in_frequency:
        (cert["tangent"] if cert.has("tangent") else cert).fail(
            "a segment in the forcing frequency has a 'tangent' (docs/prove.md), nothing else has")
    if in_frequency:
        K, tube = check_tangent(cert["tangent"], m, residual, u_mid, U, C, N)
    else:
        K = krawczyk(u_mid, U)
    # 2. The true orbit, enclosed tightly: Newton at 192 bits from the midpoint, then Krawczyk's
    # test of the checker's own on a box of relative radius 2^-120 around it, inside U (so the
    # zero there is the one of U). A parameter interval has a set of orbits: K(U) ∩ U, iterated.
    E = contract(residual, krawczyk, u_mid, U, K, C, m.point, m.thin)
    # The Krawczyk records and the certificate's list: inside the box, containing the true orbit.
    for p in range(N):
        ledger.check("krawczyk", names[p], "inside the box", K[p], E[p], box=U[p])
        claim_contains(kr_nodes[p], E[p], f"the orbit's {names[p]}")
        if not holds("inside the box", kr_nodes[p].pair(), U[p]):
            raise NotConfirmed(f"{kr_nodes[p].path} = {show_pair(kr_nodes[p].v)} is not inside the box")

    # 3. No contact between the impacts, over the whole box; the monodromy at the true orbit.
    def flight_quantities(vec, mm, j):
        k = (j + 1) % count
        t, X, V = unpack(vec, j)
        tn = unpack(vec, k)[0] + (q * mm.T if j == count - 1 else 0)
        S = tn - t
        Xe, Ve = mm.flight(t, X, V, S)
        M2 = [mm.derivative_bound(t, X, V, 2, l) for l in range(len(mm.contacts))]
        return t, X, V, tn, S, Xe, Ve, mm.contact_of(V, hits[j]), mm.contact_of(Ve, hits[k]), M2

    def orbit_values(E_, mm):
        """Every flight's quantities and the monodromy (flights and saltation matrices, docs/model.md
        §5.6) at the orbits in E_ of the model mm."""
        M = [[ONE if i == j else ZERO for j in range(2 * n)] for i in range(2 * n)]
        values = []
        for j in range(count):
            ck = hits[(j + 1) % count]
            tT, XT, VT, tnT, ST, XeT, VeT, aT, vmT, M2T = flight_quantities(E_, mm, j)
            values.append((tT, XT, VT, tnT, ST, XeT, VeT, aT, vmT, M2T))
            if mm.zeta is not None:
                M = matmul(damped_saltation(mm, tnT, XeT, VeT, vmT, ck), matmul(flight_jacobian(mm, tT, XT, VT, ST), M))
                continue
            Phi = [[ZERO] * (2 * n) for _ in range(2 * n)]
            for i in range(n):
                c, s = iv.cos(mm.w_i[i] * ST), iv.sin(mm.w_i[i] * ST)
                Phi[i][i], Phi[i][n + i], Phi[n + i][i], Phi[n + i][n + i] = c, s / mm.w_i[i], -mm.w_i[i] * s, c
            aB = mm.contact_acceleration(tnT, XeT, ck)
            c_, T_, e_, r_, W_ = mm.contacts[ck]
            Sal = [[ZERO] * (2 * n) for _ in range(2 * n)]
            for i in range(n):
                for l in range(n):
                    pr = (1 if i == l else 0) - (1 + r_) * T_[i] * c_[l] / W_
                    Sal[i][l] = pr
                    Sal[n + i][n + l] = pr
                    Sal[n + i][l] = (1 + r_) * aB * T_[i] * c_[l] / (W_ * vmT)
            M = matmul(Sal, matmul(Phi, M))
        return values, M

    # The true values: at the orbit in E. Over an affine parameter interval E holds the orbits of
    # every parameter value; the quantities evaluated over E and the whole interval at once lose the
    # correlation between the orbit and its parameter (the checker's enclosures would come out wider
    # than the prover's claims). So the interval is cut into PARAMETER_PIECES pieces P_k, the orbits
    # of P_k enclosed in E_k = E ∩ K_k(E) (every zero of F(·, p), p ∈ P_k, in E lies in K_k(E): the
    # Krawczyk operator of P_k, whatever its inclusion), iterated, and the values are the hull over
    # the pieces.
    # The quantities over the box likewise: the hull over the pieces of their values over (U, P_k).
    piece_models = []
    if swept:
        p0, p1 = m.ends[swept]
        cuts = [p0] + [p0 + (p1 - p0) * k / PARAMETER_PIECES for k in range(1, PARAMETER_PIECES)] + [p1]
        parts = []
        for k in range(PARAMETER_PIECES):
            a_, b_ = cuts[k], cuts[k + 1]
            mk = m.with_parameter(swept, iv.mpf([lo(a_), hi(b_)]))
            piece_models.append(mk)
            kk = krawczyk_over(mk, [m.with_parameter(swept, a_), m.with_parameter(swept, b_)])
            Ek = E
            for _ in range(3):
                Kn = kk([mid(x) for x in Ek], Ek)
                En = [meet(Kn[p], Ek[p]) for p in range(N)]
                if any(x is None for x in En):
                    raise NotConfirmed(f"the orbits of the parameter piece [{show(lo(a_))}, {show(hi(b_))}] are not "
                                       "enclosed in the box")
                Ek = En
            parts.append(orbit_values(Ek, mk))
        values, monodromy = hull_tree([x[0] for x in parts]), hull_tree([x[1] for x in parts])
        multipliers = piecewise_eigenvalues([x[1] for x in parts])
    else:
        values, monodromy = orbit_values(E, m)
        multipliers = eigenvalues(monodromy)
    over_box = [hull_tree([flight_quantities(U, mk, j) for mk in piece_models or [m]]) for j in range(count)]

    budget = [MAX_PIECES]
    vbefore = [None] * count
    for j in range(count):
        k = (j + 1) % count
        fl = flights[j]
        cj, ck = hits[j], hits[k]
        gap_keys = ("gaps",) if several else ("second_derivative_bound", "pieces")
        fl.obj(("from", "duration", "velocity_after", "velocity_before_next", "velocity_after_lower",
                "speed_before_lower", "start_window", "end_window") + gap_keys)
        if fl["from"].integer(0, count - 1) != j:
            fl["from"].fail(f"{fl['from'].v}, expected {j}")
        where = f"flight {j} (impact {j} to impact {k})"

        t, X, V, tn, S, Xe, Ve, a, vm, M2 = over_box[j]
        tT, XT, VT, tnT, ST, XeT, VeT, aT, vmT, M2T = values[j]
        ledger.check("duration", where, "> 0", S, ST)
        ledger.check("contact velocity after impact", where, "> 0", a, aT)
        ledger.check("contact velocity before impact", where, "< 0", vm, vmT)
        # Each gap: its second-derivative bound and where it must be positive. One contact: the
        # certificate's flight holds them itself (second_derivative_bound, pieces).
        if several:
            gap_nodes = fl["gaps"].items(exactly=len(m.contacts))
            for l, g in enumerate(gap_nodes):
                g.obj(("contact", "second_derivative_bound", "pieces"))
                if g["contact"].integer(0, len(m.contacts) - 1) != l:
                    g["contact"].fail(f"{g['contact'].v}, expected {l}")
        else:
            gap_nodes = [fl]
        gap_where = [f"{where}, gap of contact {l}" if several else where for l in range(len(m.contacts))]
        for l in range(len(m.contacts)):
            ledger.check("second-derivative bound", gap_where[l], "finite", M2[l], M2T[l])
            claim_upper(gap_nodes[l]["second_derivative_bound"], M2T[l], f"the bound on |g''| of {gap_where[l]}")
        claim_contains(fl["duration"], ST, f"the duration of {where}")
        claim_contains(fl["velocity_after"], aT, f"the contact velocity after impact {j}")
        claim_contains(fl["velocity_before_next"], vmT, f"the contact velocity before impact {k}")
        ws, we = fl["start_window"].point(), fl["end_window"].point()
        a_low, b_low = fl["velocity_after_lower"].point(), fl["speed_before_lower"].point()
        claim_lower(fl["velocity_after_lower"], a, f"the contact velocity after impact {j} over the box")
        claim_lower(fl["speed_before_lower"], -vm, f"the contact speed before impact {k} over the box")
        start = a_low - M2[cj] * ws / 2   # g_cj(s) >= s (a - M2 s/2) on (0, ws]
        end = b_low - M2[ck] * we / 2     # g_ck(S - σ) >= σ (b - M2 σ/2) on (0, we]
        if not (positive(ws) and positive(we)):
            raise NotConfirmed(f"{fl.path}: the windows must be > 0")
        ledger.check("start window a - M2 ws/2", where, "> 0", start, a_low - M2T[cj] * ws / 2)
        ledger.check("end window b - M2 we/2", where, "> 0", end, b_low - M2T[ck] * we / 2)
        # Every gap positive between the windows: the gap of the contact just hit from ws on, that of
        # the contact hit next up to the end window, every other one on all of [0, S].
        for l in range(len(m.contacts)):
            bottom = lo(ws) if l == cj else mp.mpf(0)
            top = hi(iv.mpf(hi(S)) - we) if l == ck else hi(S)
            if bottom < top and in_frequency:
                # A frequency segment: the orbits of each piece P_k lie in its tube T_k (check_tangent),
                # far narrower than the box in the times; the gap over the union of (T_k, P_k).
                starts = [unpack(tube(mk.w), j) + (mk,) for mk in piece_models]
                positive_pieces(gap_nodes[l]["pieces"], bottom, top,
                                lambda s, l=l: hull_tree([mk.contact_of(mk.flight(tk, Xk, Vk, s)[0], l) - mk.contacts[l][2]
                                                          for tk, Xk, Vk, mk in starts]),
                                lambda s, l=l: hull_tree([mk.contact_of(mk.flight(tk, Xk, Vk, s)[1], l)
                                                          for tk, Xk, Vk, mk in starts]),
                                f"the gap on {gap_where[l]}", budget)
            elif bottom < top:
                positive_pieces(gap_nodes[l]["pieces"], bottom, top,
                                lambda s, l=l: m.contact_of(m.flight(t, X, V, s)[0], l) - m.contacts[l][2],
                                lambda s, l=l: m.contact_of(m.flight(t, X, V, s)[1], l), f"the gap on {gap_where[l]}",
                                budget)
            else:
                gap_nodes[l]["pieces"].items(at_most=MAX_PIECES)
        vbefore[k] = vmT
    M = monodromy
    for i in range(2 * n):
        for j in range(2 * n):
            claim_contains(mono_nodes[i][j], M[i][j], f"the monodromy entry ({i}, {j}) of the orbit")
    # Stability along a frequency segment: the spectral radius below 1 on sub-pieces (docs/prove.md
    # "Stability along a segment").
    radius_below_one = False
    if cert.has("spectral_bound"):
        if not in_frequency:
            cert["spectral_bound"].fail("only a segment in the forcing frequency has a 'spectral_bound'")
        check_spectral_bound(cert["spectral_bound"], cert, m, residual, orbit_values, U, N, n)
        radius_below_one = True

    truth = Truth()
    truth.kind, truth.period = "impact", q
    truth.radius_below_one = radius_below_one
    truth.sequence = ["impact"] * count
    truth.contacts = hits
    for j in range(count):
        truth.events.append(("impact", unpack(E, j)[0], vbefore[j]))
    t0, X0, V0 = unpack(E, 0)
    truth.section = (t0, X0, V0, "just after impact 0")
    boxes = multipliers
    truth.multipliers = boxes
    truth.not_enclosed = boxes is None
    truth.min_box_width = max(hi(x) - lo(x) for x in U)
    least_period(q, count, n, E, unpack, m, hits)

    def reason(node, text):
        prefix = interval_prefix(node, text, m)
        rest = text[len(prefix):]
        # A frequency segment: uniqueness in the tube along the tangent (check_tangent), not in the box.
        g = re.fullmatch(r"exactly one period-(\d+) orbit with (\d+) impact\(s\) per period in the tube along the "
                         r"family's tangent \(the certificate's tangent: ũ \+ a\(ω − ω̃\) \+ W\) and no other "
                         r"contact in its box of width (\S+) \(Krawczyk\)", rest) if in_frequency else \
            re.fullmatch(r"exactly one period-(\d+) orbit with (\d+) impact\(s\) per period and no other contact "
                         r"in a box of width (\S+) around the orbit found \(Krawczyk\)", rest)
        if not g:
            raise NotConfirmed(f"{node.path}: '{text[:120]}' is not a statement the checker verifies")
        check_count(node, "period", int(g.group(1)), q)
        check_count(node, "impacts per period", int(g.group(2)), count)
        check_width(node, g.group(3), max(hi(x) - lo(x) for x in U), "the box")
    truth.reason = reason
    return truth


def flight_jacobian(m, t, X, V, S):
    """∂(X, V)(t + S)/∂(X, V)(t) at fixed t and S, by forward differentiation of the flight."""
    n = m.n
    Xe, Ve = m.flight(t, [variable(X[i], i) for i in range(n)], [variable(V[i], n + i) for i in range(n)], S)
    return [[D.lift(z).g.get(l, ZERO) for l in range(2 * n)] for z in Xe + Ve]


def damped_saltation(m, t, X, Vm, vm, j):
    """The saltation matrix of an impact, S = Dg + (f⁺ − Dg f⁻) ∇hᵀ/(∇h·f⁻): the reset
    g(X, V) = (X, Impact(V)) with Jacobian Dg, the vector fields f = (V, Ẍ(t, X, V)) before and after,
    ∇h = (c, 0), ∇h·f⁻ = c·V⁻. The position part of f⁺ − Dg f⁻ is V⁺ − V⁻ = −(1 + r)(c·V⁻/W)T, whose
    quotient by c·V⁻ is −(1 + r)T/W exactly: taken so (the quotient of the enclosures would not cancel
    c·V⁻, and over a parameter interval it comes out wide)."""
    n = m.n
    c, T, e, r, W = m.contacts[j]
    Vp = m.impact(Vm, j)
    Dg = [[ONE if i == l else ZERO for l in range(2 * n)] for i in range(2 * n)]
    for i in range(n):
        for l in range(n):
            Dg[n + i][n + l] = (ONE if i == l else ZERO) - (1 + r) * T[i] * c[l] / W
    fm = m.acceleration(t, X, Vm)
    fp = m.acceleration(t, X, Vp)
    jump = [-(1 + r) * T[i] / W for i in range(n)] + \
        [(fp[i] - sum((Dg[n + i][n + l] * fm[l] for l in range(n)), ZERO)) / vm for i in range(n)]
    grad = list(c) + [ZERO] * n
    return [[Dg[i][l] + jump[i] * grad[l] for l in range(2 * n)] for i in range(2 * n)]


def hull_tree(items):
    """The hull of intervals held in equal nested lists or tuples, position by position."""
    first = items[0]
    if isinstance(first, (list, tuple)):
        return type(first)(hull_tree([x[i] for x in items]) for i in range(len(first)))
    return iv.mpf([min(lo(x) for x in items), max(hi(x) for x in items)])


def matmul(A, B):
    return [[sum((A[i][k] * B[k][j] for k in range(len(B))), ZERO) for j in range(len(B[0]))] for i in range(len(A))]


def check_tangent(node, m, residual, u_mid, U, C, N):
    """Krawczyk's test of a segment in the forcing frequency (docs/prove.md "Along a branch"): with
    the centre ω̃ ∈ P, the direction a and the box W ∋ 0 of the certificate's `tangent`, for every
    p ∈ P the orbits are u = ũ + a(p − ω̃) + w, w ∈ W a zero of G_p(w) = F(ũ + a(p − ω̃) + w, p), and
    K(W) = −C G_p(0) + (I − C J_u(T, P)) W ⊂ int W, T = ũ + a(P − ω̃) + W (inside the certificate's
    box), proves one zero in W for each p. G_p(0) = g(p) by Taylor's theorem with the Lagrange
    remainder, g(ω̃) + g'(ω̃)(p − ω̃) + g''(P)(p − ω̃)²/2, from second-order jets (J2) of the residual
    with the frequency a variable, written here (flight_in_frequency). Returns K mapped to u,
    ũ + a(P − ω̃) + K(W): the certificate's Krawczyk records must lie in the box and contain the
    orbits it encloses."""
    node.obj(("centre", "direction", "box"))
    P = m.w
    wc = iv.mpf(node["centre"].num())
    if not (lo(P) <= lo(wc) and hi(wc) <= hi(P)):
        node["centre"].fail(f"{node['centre'].v} is not inside the frequency interval")
    a = [iv.mpf(x.num()) for x in node["direction"].items(exactly=N)]
    W = [x.pair() for x in node["box"].items(exactly=N)]
    for p in range(N):
        if not (lo(W[p]) <= 0 <= hi(W[p])):
            node["box"][p].fail("the tube's box must hold 0 (the centre of the expansion)")
    delta = iv.mpf([min(lo(P - wc), 0), max(hi(P - wc), 0)])
    d2 = iv.mpf([0, max(abs(lo(delta)), abs(hi(delta))) ** 2])  # (p − ω̃)² over P

    def along(d):
        dj = J2(d, ONE)
        return residual([J2(iv.mpf(u_mid[p])) + J2(a[p]) * dj for p in range(N)], m, J2(wc) + dj)

    at, over = along(ZERO), along(delta)
    g = [J2.lift(at[l]).v + J2.lift(at[l]).d1 * delta + J2.lift(over[l]).d2 * d2 / 2 for l in range(N)]
    T = [iv.mpf(u_mid[p]) + a[p] * delta + W[p] for p in range(N)]
    for p in range(N):
        if not inside(T[p], U[p]):
            raise NotConfirmed(f"the tube's component {p}, {show_iv(T[p])}, is not inside the box {show_iv(U[p])}")
    J = [r.g if isinstance(r, D) else {} for r in residual([variable(T[p], p) for p in range(N)], m)]
    K, KU = [], []
    for p in range(N):
        k = -sum((C[p][j] * g[j] for j in range(N)), ZERO)
        acc = {}
        for j in range(N):
            for l, d in J[j].items():
                acc[l] = acc[l] + C[p][j] * d if l in acc else C[p][j] * d
        for l in range(N):
            k += ((ONE if l == p else ZERO) - acc.get(l, ZERO)) * W[l]
        if not (lo(k) > lo(W[p]) and hi(k) < hi(W[p])):
            raise NotConfirmed(f"Krawczyk's test in the tube fails: K(W) component {p}, {show_iv(k)}, is not inside "
                               f"the interior of W = {show_iv(W[p])}")
        K.append(k)
        KU.append(iv.mpf(u_mid[p]) + a[p] * delta + k)

    def tube(Pk):
        """ũ + a(P_k − ω̃) + W: every orbit of a piece P_k of the interval lies in it."""
        return [iv.mpf(u_mid[p]) + a[p] * (Pk - wc) + W[p] for p in range(N)]
    return KU, tube


def exact_inverse(S, node):
    """The inverse of a matrix of doubles, exactly (rational Gauss-Jordan), as mpmath intervals."""
    from fractions import Fraction
    n = len(S)
    A = [[Fraction(float(x)) for x in row] + [Fraction(int(i == j)) for j in range(n)] for i, row in enumerate(S)]
    for c in range(n):
        r = next((r for r in range(c, n) if A[r][c] != 0), None)
        if r is None:
            node.fail("the similarity matrix is singular")
        A[c], A[r] = A[r], A[c]
        piv = A[c][c]
        A[c] = [x / piv for x in A[c]]
        for r in range(n):
            if r != c and A[r][c] != 0:
                f = A[r][c]
                A[r] = [x - f * y for x, y in zip(A[r], A[c])]
    return [[iv.mpf(x.numerator) / iv.mpf(x.denominator) for x in row[n:]] for row in A]


def block_norm_bound(B, blocks):
    """max_b Σ_c ‖B_bc‖₂ (an upper bound), the induced norm of B for ‖x‖ = max_b ‖x_b‖₂ over the blocks:
    a 1 x 1 block its modulus, a diagonal 2 x 2 block its spectral norm √((F + √(F² − 4 det²))/2),
    F = ‖·‖_F², any other block its Frobenius norm."""
    starts = [sum(blocks[:k]) for k in range(len(blocks))]
    worst = mp.mpf(0)
    for b, (r0, rb) in enumerate(zip(starts, blocks)):
        total = ZERO
        for c, (c0, cb) in enumerate(zip(starts, blocks)):
            sub = [[B[r0 + i][c0 + j] for j in range(cb)] for i in range(rb)]
            if rb == cb == 1:
                norm = iv.mpf([0, max(abs(lo(sub[0][0])), abs(hi(sub[0][0])))])
            else:
                F = sum((x * x for row in sub for x in row), ZERO)
                if rb == cb == 2 and b == c:
                    det = sub[0][0] * sub[1][1] - sub[0][1] * sub[1][0]
                    Fh = iv.mpf(hi(F))
                    d2 = iv.mpf(max(lo(det * det), 0))
                    root = iv.sqrt(iv.mpf([0, max(hi(Fh * Fh - 4 * d2), 0)]))
                    norm = iv.sqrt((Fh + root) / 2)
                else:
                    norm = iv.sqrt(iv.mpf([0, hi(F)]))
            total = total + iv.mpf(hi(norm))
        worst = max(worst, hi(total))
    return worst


def check_spectral_bound(node, cert, m, residual, orbit_values, U, N, n):
    """A segment in the forcing frequency proven stable (docs/prove.md "Stability along a segment"):
    its sub-pieces P_k, contiguous and covering the interval, each with a tube of its own (Krawczyk's
    test in the tube along its tangent, check_tangent) lying inside the segment's tube for every
    ω ∈ P_k (so its orbit is the segment's orbit), and a bound: with the certificate's S and its exact
    inverse, ρ(M) = ρ(S⁻¹MS) ≤ max_b Σ_c ‖(S⁻¹MS)_bc‖₂ for every monodromy M of the orbits of P_k (the
    checker's own monodromy over its own enclosure of them), below the claimed bound, itself < 1."""
    pieces = node.items(at_least=1, at_most=MAX_PIECES)
    seg = cert["tangent"]
    u_seg = [iv.mpf(x.num()) for x in cert["midpoint"].items(exactly=N)]
    a_seg = [iv.mpf(x.num()) for x in seg["direction"].items(exactly=N)]
    W_seg = [x.pair() for x in seg["box"].items(exactly=N)]
    wc_seg = iv.mpf(seg["centre"].num())
    text = m.texts["frequency"]
    first, last = [e.strip() for e in text[1:-1].split(",")]
    previous = first
    for k, piece in enumerate(pieces):
        piece.obj(("interval", "midpoint", "tangent", "similarity", "blocks", "bound"))
        t = piece["interval"].text()
        g = re.fullmatch(r"\[([^,\]]+), ([^,\]]+)\]", t)
        if not g:
            piece["interval"].fail("not an interval '[a, b]' of two decimals")
        if g.group(1) != previous:
            piece["interval"].fail(f"starts at {g.group(1)}, expected {previous} (the sub-pieces must be contiguous "
                                   "and cover the segment's interval)")
        a_, b_ = decimal(piece["interval"], g.group(1)), decimal(piece["interval"], g.group(2))
        if not hi(a_) < lo(b_):
            piece["interval"].fail("an empty sub-piece")
        previous = g.group(2)
        mk = m.with_parameter("frequency", iv.mpf([lo(a_), hi(b_)]))
        u_k = [x.num() for x in piece["midpoint"].items(exactly=N)]
        tn = piece["tangent"]
        wc_k = iv.mpf(tn["centre"].num())
        # The checker's own preconditioner: the inverse of the Jacobian at (u_k, ω̃_k).
        Jr = residual([variable(iv.mpf(u_k[p]), p) for p in range(N)], mk.with_parameter("frequency", wc_k))
        Jm = mp.matrix([[mid(r.g.get(l, ZERO)) if isinstance(r, D) else 0 for l in range(N)] for r in Jr])
        try:
            Ci = mp.inverse(Jm)
        except ZeroDivisionError:
            raise NotConfirmed(f"{piece.path}: the shooting map's Jacobian at the sub-piece's midpoint is singular")
        C = [[iv.mpf(Ci[p, l]) for l in range(N)] for p in range(N)]
        KU, _ = check_tangent(tn, mk, residual, u_k, U, C, N)
        a_k = [iv.mpf(x.num()) for x in tn["direction"].items(exactly=N)]
        W_k = [x.pair() for x in tn["box"].items(exactly=N)]
        for p in range(N):
            d = (iv.mpf(u_k[p]) - u_seg[p] + a_seg[p] * (wc_seg - wc_k)) + (a_k[p] - a_seg[p]) * (mk.w - wc_k) + W_k[p]
            if not inside(d, W_seg[p]):
                raise NotConfirmed(f"{piece.path}: the sub-piece's tube leaves the segment's tube in component {p} "
                                   f"({show_iv(d)} is not inside W = {show_iv(W_seg[p])})")
        M = orbit_values(KU, mk)[1]
        S_rows = [[x.num() for x in row.items(exactly=2 * n)] for row in piece["similarity"].items(exactly=2 * n)]
        blocks = [x.integer(1, 2) for x in piece["blocks"].items(at_least=1, at_most=2 * n)]
        if sum(blocks) != 2 * n:
            piece["blocks"].fail(f"the blocks add up to {sum(blocks)}, not {2 * n}")
        Sinv = exact_inverse(S_rows, piece["similarity"])
        S = [[iv.mpf(x) for x in row] for row in S_rows]
        B = matmul(Sinv, matmul(M, S))
        rho = block_norm_bound(B, blocks)
        claim = piece["bound"].num()
        if not claim < 1:
            piece["bound"].fail("a spectral radius bound of a stable orbit must be < 1")
        if not rho <= claim:
            raise NotConfirmed(f"{piece['bound'].path} = {claim!r}: the checker bounds the spectral radius over "
                               f"{t} by {show(rho)}")
    if previous != last:
        node.fail(f"the sub-pieces end at {previous}, not at the segment's end {last}")


def contract(residual, krawczyk, u_mid, U, K, C, point_model, thin_model=False):
    """The checker's enclosure of the zero in U. K(U) ⊂ int U has been tested by the caller (the
    ledger rejects it otherwise). For a model of point parameters: Newton at 192 bits from the
    midpoint with the preconditioner C, then Krawczyk's test on a box of relative radius 2^-120
    around the point; that box lies in U, so its zero is U's. For a thin model (a physical scene's
    enclosed modal data) the same with radius 2^-100 or 2^-80, which holds the zeros of every model
    of the set. Otherwise (or should that fail): K(U) ∩ U, intersected with K of itself three times."""
    N = len(U)
    if all(lo(K[p]) > lo(U[p]) and hi(K[p]) < hi(U[p]) for p in range(N)):
        # A model of intervals as thin as a physical scene's enclosed modal data (~1e-33): its set of
        # orbits is as thin, and a box of radius 2^-100 or 2^-80 holds it all (Krawczyk for every
        # model of the set at once).
        if point_model or thin_model:
            u = [mp.mpf(x) for x in u_mid]
            for _ in range(8):
                F = [mid(value(r)) for r in residual([iv.mpf(x) for x in u])]
                du = [sum((mid(C[p][l]) * F[l] for l in range(N)), mp.mpf(0)) for p in range(N)]
                u = [u[p] - du[p] for p in range(N)]
                if max(abs(du[p]) / (1 + abs(u[p])) for p in range(N)) < mp.mpf(2) ** (20 - PREC):
                    break
            for e in (120,) if point_model else (100, 80):
                V = [iv.mpf([x - mp.mpf(2) ** -e * (1 + abs(x)), x + mp.mpf(2) ** -e * (1 + abs(x))]) for x in u]
                if all(inside(V[p], U[p]) for p in range(N)):
                    KV = krawczyk(u, V)
                    if all(lo(KV[p]) > lo(V[p]) and hi(KV[p]) < hi(V[p]) for p in range(N)):
                        return [meet(KV[p], V[p]) for p in range(N)]
        E = [meet(K[p], U[p]) for p in range(N)]
        for _ in range(3):
            Kn = krawczyk([mid(x) for x in E], E)
            En = [meet(Kn[p], E[p]) for p in range(N)]
            if any(x is None for x in En):
                break
            E = En
        return E
    return U  # the ledger's Krawczyk records fail (not confirmed) before these are used


def least_period(q, count, n, E, unpack, m, hits):
    """The orbit's least period is q: for every prime ℓ dividing q, the orbit is not (q/ℓ)-periodic.
    A (q/ℓ)-periodic orbit has ℓ | m impacts per q periods and maps impact j onto impact j + m/ℓ
    shifted by (q/ℓ)T: some time or state difference must exclude 0."""
    qT = q * m.T
    for ell in prime_factors(q):
        if count % ell:
            continue
        p, h = q // ell, count // ell
        shift = p * m.T
        apart = False
        for j in range(count):
            k = (j + h) % count
            tj, Xj, Vj = unpack(E, j)
            tk, Xk, Vk = unpack(E, k)
            dt = tk + (qT if j + h >= count else 0) - tj - shift
            if hits[k] != hits[j] or excludes_zero(dt) or any(excludes_zero(Xk[i] - Xj[i]) or excludes_zero(Vk[i] - Vj[i]) for i in range(n)):
                apart = True
                break
        if not apart:
            raise NotConfirmed(f"period: {q} is claimed, but the orbit repeats after {p} forcing period(s) "
                               f"(impact j + {h} is impact j shifted by {p}T, within the checker's enclosures)")


def interval_prefix(node, text, m):
    """"for every amplitude in [a, b]: " exactly when the model has that parameter interval."""
    keys = {"amplitude": "amplitude", "frequency": "frequency", "stop position": "stop", "restitution": "restitution"}
    g = re.match(r"for every (amplitude|frequency|stop position|restitution) in (\[[^\]]*\]): ", text)
    intervals = [k for k in keys.values() if isinstance(m.texts[k], str) and m.texts[k].startswith("[")]
    if g:
        if intervals != [keys[g.group(1)]] or m.texts[keys[g.group(1)]] != g.group(2):
            raise NotConfirmed(f"{node.path}: '{g.group(0)}' is not the model's parameter interval")
        return g.group(0)
    if intervals:
        raise NotConfirmed(f"{node.path}: the model has the parameter interval model.{intervals[0]} "
                           f"= {m.texts[intervals[0]]}, the reason does not say so")
    return ""


def check_count(node, what, claimed, true):
    if claimed != true:
        raise NotConfirmed(f"{node.path}: {what} {claimed}, the proof has {true}")


def check_width(node, text, width, what):
    """A width printed with two significant digits ("4.0e-12") must not understate `width`."""
    try:
        w = mp.mpf(text)
    except (ValueError, TypeError):
        raise NotConfirmed(f"{node.path}: '{text}' is not a width")
    digits = re.fullmatch(r"\d\.\d[eE]([+-]?\d+)", text)
    half_unit = mp.mpf(10) ** (int(digits.group(1)) - 1) / 2 if digits else mp.mpf(0)
    if not width <= w + half_unit:
        raise NotConfirmed(f"{node.path}: width {text}, but {what} is {show(width)} wide")


# ---- One-DOF sticking orbits -------------------------------------------------------------------

SUPERSTABLE = "superstable: a one-DOF trajectory that sticks is released from the same state at the same phase"


def newton_root(gap, slope, S, center, rounds=3):
    """The root of the gap in S, tightened: interval Newton from the certificate's box S, then
    from mpmath centres of the enclosures found."""
    E = S
    for _ in range(rounds):
        c = iv.mpf(center)
        Nw = c - gap(c) / slope(E)
        En = meet(Nw, E)
        if En is None:
            break
        E = En
        center = mid(E)
    return E


def check_sticking(cert, m, ledger):
    """The release, each flight and landing (interval Newton), the chattering tail, and the
    reaction over the sticking phase (docs/prove.md "One-DOF sticking orbits")."""
    if len(m.contacts) > 1:
        raise NotConfirmed("a sticking certificate needs a model of one contact")
    if m.n != 1 or not lo(m.c[0]) == 1 == hi(m.c[0]):
        raise NotConfirmed("a sticking certificate needs one mode with shape 1")
    if not hi(m.r) < 1:
        raise NotConfirmed("a sticking certificate needs 0 <= r < 1")
    plastic = lo(m.r) == 0 and hi(m.r) == 0
    w, w1s, kappa, TB, x0 = m.w, m.w_i[0] ** 2, m.TA[0] * m.f, m.TB[0], m.x0
    rel = "release"
    ratio = w1s * x0 / kappa
    ledger.check("forcing T_A f", rel, "!= 0", kappa, kappa)
    ledger.check("1 - |omega_1^2 x0/(T_A f)|", rel, "> 0", 1 - abs(ratio), 1 - abs(ratio))
    # φ1 (eq. (32)): sin φ1 = ratio, κ cos φ1 > 0; enclosed to 2^-170 by the monotonicity of sin.
    r_mid = mid(ratio)
    phi = mp.asin(r_mid) if positive(kappa) else mp.pi - mp.asin(r_mid)
    eps = mp.mpf(2) ** -170
    P = iv.mpf([phi - eps, phi + eps])
    if positive(kappa):
        ok = hi(iv.sin(lo(P))) < lo(ratio) and lo(iv.sin(hi(P))) > hi(ratio) and hi(P) < mp.pi / 2
    else:
        ok = lo(iv.sin(lo(P))) > hi(ratio) and hi(iv.sin(hi(P))) < lo(ratio) and lo(P) > mp.pi / 2
    if not ok:
        raise NotConfirmed("the checker cannot enclose the release phase (the reaction's root)")
    release = cert["release"].obj(("phase", "time", "reaction_rate"))
    tr = P / w
    rate = -(kappa * w * iv.cos(P)) / TB
    claim_contains(release["phase"], P, "the release phase φ1 of eq. (32)")
    claim_contains(release["time"], tr, "the release time φ1/ω")
    claim_contains(release["reaction_rate"], rate, "the reaction rate at the release")
    ledger.check("reaction rate", rel, "< 0", rate, rate)

    def reaction(t):
        return (w1s * x0 - kappa * iv.sin(w * t)) / TB

    truth = Truth()
    truth.kind = "sticking"
    truth.sequence = ["release"]
    truth.events = [("release", tr, None)]
    X0 = [x0]
    flights = cert["flights"].items(at_least=1, at_most=MAX_FLIGHTS)
    budget = [MAX_PIECES]
    t, vplus = tr, None
    landing_low = None
    t_end = None
    for k, fn in enumerate(flights):
        fl, land = f"flight {k}", f"landing {k}"
        common = ("start", "start_window", "landing_center", "landing_box", "landing", "pieces")
        start_kind = "release" if k == 0 else ("impact" if vplus is not None else "departure")
        extra = {"release": ("third_derivative", "third_derivative_lower", "fourth_derivative_bound"),
                 "impact": ("velocity_after", "velocity_after_lower", "second_derivative_bound"),
                 "departure": ("second_derivative", "second_derivative_lower", "third_derivative_bound")}[start_kind]
        fn.obj(common + extra + (() if not plastic else ("landing_slope", "reaction_at_landing")))
        if fn["start"].text() != start_kind:
            raise NotConfirmed(f"{fn['start'].path}: '{fn['start'].v}', the flight starts at a {start_kind}")
        V0 = [ZERO] if vplus is None else [vplus]
        gap = lambda s, t=t, V0=V0: m.contact_of(m.flight(t, X0, V0, s)[0]) - x0  # noqa: E731
        slope = lambda s, t=t, V0=V0: m.contact_of(m.flight(t, X0, V0, s)[1])  # noqa: E731
        ws = fn["start_window"].point()
        if not positive(ws):
            raise NotConfirmed(f"{fn['start_window'].path}: the window must be > 0")
        if start_kind == "impact":
            M2 = m.derivative_bound(t, X0, V0, 2)
            ledger.check("contact velocity after impact", fl, "> 0", vplus, vplus)
            ledger.check("second-derivative bound", fl, "finite", M2, M2)
            claim_contains(fn["velocity_after"], vplus, f"the speed after the impact that starts {fl}")
            claim_lower(fn["velocity_after_lower"], vplus, f"the speed after the impact that starts {fl}")
            claim_upper(fn["second_derivative_bound"], M2, f"the bound on |x''| of {fl}")
            a_low = fn["velocity_after_lower"].point()
            margin = a_low - M2 * ws / 2   # g(s) >= s (a - M2 s/2) on (0, ws]
            ledger.check("start window a - M2 ws/2", fl, "> 0", margin, margin)
        elif start_kind == "release":
            g3 = kappa * w * iv.cos(w * t)   # x''' at rest on the stop
            M4 = m.derivative_bound(t, X0, V0, 4)
            ledger.check("third derivative of the gap", fl, "> 0", g3, g3)
            ledger.check("fourth-derivative bound", fl, "finite", M4, M4)
            claim_contains(fn["third_derivative"], g3, f"g''' at the start of {fl}")
            claim_lower(fn["third_derivative_lower"], g3, f"g''' at the start of {fl}")
            claim_upper(fn["fourth_derivative_bound"], M4, f"the bound on |x''''| of {fl}")
            margin = fn["third_derivative_lower"].point() / 6 - M4 * ws / 24  # g(s)/s^3 >= g'''/6 - M4 s/24
            ledger.check("start window g'''/6 - M4 ws/24", fl, "> 0", margin, margin)
        else:
            g2 = kappa * iv.sin(w * t) - w1s * x0   # x'' at rest on the stop = -T_B R > 0
            M3 = m.derivative_bound(t, X0, V0, 3)
            ledger.check("second derivative of the gap", fl, "> 0", g2, g2)
            ledger.check("third-derivative bound", fl, "finite", M3, M3)
            claim_contains(fn["second_derivative"], g2, f"g'' at the start of {fl}")
            claim_lower(fn["second_derivative_lower"], g2, f"g'' at the start of {fl}")
            claim_upper(fn["third_derivative_bound"], M3, f"the bound on |x'''| of {fl}")
            margin = fn["second_derivative_lower"].point() / 2 - M3 * ws / 6  # g(s)/s^2 >= g''/2 - M3 s/6
            ledger.check("start window g''/2 - M3 ws/6", fl, "> 0", margin, margin)
        # The landing: interval Newton on the certificate's box, then tightened.
        s0 = fn["landing_center"].num()
        S = fn["landing_box"].pair()
        if not lo(S) <= s0 <= hi(S):
            raise NotConfirmed(f"{fn['landing_center'].path} = {s0} is not in the landing box")
        gp = slope(S)
        Nw = iv.mpf(s0) - gap(iv.mpf(s0)) / gp
        root = meet(Nw, S)
        ledger.check("contact velocity at the landing", land, "< 0", gp, slope(root) if root else gp)
        if not (finite(Nw) and lo(Nw) > lo(S) and hi(Nw) < hi(S)):
            raise NotConfirmed(f"the interval Newton test at {land} fails: {show_iv(Nw)} is not inside the landing "
                               f"box {show_pair(fn['landing_box'].v)}")
        if start_kind == "impact":
            # Centred form of the landing as a function of the flight's start (t, v): the landing from
            # the centre, tightened by Newton, plus the derivatives over the box times the offsets
            # (mean-value theorem; s(t, v) stays in Nw over the box).
            tc, vc = mid(t), mid(vplus)
            Tc, Vc = iv.mpf(tc), iv.mpf(vc)
            gap_c = lambda s_, Tc=Tc, Vc=Vc: m.contact_of(m.flight(Tc, X0, [Vc], s_)[0]) - x0  # noqa: E731
            slope_c = lambda s_, Tc=Tc, Vc=Vc: m.contact_of(m.flight(Tc, X0, [Vc], s_)[1])  # noqa: E731
            s_c = newton_root(gap_c, slope_c, S, s0, rounds=4)
            Xe, Ve = m.flight(variable(t, 0), [D(x0)], [variable(vplus, 1)], variable(Nw, 2))
            g_, vel = m.contact_of(Xe), m.contact_of(Ve)
            gt, gv, gs = g_.g.get(0, ZERO), g_.g.get(1, ZERO), g_.g.get(2, ZERO)
            vt, vv, vs = vel.g.get(0, ZERO), vel.g.get(1, ZERO), vel.g.get(2, ZERO)
            ds_dt, ds_dv = -gt / gs, -gv / gs
            dT, dV = t - Tc, vplus - Vc
            s_true = meet(s_c + ds_dt * dT + ds_dv * dV, Nw)
            t_next = Tc + s_c + (1 + ds_dt) * dT + ds_dv * dV
            v_minus = meet(slope_c(s_c) + (vt + vs * ds_dt) * dT + (vv + vs * ds_dv) * dV, slope(Nw))
            if s_true is None or v_minus is None:
                raise NotConfirmed(f"the checker's enclosures of {land} do not meet")
        else:
            s_true = newton_root(gap, slope, meet(Nw, S), mid(meet(Nw, S)), rounds=4)
            t_next = t + s_true
            v_minus = slope(s_true)
        ledger.check("interval Newton", land, "inside the box", Nw, s_true, box=S)
        claim_contains(fn["landing"], s_true, f"the duration of {fl} to its landing")
        if not holds("inside the box", fn["landing"].pair(), S):
            raise NotConfirmed(f"{fn['landing'].path} = {show_pair(fn['landing'].v)} is not inside the landing box")
        after = iv.mpf(lo(S)) - ws
        ledger.check("landing after the start window", land, "> 0", after, after)
        positive_pieces(fn["pieces"], lo(ws), lo(S), gap, slope, f"the gap on {fl}", budget)
        landing_low = lo(S) + lo(t - tr)
        truth.events.append(("impact", t_next, v_minus))
        truth.sequence.append("impact")
        if not plastic:
            ledger.check("contact velocity before impact", land, "< 0", v_minus, v_minus)
            vplus = -m.r * v_minus
            t = t_next
            continue
        R_land = reaction(t_next)
        claim_contains(fn["landing_slope"], v_minus, f"the contact velocity at {land}")
        claim_contains(fn["reaction_at_landing"], R_land, f"the reaction at {land}")
        if k == len(flights) - 1:
            ledger.check("reaction at the landing", land, "> 0", R_land, R_land)
            truth.events.append(("stick", t_next, v_minus))
            truth.sequence.append("stick")
            t_end = t_next
        else:
            ledger.check("reaction at the landing", land, "< 0", R_land, R_land)
            truth.events.append(("departure", t_next, None))
            truth.sequence.append("departure")
            t = t_next
    if not plastic:
        t_end = check_tail(cert, m, ledger, len(flights), t, vplus, reaction, w1s)
        truth.events += [("accumulation", t_end, None), ("stick", t_end, None)]
        truth.sequence += ["accumulation", "stick"]
    elif cert.has("tail"):
        cert["tail"].fail("a plastic (r = 0) orbit has no chattering tail")
    # Sticking from t_end until the next release t_r + kT, k periods after the first.
    st = cert["sticking"].obj(("periods", "rate_lower", "second_derivative_bound", "end_window", "pieces"))
    turns = (t_end - tr) / m.T
    k = st["periods"].integer(1, 1 << 20)
    ledger.check("landing time / T", "sticking phase", f"inside ({k - 1}, {k})", turns, turns)
    M2R = abs(kappa) * w * w / TB
    claim_upper(st["second_derivative_bound"], M2R, "the bound |κ| ω²/T_B on |R''|")
    claim_lower(st["rate_lower"], -rate, "-R' at the release")
    we = st["end_window"].point()
    if not positive(we):
        raise NotConfirmed(f"{st['end_window'].path}: the window must be > 0")
    end = st["rate_lower"].point() - M2R * we / 2
    ledger.check("end window b - M2 we/2", "sticking phase", "> 0", end, end)
    top = hi(k * m.T - we)
    if landing_low < top:
        positive_pieces(st["pieces"], landing_low, top, lambda tau: reaction(tr + tau),
                        lambda tau: -(kappa * w * iv.cos(w * (tr + tau))) / TB, "the reaction over the sticking phase",
                        budget)
    # The least period is k: a release needs the body at rest on the stop with R = 0 falling; before
    # t_end (> t_r + (k−1)T) it is in flight, or at an impact with a speed, or departs with R < 0.
    truth.period = k
    truth.section = (tr, [x0], [ZERO], "the release")
    truth.multipliers = "zero"
    flights_count = len(flights)

    def reason(node, text):
        interval_prefix(node, "", m)
        if plastic:
            g = re.fullmatch(r"exactly one period-(\d+) sticking orbit through the release: release, (\d+) flight\(s\) "
                             r"with plastic landings, sticking with R > 0 until the next release", text)
        else:
            g = re.fullmatch(r"exactly one period-(\d+) sticking orbit through the release: release, (\d+) impacts "
                             r"followed, a chattering tail accumulating within (\S+), sticking with R > 0 until the "
                             r"next release", text)
        if not g:
            raise NotConfirmed(f"{node.path}: '{text[:120]}' is not a statement the checker verifies")
        check_count(node, "period", int(g.group(1)), k)
        check_count(node, "flights", int(g.group(2)), flights_count)
        if not plastic:
            acc = [e for e in cert["summary"]["events"].items() if isinstance(e.v, dict) and e.v.get("kind") == "accumulation"]
            if acc:
                a = acc[0]["time"].pair()
                check_width(node, g.group(3), hi(a) - lo(a), f"{acc[0].path}.time")
    truth.reason = reason
    return truth


def check_tail(cert, m, ledger, count, tL, vplus, reaction, w1s):
    """The rest of the chattering sequence, bounded (docs/prove.md): on W = [t, t + L] with T_B R in
    [A_lo, A_hi], A_lo > 0, every flight from speed v lasts at most 2v/A_lo and lands at most
    r sqrt(a_hi/A_lo) v, a_hi = A_hi + w1² v²/(2 A_lo); the impacts accumulate before
    t + 2v/(A_lo (1 - rho)), and after t + 2 v_lo/(a_hi (1 - r sqrt(A_lo/a_hi)))."""
    tail = cert["tail"].obj(("after_flight", "speed_upper", "speed_lower", "window", "reaction_lower",
                             "reaction_upper", "contraction", "time_bound", "accumulation"))
    if tail["after_flight"].integer(0, MAX_FLIGHTS) != count - 1:
        raise NotConfirmed(f"{tail['after_flight'].path}: {tail['after_flight'].v}, the last flight is {count - 1}")
    tl = "chattering tail"
    v, L = tail["speed_upper"].point(), tail["window"].point()
    claim_upper(tail["speed_upper"], vplus, "the speed after the last impact followed")
    claim_lower(tail["speed_lower"], vplus, "the speed after the last impact followed")
    v_low = tail["speed_lower"].point()
    if not positive(v_low):
        raise NotConfirmed(f"{tail['speed_lower'].path}: the lower speed bound must be > 0")
    A = m.TB[0] * reaction(iv.mpf([lo(tL), hi(tL + L)]))
    claim_lower(tail["reaction_lower"], A, "T_B R over the tail's window")
    claim_upper(tail["reaction_upper"], A, "T_B R over the tail's window")
    A_low, A_high = tail["reaction_lower"].point(), tail["reaction_upper"].point()
    ledger.check("tail reaction T_B R over the window", tl, "> 0", A, A)
    a_hi = A_high + w1s * v * v / (2 * A_low)
    rho = m.r * iv.sqrt(a_hi / A_low)
    claim_contains(tail["contraction"], rho, "the tail's contraction r sqrt(a_hi/A_lo)")
    ledger.check("tail contraction 1 - rho", tl, "> 0", 1 - rho, 1 - rho)
    if m.zeta is None:
        Tmax = 2 * v / (A_low * (1 - rho))
        rho_low = m.r * iv.sqrt(A_low / a_hi)
        Tmin = 2 * v_low / (a_hi * (1 - rho_low))
    else:
        # Damped, y'' = -w1² y - 2σ y' - T_B R (σ = ζ w1): the damping shortens the rise (Y <= v²/(2 A_lo))
        # and takes energy in the fall (landing speed <= v sqrt(a_hi/A_lo)), but slows the fall, where
        # y'' <= -(A_lo - 2σ v sqrt(a_hi/A_lo)) = -f_lo: a flight lasts at most v/A_lo + v/sqrt(A_lo f_lo)
        # <= 2v/f_lo. From below, at least the first rise, v_lo/(a_hi + 2σ v).
        sigma = m.zeta[0] * m.w_i[0]
        f_lo = A_low - 2 * sigma * v * iv.sqrt(a_hi / A_low)
        ledger.check("tail fall acceleration A_lo - 2 sigma v sqrt(a_hi/A_lo)", tl, "> 0", f_lo, f_lo)
        Tmax = 2 * v / (f_lo * (1 - rho))
        Tmin = v_low / (a_hi + 2 * sigma * v)
    claim_upper(tail["time_bound"], Tmax, "the tail's time bound")
    ledger.check("tail window L - Tmax", tl, "> 0", L - Tmax, L - Tmax)
    t_end = iv.mpf([lo(tL + Tmin), hi(tL + Tmax)])
    claim_contains(tail["accumulation"], t_end, "the accumulation time")
    return t_end


# ---- The summary: what `vibro prove` prints ---------------------------------------------------

SUMMARY_KEYS = ("verdict", "reason", "kind", "period", "sequence", "events", "section", "multipliers", "stability",
                "box_width")
SEGMENT_STABLE = ("the spectral radius of the monodromy is below 1 for every frequency of the interval (spectral_bound: "
                  "a similarity by the eigenvectors of a midpoint monodromy and a block norm, on sub-pieces)")
NOTES = ("the discriminant of the 2 x 2 monodromy is not separated from 0",
         "a multiplier enclosure meets the unit circle",
         "the eigenvalues of the enclosed monodromy could not be separated (Rump's test)", SUPERSTABLE,
         "sticking collapses the contact's displacement and velocity: the monodromy has rank 2n - 2, its two "
         "other multipliers are 0",
         "sticking on the contacts held at the section collapses their displacements and velocities: the "
         "multipliers listed are those of the monodromy on the held subspace, its other multipliers are 0",
         SEGMENT_STABLE)


def summary_shape(s, n):
    """The summary's form, before any proof is checked (a malformed one is refused at once)."""
    s.obj(SUMMARY_KEYS, ("stability_note", "requested_period", "modal_data"))
    s["verdict"].text(("proven",))
    s["kind"].text(("impact", "sticking"))
    s["period"].integer(1, 1 << 20)
    for x in s["sequence"].items(at_most=4 * MAX_FLIGHTS):
        x.text()
    for e in s["events"].items(at_most=4 * MAX_FLIGHTS):
        e.obj(("kind", "contact", "time", "phase", "velocity_before"))
        e["kind"].text()
        e["contact"].integer(0, 1 << 20)
        for key in ("time", "phase", "velocity_before"):
            e[key].pair()
    sec = s["section"].obj(("time", "X", "V", "at"))
    sec["time"].pair()
    for key in ("X", "V"):
        for x in sec[key].items(exactly=n):
            x.pair()
    sec["at"].text()
    for x in s["multipliers"].items(at_most=2 * MAX_MODES):
        x.obj(("re", "im"))
        x["re"].pair()
        x["im"].pair()
    s["stability"].text(("stable", "unstable", "undecided"))
    if s.has("stability_note"):
        s["stability_note"].text(NOTES)
    if not s["box_width"].num() >= 0:
        s["box_width"].fail("a width must be >= 0")
    s["reason"].text()


def check_summary(cert, s, truth, m):
    """Every claim of the summary against the checker's truth."""
    s.obj(SUMMARY_KEYS, ("stability_note", "requested_period", "modal_data"))
    s["verdict"].text(("proven",))
    if s["kind"].text() != truth.kind:
        raise NotConfirmed(f"{s['kind'].path}: '{s['kind'].v}', the orbit proven is of kind '{truth.kind}'")
    period = s["period"].integer(1, 1 << 20)
    if period != truth.period:
        raise NotConfirmed(f"{s['period'].path}: {period}, the orbit proven has period {truth.period}")
    seq = [x.text() for x in s["sequence"].items(at_most=4 * MAX_FLIGHTS)]
    if seq != truth.sequence:
        raise NotConfirmed(f"{s['sequence'].path}: {seq[:8]}{'...' if len(seq) > 8 else ''}, the orbit proven has "
                           f"{truth.sequence[:8]}{'...' if len(truth.sequence) > 8 else ''}")
    events = s["events"].items(at_most=4 * MAX_FLIGHTS)
    if len(events) != len(truth.events):
        raise NotConfirmed(f"{s['events'].path}: {len(events)} events, the orbit proven has {len(truth.events)}")
    widths = [truth.min_box_width]
    for k, (e, (kind, time, vb)) in enumerate(zip(events, truth.events)):
        e.obj(("kind", "contact", "time", "phase", "velocity_before"))
        if e["kind"].text() != kind:
            raise NotConfirmed(f"{e['kind'].path}: '{e['kind'].v}', the event proven there is '{kind}'")
        contact = truth.contacts[k] if truth.contacts else 0
        if e["contact"].integer(0, 1 << 20) != contact:
            raise NotConfirmed(f"{e['contact'].path}: {e['contact'].v}, the event proven there is at contact {contact}")
        C = claim_contains(e["time"], time, f"the time of this {kind}")
        widths.append((hi(C) - lo(C), e["time"].path))
        claim_phase(e["phase"], time, m, f"the phase of this {kind}")
        claim_contains(e["velocity_before"], ZERO if vb is None else vb, f"the contact velocity before this {kind}")
    sec = s["section"].obj(("time", "X", "V", "at"))
    t, X, V, at = truth.section
    C = claim_contains(sec["time"], t, "the section's time")
    widths.append((hi(C) - lo(C), sec["time"].path))
    for name, vals in (("X", X), ("V", V)):
        nodes = sec[name].items(exactly=m.n)
        for node, x in zip(nodes, vals):
            C = claim_contains(node, x, f"the section's modal {'displacement' if name == 'X' else 'velocity'}")
            widths.append((hi(C) - lo(C), node.path))
    if sec["at"].text() != at:
        raise NotConfirmed(f"{sec['at'].path}: '{sec['at'].v}', the section of a {truth.kind} orbit is {at}")
    # Box width: no claimed enclosure of the orbit's times or section is wider.
    bw = s["box_width"].num()
    if not bw >= 0:
        s["box_width"].fail("a width must be >= 0")
    if not truth.min_box_width <= bw * (1 + mp.mpf(2) ** -52):
        raise NotConfirmed(f"{s['box_width'].path} = {s['box_width'].v!r}: the box is {show(truth.min_box_width)} wide")
    for w, where in widths[1:]:
        if not w <= bw * (1 + mp.mpf(2) ** -52):
            raise NotConfirmed(f"{s['box_width'].path} = {s['box_width'].v!r}, but {where} is {show(w)} wide")
    # Multipliers and stability.
    listed = s["multipliers"].items(at_most=2 * MAX_MODES)
    claims = []
    for x in listed:
        x.obj(("re", "im"))
        claims.append((x["re"].pair(), x["im"].pair()))
    stability = s["stability"].text(("stable", "unstable", "undecided"))
    note = s["stability_note"].text(NOTES) if s.has("stability_note") else None
    if truth.multipliers == "zero":
        if claims and (len(claims) != 2 or not all(inside(ZERO, re) and inside(ZERO, im) for re, im in claims)):
            raise NotConfirmed(f"{s['multipliers'].path}: the orbit's multipliers are 0 and 0 (superstable)")
        mods = [ZERO, ZERO]
    else:
        if truth.not_enclosed:
            if claims or stability != "undecided" and not (stability == "stable" and truth.radius_below_one):
                raise NotConfirmed(f"{s['multipliers'].path}: the checker cannot enclose the multipliers of the "
                                   f"monodromy, so it confirms no multiplier and no stability")
            mods = None
        elif not claims and truth.radius_below_one:
            mods = None  # a frequency segment's stability by its spectral bound: no multiplier claimed
        else:
            if len(claims) != len(truth.multipliers):
                raise NotConfirmed(f"{s['multipliers'].path}: {len(claims)} multipliers, the orbit has "
                                   f"{len(truth.multipliers)}")
            left = match(claims, truth.multipliers)
            if left is not None:
                re, im = truth.multipliers[left]
                raise NotConfirmed(f"{s['multipliers'].path}: no claimed multiplier contains the multiplier that the "
                                   f"checker encloses in {show_iv(re)} + i {show_iv(im)}")
            mods = [re * re + im * im for re, im in truth.multipliers]
    if stability == "stable" and not (mods is not None and all(hi(x) < 1 for x in mods)) and \
            not truth.radius_below_one:
        raise NotConfirmed(f"{s['stability'].path}: 'stable', but the checker's |multiplier|² are "
                           f"{', '.join(show_iv(x) for x in mods or [])}")
    if stability == "unstable" and not (mods is not None and any(lo(x) > 1 for x in mods)):
        raise NotConfirmed(f"{s['stability'].path}: 'unstable', but the checker's |multiplier|² are "
                           f"{', '.join(show_iv(x) for x in mods or [])}")
    held = truth.held_note
    if (note == SEGMENT_STABLE) != (truth.radius_below_one and stability == "stable" and not claims):
        raise NotConfirmed(f"{s['stability_note'].path if note else s.path}: the note '{SEGMENT_STABLE[:40]}...' "
                           "goes with a verified spectral_bound, exactly")
    if note == SUPERSTABLE and truth.multipliers != "zero" or note is not None and note != SUPERSTABLE and \
            truth.multipliers == "zero" or note == HELD_NOTE and not held or \
            note == SET_NOTE and not truth.set_note or truth.set_note and note not in (SET_NOTE,) + NOTES[:3]:
        raise NotConfirmed(f"{s['stability_note'].path}: '{note}' is not about this orbit")
    # Asked for a period Q that the least period divides: the orbit is also the period-Q orbit, and
    # the reason says so (docs/prove.md "The period is the least period").
    text = s["reason"].text()
    if s.has("requested_period"):
        Q = s["requested_period"].integer(2, 1 << 20)
        if Q <= period or Q % period:
            raise NotConfirmed(f"{s['requested_period'].path}: {Q} is not a multiple of the least period {period} "
                               f"above it")
        suffix = f"; its least period {period} divides the requested period {Q}, so it is also the period-{Q} orbit"
        if not text.endswith(suffix):
            raise NotConfirmed(f"{s['reason'].path}: does not end with '{suffix}'")
        text = text[:-len(suffix)]
    elif "; its least period" in text:
        raise NotConfirmed(f"{s['reason'].path}: states a requested period the summary does not have")
    truth.reason(s["reason"], text)


# ---- Sticking orbits of several modes ----------------------------------------------------------

HELD_NOTE = ("sticking collapses the contact's displacement and velocity: the monodromy has rank 2n - 2, its two "
             "other multipliers are 0")
STICKING_MODES_KEYS = ("unknowns", "midpoint", "box", "preconditioner", "krawczyk", "release", "flights", "sticking",
                       "monodromy")


def _raw_matmul(A, B):
    """The product of two matrices of mpmath intervals held as raw (lo, hi) pairs (libmpi, rounded
    outward at PREC bits): the Taylor series of the held flow without the context's conversions."""
    mul, add = libmpi.mpi_mul, libmpi.mpi_add
    n, k, m = len(A), len(B), len(B[0])
    out = []
    for i in range(n):
        row = A[i]
        res = []
        for j in range(m):
            acc = _RAW_ZERO
            for l in range(k):
                acc = add(acc, mul(row[l], B[l][j], PREC), PREC)
            res.append(acc)
        out.append(res)
    return out


# The exponentials e^{As} of the held flows (Held.exp), remembered for every flow built on the same
# matrix A (its exact entries and the precision): a pure function of A and s, and the checker run on
# many edits of one certificate builds the same flows again. At most EXP_MEMO matrices.
EXP_MEMO = 8
_EXPS = {}


def exponentials_of(A):
    """The table s ↦ e^{As} shared by every flow of matrix A (a fresh one unless every entry is an
    interval)."""
    if any(type(x) is not IV for row in A for x in row):
        return {}
    key = (iv.prec, len(A)) + tuple(x._mpi_ for row in A for x in row)
    table = _EXPS.get(key)
    if table is None:
        if len(_EXPS) >= EXP_MEMO:
            _EXPS.clear()
        table = _EXPS[key] = {}
    return table


class Held:
    """The flow of the structure held at contact 0 (docs/prove.md "Sticking orbits of several
    modes"), written directly: Ẍ = Ẍ_free + T_B R with R chosen so that c·Ẍ = 0, i.e.
    R = −c·Ẍ_free/s_B = (c·(Ω²X + DẊ) − s_A f sin ωt)/s_B. In Z = (X, Ẋ, sin ωt, cos ωt) it is Ż = AZ,
    Z(t0 + s) = e^{As}Z(t0), e^{As} enclosed by its Taylor series and a remainder bound."""

    def __init__(self, m):
        n, N = m.n, 2 * m.n + 2
        self.n, self.N, self.m = n, N, m
        c, TB = m.c, m.TB
        z = m.zeta or [ZERO] * n
        D_ = [2 * z[i] * m.w_i[i] for i in range(n)]
        A = [[ZERO] * N for _ in range(N)]
        # Column k of A: Ż for Z = e_k, the free acceleration plus T_B R(e_k).
        for k in range(N):
            X = [ONE if k == i else ZERO for i in range(n)]
            V = [ONE if k == n + i else ZERO for i in range(n)]
            sn = ONE if k == 2 * n else ZERO
            cs = ONE if k == 2 * n + 1 else ZERO
            free = [m.TA[i] * m.f * sn - m.w_i[i] ** 2 * X[i] - D_[i] * V[i] for i in range(n)]
            R = -sum((c[i] * free[i] for i in range(n)), ZERO) / m.sB
            for i in range(n):
                A[i][k] = V[i]
                A[n + i][k] = free[i] + TB[i] * R
            A[2 * n][k] = m.w * cs
            A[2 * n + 1][k] = -m.w * sn
        self.A = A
        self.l = [c[i] * m.w_i[i] ** 2 / m.sB for i in range(n)] + [c[i] * D_[i] / m.sB for i in range(n)] + \
            [-m.sA * m.f / m.sB, ZERO]
        self.lA = [sum((self.l[i] * A[i][k] for i in range(N)), ZERO) for k in range(N)]
        self.cache = exponentials_of(A)

    def state(self, t, X, V):
        wt = t * self.m.w if isinstance(t, D) else self.m.w * t
        return list(X) + list(V) + [dsin(wt), dcos(wt)]

    def exp(self, s):
        """e^{As} for every s in the interval s."""
        key = (lo(s), hi(s))
        if key in self.cache:
            return self.cache[key]
        if lo(s) != hi(s) and lo(s) != 0:
            # e^{As} = e^{A s_lo} e^{A[0, s_hi − s_lo]}: the width is not squared.
            E = matmul(self.exp(iv.mpf(lo(s))), self.exp(iv.mpf([0, hi(s) - lo(s)])))
            if len(self.cache) < 4096:
                self.cache[key] = E
            return E
        N = self.N
        B = [[self.A[i][k] * s for k in range(N)] for i in range(N)]
        norm = max(sum((max(abs(lo(x)), abs(hi(x))) for x in row), mp.mpf(0)) for row in B)
        k = 0
        while norm / 2 ** k > mp.mpf(1) / 8:
            k += 1
        scale = iv.mpf(2) ** -k
        B = [[x * scale for x in row] for row in B]
        beta = iv.mpf(norm) * scale
        # Terms up to j = J, where β^(J+1)/(J+1)! < 2^-(PREC+10); the rest bounded in ‖·‖∞ by
        # β^(J+1)/(J+1)! · 1/(1 − β/(J+2)).
        Br = [[x._mpi_ for x in row] for row in B]
        Er = [[_RAW_ONE if i == j else _RAW_ZERO for j in range(N)] for i in range(N)]
        term = [row[:] for row in Er]
        J, bound = 0, ONE
        while True:
            J += 1
            term = _raw_matmul(term, Br)
            div = (from_int(J), from_int(J))
            term = [[libmpi.mpi_div(x, div, PREC) for x in row] for row in term]
            Er = [[libmpi.mpi_add(Er[i][l], term[i][l], PREC) for l in range(N)] for i in range(N)]
            bound = bound * beta / J
            if hi(bound * beta / (J + 1)) < mp.mpf(2) ** -(PREC + 10) or J >= 200:
                break
        rest = bound * beta / (J + 1) / (1 - beta / (J + 2))
        pad = iv.mpf([-hi(rest), hi(rest)])._mpi_
        Er = [[libmpi.mpi_add(x, pad, PREC) for x in row] for row in Er]
        for _ in range(k):
            Er = _raw_matmul(Er, Er)
        E = [[iv.make_mpf(x) for x in row] for row in Er]
        if len(self.cache) < 4096:
            self.cache[key] = E
        return E

    def advance(self, z, s):
        """e^{As}z for intervals, or with gradients (D): e^{As}∇z + A e^{As}z ∇s."""
        dual = isinstance(s, D) or any(isinstance(x, D) for x in z)
        if not dual:
            E = self.exp(s)
            return [sum((E[i][k] * z[k] for k in range(self.N)), ZERO) for i in range(self.N)]
        s = D.lift(s)
        z = [D.lift(x) for x in z]
        E = self.exp(s.v)
        Ez = [sum((E[i][k] * z[k].v for k in range(self.N)), ZERO) for i in range(self.N)]
        AEz = [sum((self.A[i][k] * Ez[k] for k in range(self.N)), ZERO) for i in range(self.N)]
        out = []
        for i in range(self.N):
            g = {}
            for k in range(self.N):
                for idx, d in z[k].g.items():
                    g[idx] = g[idx] + E[i][k] * d if idx in g else E[i][k] * d
            for idx, d in s.g.items():
                g[idx] = g[idx] + AEz[i] * d if idx in g else AEz[i] * d
            out.append(D(Ez[i], g))
        return out


def dot(l, z):
    out = ZERO
    for a, b in zip(l, z):
        out = b * D(a) + out if isinstance(b, D) else a * b + out
    return out


def make_krawczyk(residual, C, N):
    def krawczyk(center, box):
        F = [value(r) for r in residual([iv.mpf(x) for x in center])]
        J = [r.g if isinstance(r, D) else {} for r in residual([variable(box[p], p) for p in range(N)])]
        diff = [box[l] - center[l] for l in range(N)]
        K = []
        for p in range(N):
            k = iv.mpf(center[p])
            acc = {}
            for j in range(N):
                c = C[p][j]
                k -= c * F[j]
                for l, d in J[j].items():
                    acc[l] = acc[l] + c * d if l in acc else c * d
            for l in range(N):
                k += ((ONE if l == p else ZERO) - acc.get(l, ZERO)) * diff[l]
            K.append(k)
        return K
    return krawczyk


def plastic_saltation(m, t, X, Vm, vm, sticks):
    """S = Dg + (f⁺ − Dg f⁻)∇hᵀ/(∇h·f⁻) of a plastic landing at contact 0: Dg = diag(I, Π),
    Π = I − T_B cᵀ/s_B; f⁺ the held field (sticking) or the free one (a departure) at ΠẊ⁻."""
    n = m.n
    Pi = [[(ONE if i == l else ZERO) - m.TB[i] * m.c[l] / m.sB for l in range(n)] for i in range(n)]
    Vp = [sum((Pi[i][l] * Vm[l] for l in range(n)), ZERO) for i in range(n)]
    am, ap = m.acceleration(t, X, Vm), m.acceleration(t, X, Vp)
    if sticks:
        ap = [sum((Pi[i][l] * ap[l] for l in range(n)), ZERO) for i in range(n)]
    Pam = [sum((Pi[i][l] * am[l] for l in range(n)), ZERO) for i in range(n)]
    jump = [Vp[i] - Vm[i] for i in range(n)] + [ap[i] - Pam[i] for i in range(n)]
    S = [[ZERO] * (2 * n) for _ in range(2 * n)]
    for i in range(n):
        S[i][i] = ONE
        for l in range(n):
            S[n + i][n + l] = Pi[i][l]
    for i in range(2 * n):
        for l in range(n):
            S[i][l] = S[i][l] + jump[i] * m.c[l] / vm
    return S


def check_sticking_modes(cert, m, ledger):
    """A sticking orbit of several modes held on contact 0 with plastic landings (docs/prove.md
    "Sticking orbits of several modes"): Krawczyk on the release and the landings, each flight free
    of contact, R < 0 at each landing but the last, R > 0 at the last and over the held phase up to
    the release, where Ṙ < 0; the monodromy and its multipliers on the held subspace."""
    if len(m.contacts) > 1:
        raise NotConfirmed("a sticking certificate of several modes needs a model of one contact")
    if m.n < 2:
        raise NotConfirmed("a certificate with unknowns of a sticking orbit needs several modes")
    if not (lo(m.r) == 0 == hi(m.r)):
        raise NotConfirmed("a sticking certificate of several modes needs r = 0 (plastic landings)")
    if not positive(m.sB):
        raise NotConfirmed("s_B = c·T_B must be > 0")
    q = cert["period"].integer(1, 1 << 20)
    n = m.n
    per = 2 * n + 1
    names_node = cert["unknowns"]
    N = len(names_node.items(at_least=2 * per, at_most=MAX_UNKNOWNS))
    if N % per:
        names_node.fail(f"{N} unknowns: not a multiple of 2n + 1 = {per} (n = {n} modes)")
    count = N // per - 1  # landings
    expected = []
    for b in range(count + 1):
        expected += [f"t_{b}"] + [f"X_{b}[{i}]" for i in range(n)] + [f"V_{b}[{i}]" for i in range(n)]
    names = [x.text() for x in names_node.items()]
    if names != expected:
        k = next(p for p in range(N) if names[p] != expected[p])
        names_node[k].fail(f"'{names[k]}', expected '{expected[k]}'")
    u_mid = [x.num() for x in cert["midpoint"].items(exactly=N)]
    box_nodes = cert["box"].items(exactly=N)
    U = [b.pair() for b in box_nodes]
    for p in range(N):
        if not lo(U[p]) < u_mid[p] < hi(U[p]):
            cert["midpoint"][p].fail(f"{u_mid[p]} is not inside the box {show_pair(box_nodes[p].v)}")
    C = [[iv.mpf(x.num()) for x in row.items(exactly=N)] for row in cert["preconditioner"].items(exactly=N)]
    kr_nodes = cert["krawczyk"].items(exactly=N)
    flights = cert["flights"].items(exactly=count)
    mono_nodes = [row.items(exactly=2 * n) for row in cert["monodromy"].items(exactly=2 * n)]
    qT = q * m.T
    h = Held(m)

    def unpack(vec, b):
        o = b * per
        return vec[o], vec[o + 1:o + 1 + n], vec[o + 1 + n:o + per]

    def residual(vec, m=m):
        out = []
        for j in range(count):
            t, X, V = unpack(vec, j)
            tn, Xn, Vn = unpack(vec, j + 1)
            Xe, Ve = m.flight(t, X, V, tn - t)
            Vp = m.impact(Ve)
            out.append(m.contact_of(Xe) - m.x0)
            out += [Xe[i] - Xn[i] for i in range(n)]
            out += [Vp[i] - Vn[i] for i in range(n)]
        tm, Xm, Vm = unpack(vec, count)
        tr, Xr, Vr = unpack(vec, 0)
        z = h.advance(h.state(tm, Xm, Vm), tr + qT - tm)
        out += [z[i] - Xr[i] for i in range(n)]
        out += [z[n + i] - Vr[i] for i in range(n)]
        out.append(dot(h.l, h.state(tr, Xr, Vr)))
        return out

    krawczyk = make_krawczyk(residual, C, N)
    K = krawczyk(u_mid, U)
    E = contract(residual, krawczyk, u_mid, U, K, C, m.point, m.thin)
    for p in range(N):
        ledger.check("krawczyk", names[p], "inside the box", K[p], E[p], box=U[p])
        claim_contains(kr_nodes[p], E[p], f"the orbit's {names[p]}")
        if not holds("inside the box", kr_nodes[p].pair(), U[p]):
            raise NotConfirmed(f"{kr_nodes[p].path} = {show_pair(kr_nodes[p].v)} is not inside the box")

    # The release: R falls through 0.
    rel = cert["release"].obj(("reaction_rate",))
    rate = dot(h.lA, h.state(*unpack(U, 0)))
    rateT = dot(h.lA, h.state(*unpack(E, 0)))
    ledger.check("reaction rate", "release", "< 0", rate, rateT)
    claim_contains(rel["reaction_rate"], rateT, "the reaction rate at the release")

    truth = Truth()
    truth.kind, truth.period = "sticking", q
    truth.sequence = ["release"]
    truth.events = [("release", unpack(E, 0)[0], None)]
    budget = [MAX_PIECES]
    top = max([hi(m.w)] + [hi(w) for w in m.w_i])
    M = [[ONE if i == j else ZERO for j in range(2 * n)] for i in range(2 * n)]
    for j in range(count):
        fn = flights[j]
        fl, land = f"flight {j}", f"landing {j + 1}"
        start = "release" if j == 0 else "departure"
        extra = ("third_derivative", "third_derivative_lower", "fourth_derivative_bound") if j == 0 else \
            ("second_derivative", "second_derivative_lower", "third_derivative_bound")
        fn.obj(("start", "duration", "start_window", "second_derivative_bound", "velocity_before_next",
                "speed_before_lower", "end_window", "pieces", "reaction_at_landing") + extra)
        if fn["start"].text() != start:
            raise NotConfirmed(f"{fn['start'].path}: '{fn['start'].v}', the flight starts at a {start}")

        def quantities(vec):
            t, X, V = unpack(vec, j)
            tn, Xn, Vn = unpack(vec, j + 1)
            S = tn - t
            Xe, Ve = m.flight(t, X, V, S)
            return t, X, V, tn, Xn, Vn, S, Xe, Ve, m.contact_of(Ve)

        t, X, V, tn, Xn, Vn, S, Xe, Ve, vm = quantities(U)
        tT, XT, VT, tnT, XnT, VnT, ST, XeT, VeT, vmT = quantities(E)
        ledger.check("duration", fl, "> 0", S, ST)
        ledger.check("contact velocity before impact", fl, "< 0", vm, vmT)
        claim_contains(fn["duration"], ST, f"the duration of {fl}")
        claim_contains(fn["velocity_before_next"], vmT, f"the contact velocity before {land}")
        ws = fn["start_window"].point()
        if not positive(ws):
            raise NotConfirmed(f"{fn['start_window'].path}: the window must be > 0")
        if j == 0:
            # At the true orbit g = g' = g'' = 0 (on the stop, at rest, R = 0): g(s) >= s^3 (g'''/6 - M4 s/24).
            def g3_of(t_, X_, V_):
                acc = m.acceleration(t_, X_, V_)
                z = m.zeta or [ZERO] * n
                jerk = [m.TA[i] * m.f * m.w * iv.cos(m.w * t_) - m.w_i[i] ** 2 * V_[i] - 2 * z[i] * m.w_i[i] * acc[i]
                        for i in range(n)]
                return m.contact_of(jerk)
            g3, g3T = g3_of(t, X, V), g3_of(tT, XT, VT)
            M4, M4T = m.derivative_bound(t, X, V, 4), m.derivative_bound(tT, XT, VT, 4)
            ledger.check("third derivative of the gap", fl, "> 0", g3, g3T)
            ledger.check("fourth-derivative bound", fl, "finite", M4, M4T)
            claim_contains(fn["third_derivative"], g3T, f"g''' at the start of {fl}")
            claim_lower(fn["third_derivative_lower"], g3, f"g''' at the start of {fl} over the box")
            claim_upper(fn["fourth_derivative_bound"], M4T, f"the bound on |g''''| of {fl}")
            margin = fn["third_derivative_lower"].point() / 6 - M4 * ws / 24
            ledger.check("start window g'''/6 - M4 ws/24", fl, "> 0", margin,
                         fn["third_derivative_lower"].point() / 6 - M4T * ws / 24)
        else:
            g2, g2T = m.contact_of(m.acceleration(t, X, V)), m.contact_of(m.acceleration(tT, XT, VT))
            M3, M3T = m.derivative_bound(t, X, V, 3), m.derivative_bound(tT, XT, VT, 3)
            ledger.check("second derivative of the gap", fl, "> 0", g2, g2T)
            ledger.check("third-derivative bound", fl, "finite", M3, M3T)
            claim_contains(fn["second_derivative"], g2T, f"g'' at the start of {fl}")
            claim_lower(fn["second_derivative_lower"], g2, f"g'' at the start of {fl} over the box")
            claim_upper(fn["third_derivative_bound"], M3T, f"the bound on |g'''| of {fl}")
            margin = fn["second_derivative_lower"].point() / 2 - M3 * ws / 6
            ledger.check("start window g''/2 - M3 ws/6", fl, "> 0", margin,
                         fn["second_derivative_lower"].point() / 2 - M3T * ws / 6)
        M2, M2T = m.derivative_bound(t, X, V, 2), m.derivative_bound(tT, XT, VT, 2)
        ledger.check("second-derivative bound", fl, "finite", M2, M2T)
        claim_upper(fn["second_derivative_bound"], M2T, f"the bound on |g''| of {fl}")
        claim_lower(fn["speed_before_lower"], -vm, f"the contact speed before {land} over the box")
        we = fn["end_window"].point()
        if not positive(we):
            raise NotConfirmed(f"{fn['end_window'].path}: the window must be > 0")
        b_low = fn["speed_before_lower"].point()
        ledger.check("end window b - M2 we/2", fl, "> 0", b_low - M2 * we / 2, b_low - M2T * we / 2)
        topS = hi(iv.mpf(hi(S)) - we)
        if lo(ws) < topS:
            positive_pieces(fn["pieces"], lo(ws), topS,
                            lambda s: m.contact_of(m.flight(t, X, V, s)[0]) - m.x0,
                            lambda s: m.contact_of(m.flight(t, X, V, s)[1]), f"the gap on {fl}", budget)
        else:
            fn["pieces"].items(at_most=MAX_PIECES)
        sticks = j == count - 1
        R_land = dot(h.l, h.state(tn, Xn, Vn))
        R_landT = dot(h.l, h.state(tnT, XnT, VnT))
        ledger.check("reaction at the landing", land, "> 0" if sticks else "< 0", R_land, R_landT)
        claim_contains(fn["reaction_at_landing"], R_landT, f"the reaction at {land}")
        truth.events.append(("impact", tnT, vmT))
        truth.sequence.append("impact")
        if sticks:
            truth.events.append(("stick", tnT, vmT))
            truth.sequence.append("stick")
        else:
            truth.events.append(("departure", tnT, None))
            truth.sequence.append("departure")
        M = matmul(plastic_saltation(m, tnT, XeT, VeT, vmT, sticks), matmul(flight_jacobian(m, tT, XT, VT, ST), M))

    # The held phase: R > 0 from the last landing on, Ṙ < 0 over the end window, R = 0 at the release.
    st = cert["sticking"].obj(("duration", "end_window", "pieces"))
    tm, Xm, Vm = unpack(U, count)
    tmT, XmT, VmT = unpack(E, count)
    zm, zmT = h.state(tm, Xm, Vm), h.state(tmT, XmT, VmT)
    tau, tauT = unpack(U, 0)[0] + qT - tm, unpack(E, 0)[0] + qT - tmT
    ledger.check("duration", "sticking phase", "> 0", tau, tauT)
    claim_contains(st["duration"], tauT, "the duration of the sticking phase")
    weh = st["end_window"].point()
    if not positive(weh):
        raise NotConfirmed(f"{st['end_window'].path}: the window must be > 0")
    Iw = iv.mpf([lo(iv.mpf(lo(tau)) - weh), hi(tau)])
    tail_rate = dot(h.lA, h.advance(zm, Iw))
    ledger.check("reaction rate over the end window", "sticking phase", "< 0", tail_rate, dot(h.lA, h.advance(zmT, tauT)))
    topH = hi(iv.mpf(hi(tau)) - weh)
    if 0 < topH:
        # E(p) for the pieces' ends, stepped exactly: E(p_k) = e^{A(p_k − p_{k−1})} E(p_{k−1}).
        state = {"at": mp.mpf(0), "E": [[ONE if i == j else ZERO for j in range(h.N)] for i in range(h.N)]}

        def at(p):
            if p != state["at"]:
                state["E"] = matmul(h.exp(iv.mpf(p - state["at"])), state["E"])
                state["at"] = p
            return [sum((state["E"][i][k] * zm[k] for k in range(h.N)), ZERO) for i in range(h.N)]

        def r_value(c):
            # e^{Ac}z = e^{A(c − p)} e^{Ap} z for the last stepped end p.
            p0 = state["at"]
            return dot(h.l, h.advance(at(p0), c - p0))

        def r_slope(I):
            p0 = lo(I)
            return dot(h.lA, h.advance(at(p0), I - p0))

        positive_pieces(st["pieces"], mp.mpf(0), topH, r_value, r_slope, "the reaction over the sticking phase",
                        budget)
    else:
        st["pieces"].items(at_most=MAX_PIECES)

    # The monodromy at the true orbit and its restriction to the held subspace.
    Eh = h.exp(tauT)
    M = matmul([row[:2 * n] for row in Eh[:2 * n]], M)
    for i in range(2 * n):
        for j in range(2 * n):
            claim_contains(mono_nodes[i][j], M[i][j], f"the monodromy entry ({i}, {j}) of the orbit")
    kk = max(range(n), key=lambda i: abs(mid(m.c[i])))
    if not excludes_zero(m.c[kk]):
        raise NotConfirmed("the contact's shape has no nonzero entry")
    keep = [b * n + i for b in range(2) for i in range(n) if i != kk]
    B = [[ZERO] * len(keep) for _ in range(2 * n)]
    for col, p in enumerate(keep):
        b, i = divmod(p, n)
        B[p][col] = ONE
        B[b * n + kk][col] = -m.c[i] / m.c[kk]
    MB = matmul(M, B)
    Mr = [[MB[p][col] for col in range(len(keep))] for p in keep]
    boxes = eigenvalues(Mr)
    truth.multipliers = boxes
    truth.not_enclosed = boxes is None
    truth.held_note = True
    truth.section = (*unpack(E, 0), "the release")
    truth.min_box_width = max(hi(x) - lo(x) for x in U)

    def reason(node, text):
        interval_prefix(node, "", m)
        g = re.fullmatch(r"exactly one period-(\d+) sticking orbit of (\d+) modes through the release in a box of "
                         r"width (\S+) \(Krawczyk\): release, (\d+) flight\(s\) with plastic landings, sticking with "
                         r"R > 0 until the next release", text)
        if not g:
            raise NotConfirmed(f"{node.path}: '{text[:120]}' is not a statement the checker verifies")
        check_count(node, "period", int(g.group(1)), q)
        check_count(node, "modes", int(g.group(2)), n)
        check_width(node, g.group(3), max(hi(x) - lo(x) for x in U), "the box")
        check_count(node, "flights", int(g.group(4)), count)
    truth.reason = reason
    return truth


# ---- Sticking orbits held on sets of contacts --------------------------------------------------

SET_NOTE = ("sticking on the contacts held at the section collapses their displacements and velocities: the "
            "multipliers listed are those of the monodromy on the held subspace, its other multipliers are 0")
HELD_SET_KEYS = ("unknowns", "midpoint", "box", "preconditioner", "krawczyk", "segments", "coupling", "monodromy")


def iv_inverse(A, what):
    """The inverse of a small interval matrix (Gauss–Jordan on the diagonal pivots); exact zeros stay
    exact."""
    p = len(A)
    W = [list(row) for row in A]
    I = [[ONE if i == j else ZERO for j in range(p)] for i in range(p)]
    for k in range(p):
        piv = W[k][k]
        if not excludes_zero(piv):
            raise NotConfirmed(f"{what}: a pivot of the matrix is not separated from 0 ({show_iv(piv)})")
        W[k] = [x / piv for x in W[k]]
        I[k] = [x / piv for x in I[k]]
        for i in range(p):
            if i != k:
                f = W[i][k]
                W[i] = [W[i][j] - f * W[k][j] for j in range(p)]
                I[i] = [I[i][j] - f * I[k][j] for j in range(p)]
    return I


def iv_det(A):
    if not A:
        return ONE
    if len(A) == 1:
        return A[0][0]
    out = ZERO
    for c in range(len(A)):
        minor = [[A[r][k] for k in range(len(A)) if k != c] for r in range(1, len(A))]
        term = A[0][c] * iv_det(minor)
        out = out + term if c % 2 == 0 else out - term
    return out


class HeldSet(Held):
    """The flow with every contact of the set H held (docs/contacts.md "Sticking on several contacts at
    once"), written directly: Ẍ = a + Σ_h T_h λ_h with λ chosen so that c_h·Ẍ = 0 for h ∈ H, i.e.
    W_HH λ = −C_H a, a = T_A f sin ωt − Ω²X − DẊ; in Z = (X, Ẋ, sin ωt, cos ωt) a linear system Ż = AZ.
    H empty: the free flow. force[h]·Z = λ_h, rate[h]·Z = λ̇_h."""

    def __init__(self, m, held):
        n, N = m.n, 2 * m.n + 2
        self.n, self.N, self.m, self.held = n, N, m, list(held)
        z = m.zeta or [ZERO] * n
        D_ = [2 * z[i] * m.w_i[i] for i in range(n)]
        W = [[sum((m.contacts[a][0][i] * m.contacts[b][1][i] for i in range(n)), ZERO) for b in held] for a in held]
        Wi = iv_inverse(W, f"the contact matrix of the held set {held}") if held else []
        A = [[ZERO] * N for _ in range(N)]
        force = [[ZERO] * N for _ in held]
        for k in range(N):
            X = [ONE if k == i else ZERO for i in range(n)]
            V = [ONE if k == n + i else ZERO for i in range(n)]
            sn = ONE if k == 2 * n else ZERO
            cs = ONE if k == 2 * n + 1 else ZERO
            free = [m.TA[i] * m.f * sn - m.w_i[i] ** 2 * X[i] - D_[i] * V[i] for i in range(n)]
            Ca = [sum((m.contacts[h][0][i] * free[i] for i in range(n)), ZERO) for h in held]
            lam = [-sum((Wi[r][q] * Ca[q] for q in range(len(held))), ZERO) for r in range(len(held))]
            for r in range(len(held)):
                force[r][k] = lam[r]
            for i in range(n):
                A[i][k] = V[i]
                A[n + i][k] = free[i] + sum((m.contacts[h][1][i] * lam[r] for r, h in enumerate(held)), ZERO)
            A[2 * n][k] = m.w * cs
            A[2 * n + 1][k] = -m.w * sn
        self.A = A
        self.force = force
        self.rate = [[sum((f[i] * A[i][k] for i in range(N)), ZERO) for k in range(N)] for f in force]
        self.cache = exponentials_of(A)

    def row_power(self, row, k):
        for _ in range(k):
            row = [sum((row[i] * self.A[i][c] for i in range(self.N)), ZERO) for c in range(self.N)]
        return row


def stepped(h, z0):
    """s ↦ e^{As}z0 for increasing s, e^{A(p_k − p_{k−1})} stepped exactly from the last end p_k
    (the pieces of a positivity test come in order)."""
    state = {"at": mp.mpf(0), "E": [[ONE if i == j else ZERO for j in range(h.N)] for i in range(h.N)]}

    def at(p):
        if p < state["at"]:
            state["at"], state["E"] = mp.mpf(0), [[ONE if i == j else ZERO for j in range(h.N)] for i in range(h.N)]
        if p != state["at"]:
            state["E"] = matmul(h.exp(iv.mpf(p - state["at"])), state["E"])
            state["at"] = p
        return [sum((state["E"][i][k] * z0[k] for k in range(h.N)), ZERO) for i in range(h.N)]

    def value(row, c):
        # e^{Ac}z0 = e^{A(c − p)} e^{Ap} z0 from the last stepped end p (≤ c; else from 0).
        p0 = state["at"] if state["at"] <= lo(c) else mp.mpf(0)
        return dot(row, h.advance(at(p0), c - p0))

    def slope(row, I):
        p0 = lo(I)
        return dot(row, h.advance(at(p0), I - p0))

    return value, slope


def positive_pieces_refined(node, a, b, f_value, f_slope, what, budget, depth=12):
    """positive_pieces, where a piece whose mean-value form does not clear 0 is bisected (up to
    `depth` times) before it is rejected: f > 0 on the piece is what the certificate claims, and the
    checker's own enclosures (at 192 bits, its own exponentials, looser over an interval of times
    than the prover's) may need finer pieces to confirm it."""
    pieces = node.items(at_least=1, at_most=MAX_PIECES)
    budget[0] -= len(pieces)
    if budget[0] < 0:
        node.fail(f"more than {MAX_PIECES} pieces in the certificate")
    vals = [(lo(x), hi(x)) for x in (p.pair() for p in pieces)]
    if vals[0][0] > a:
        raise NotConfirmed(f"{what}: the pieces start at {show(vals[0][0])}, after {show(a)}")
    if vals[-1][1] < b:
        raise NotConfirmed(f"{what}: the pieces end at {show(vals[-1][1])}, before {show(b)}")

    def form(p0, p1):
        c = iv.mpf((p0 + p1) / 2)
        I = iv.mpf([p0, p1])
        return f_value(c) + f_slope(I) * (I - c)

    def clears(p0, p1, d):
        f = form(p0, p1)
        if positive(f):
            return None
        if d == 0:
            return f
        m = (p0 + p1) / 2
        return clears(p0, m, d - 1) or clears(m, p1, d - 1)

    for k, (p0, p1) in enumerate(vals):
        if k > 0 and vals[k - 1][1] != p0:
            raise NotConfirmed(f"{what}: a hole or an overlap between pieces {k - 1} and {k}")
        if not p0 < p1:
            raise NotConfirmed(f"{node.path}[{k}]: an empty piece")
        f = clears(p0, p1, depth)
        if f is not None:
            raise NotConfirmed(f"{what}: not positive on {node.path}[{k}] = [{show(p0)}, {show(p1)}] ({show_iv(f)})")


def set_text(s):
    return "{" + ", ".join(str(x) for x in s) + "}"


def structure_coupling(node, m):
    """W_jk = σ_jσ_k w_jᵀM⁻¹w_k exactly (rational arithmetic on the mass matrix's decimals) when every
    mode is kept: then it is the modal Σ_i c_j,i T_k,i of the true modal data."""
    from fractions import Fraction
    rows = node["mass"].items()
    N = len(rows)
    if node["kept"].integer(1, N) != N:
        raise NotConfirmed(f"{node['kept'].path}: the coupling from the structure needs every mode kept")
    M = [[Fraction(x.text()) for x in r.items(exactly=N)] for r in rows]
    Inv = [[Fraction(int(i == j)) for j in range(N)] for i in range(N)]
    for k in range(N):
        p = next((r for r in range(k, N) if M[r][k] != 0), None)
        if p is None:
            raise NotConfirmed(f"{node['mass'].path}: singular")
        M[k], M[p], Inv[k], Inv[p] = M[p], M[k], Inv[p], Inv[k]
        piv = M[k][k]
        M[k] = [x / piv for x in M[k]]
        Inv[k] = [x / piv for x in Inv[k]]
        for i in range(N):
            if i != k and M[i][k] != 0:
                f = M[i][k]
                M[i] = [a - f * b for a, b in zip(M[i], M[k])]
                Inv[i] = [a - f * b for a, b in zip(Inv[i], Inv[k])]
    ws = []
    for cn in node["contacts"].items(exactly=len(m.contacts)):
        d, q = cn["dof"].integer(0, N - 1), cn["partner"].integer(-1, N - 1)
        s = 1 if cn["side"].text(("below", "above")) == "below" else -1
        w = [Fraction(0)] * N
        w[d] += s
        if q >= 0:
            w[q] -= s
        ws.append(w)
    J = len(ws)
    out = [[None] * J for _ in range(J)]
    for a in range(J):
        for b in range(J):
            x = sum((ws[a][i] * Inv[i][k] * ws[b][k] for i in range(N) for k in range(N)), Fraction(0))
            out[a][b] = iv.mpf(x.numerator) / iv.mpf(x.denominator) if x != 0 else ZERO
    return out


def check_held_set(cert, m, ledger):
    """A sticking orbit held on sets of contacts with plastic landings (docs/prove.md "Sticking orbits
    held on sets of contacts"): Krawczyk on the segments' starts; per segment every held force > 0 up
    to the end window of its release, where it falls; every other gap > 0 (start windows after a
    release or a departure, an end window before a landing); at each landing the contact matrix a
    P-matrix and the held contacts' impulses >= 0; the monodromy and its multipliers on the subspace
    held at the section."""
    q = cert["period"].integer(1, 1 << 20)
    n, J = m.n, len(m.contacts)
    if J < 2:
        raise NotConfirmed("a certificate of a sticking orbit held on sets needs a model of several contacts")
    per = 2 * n + 1
    seg_nodes = cert["segments"].items(at_least=2, at_most=MAX_UNKNOWNS // per)
    count = len(seg_nodes)
    N = count * per
    names = [x.text() for x in cert["unknowns"].items(exactly=N)]
    expected = []
    for b in range(count):
        expected += [f"t_{b}"] + [f"X_{b}[{i}]" for i in range(n)] + [f"V_{b}[{i}]" for i in range(n)]
    if names != expected:
        k = next(p for p in range(N) if names[p] != expected[p])
        cert["unknowns"][k].fail(f"'{names[k]}', expected '{expected[k]}'")
    # The segments' sets and events, and their consistency.
    helds, ends = [], []
    for k, sn in enumerate(seg_nodes):
        end = sn["end"].text(("landing", "release"))
        keys = ("held", "end", "contact", "duration", "forces", "gaps")
        if end == "landing":
            keys += ("sticks",) + (("velocity_before", "impulses") if k < count - 1 else ())
        sn.obj(keys)
        held = [x.integer(0, J - 1) for x in sn["held"].items(at_most=J)]
        if held != sorted(set(held)):
            sn["held"].fail("not an ascending list of distinct contacts")
        c = sn["contact"].integer(0, J - 1)
        helds.append(held)
        ends.append((end == "landing", c, sn["sticks"].boolean() if end == "landing" else False))
    if ends[-1][0]:
        raise NotConfirmed(f"{seg_nodes[-1].path}: the last segment must end at the release that starts segment 0")
    landed, ever = set(), set()
    for k in range(count):
        landing, c, sticks = ends[k]
        nxt = set(helds[k])
        if landing and c in nxt or not landing and c not in nxt:
            raise NotConfirmed(f"{seg_nodes[k].path}: contact {c} cannot {'land' if landing else 'be released'} "
                               f"while the set {set_text(helds[k])} is held")
        if landing and sticks:
            nxt.add(c)
        if not landing:
            nxt.discard(c)
        if sorted(nxt) != helds[(k + 1) % count]:
            raise NotConfirmed(f"{seg_nodes[(k + 1) % count].path}.held: {set_text(helds[(k + 1) % count])}, the "
                               f"event before leaves {set_text(sorted(nxt))} held")
        if landing:
            landed.add(c)
            if not (lo(m.contacts[c][3]) == 0 == hi(m.contacts[c][3])):
                raise NotConfirmed(f"{seg_nodes[k].path}: a plastic landing of contact {c}, whose restitution is not 0")
        ever.update(helds[k])
    if ever - landed:
        raise NotConfirmed(f"contact {min(ever - landed)} is held but never lands: its constraint is no equation of the "
                           f"orbit")
    flows = [HeldSet(m, h) for h in helds]
    proj = [None] * count
    for k in range(count):
        landing, c, _ = ends[k]
        if landing:
            Z = sorted(helds[k] + [c])
            W = [[sum((m.contacts[a][0][i] * m.contacts[b][1][i] for i in range(n)), ZERO) for b in Z] for a in Z]
            Wi = iv_inverse(W, f"the contact matrix of {set_text(Z)}")
            proj[k] = [[(ONE if i == l else ZERO) - sum((m.contacts[Z[r]][1][i] * Wi[r][s] * m.contacts[Z[s]][0][l]
                                                         for r in range(len(Z)) for s in range(len(Z))), ZERO)
                        for l in range(n)] for i in range(n)]
    u_mid = [x.num() for x in cert["midpoint"].items(exactly=N)]
    box_nodes = cert["box"].items(exactly=N)
    U = [b.pair() for b in box_nodes]
    for p in range(N):
        if not lo(U[p]) < u_mid[p] < hi(U[p]):
            cert["midpoint"][p].fail(f"{u_mid[p]} is not inside the box {show_pair(box_nodes[p].v)}")
    C = [[iv.mpf(x.num()) for x in row.items(exactly=N)] for row in cert["preconditioner"].items(exactly=N)]
    kr_nodes = cert["krawczyk"].items(exactly=N)
    mono_nodes = [row.items(exactly=2 * n) for row in cert["monodromy"].items(exactly=2 * n)]
    qT = q * m.T

    def unpack(vec, b):
        o = (b % count) * per
        return vec[o], vec[o + 1:o + 1 + n], vec[o + 1 + n:o + per]

    def end_time(vec, k):
        return unpack(vec, k + 1)[0] + (qT if k == count - 1 else 0)

    def residual(vec):
        out = []
        for k in range(count):
            t, X, V = unpack(vec, k)
            tn, Xn, Vn = end_time(vec, k), *unpack(vec, k + 1)[1:]
            h = flows[k]
            z = h.advance(h.state(t, X, V), tn - t)
            landing, c, _ = ends[k]
            Ve = z[n:2 * n]
            if landing:
                out.append(m.contact_of(z[:n], c) - m.contacts[c][2])
                Vp = []
                for i in range(n):
                    acc = ZERO
                    for l in range(n):
                        term = Ve[l] * D(proj[k][i][l]) if isinstance(Ve[l], D) else proj[k][i][l] * Ve[l]
                        acc = term + acc  # a D on the left: D + interval, never interval + D
                    Vp.append(acc)
                Ve = Vp
            else:
                out.append(dot(h.force[h.held.index(c)], z))
            out += [z[i] - Xn[i] for i in range(n)]
            out += [Ve[i] - Vn[i] for i in range(n)]
        return out

    krawczyk = make_krawczyk(residual, C, N)
    K = krawczyk(u_mid, U)
    E = contract(residual, krawczyk, u_mid, U, K, C, m.point, m.thin)
    for p in range(N):
        ledger.check("krawczyk", names[p], "inside the box", K[p], E[p], box=U[p])
        claim_contains(kr_nodes[p], E[p], f"the orbit's {names[p]}")
        if not holds("inside the box", kr_nodes[p].pair(), U[p]):
            raise NotConfirmed(f"{kr_nodes[p].path} = {show_pair(kr_nodes[p].v)} is not inside the box")

    # The coupling W between the contacts: from the structure (every mode kept) or the modal data.
    cp = cert["coupling"].obj(("source", "W"))
    source = cp["source"].text(("structure", "modal"))
    if source == "structure":
        if not cert.has("structure"):
            raise NotConfirmed(f"{cp['source'].path}: 'structure', but the certificate has no structure")
        Wc = structure_coupling(cert["structure"], m)
    else:
        Wc = [[sum((m.contacts[a][0][i] * m.contacts[b][1][i] for i in range(n)), ZERO) for b in range(J)]
              for a in range(J)]
    for a, row in enumerate(cp["W"].items(exactly=J)):
        for b, x in enumerate(row.items(exactly=J)):
            claim_contains(x, Wc[a][b], f"the coupling W_{a}{b} of the contacts")

    truth = Truth()
    truth.kind, truth.period = "sticking", q
    first = ends[-1][1]
    truth.sequence = ["release"]
    truth.events = [("release", unpack(E, 0)[0], None)]
    truth.contacts = [first]
    budget = [MAX_PIECES]
    top = max([hi(m.w)] + [hi(w) for w in m.w_i])
    Mo = [[ONE if i == j else ZERO for j in range(2 * n)] for i in range(2 * n)]
    for k in range(count):
        sn, h = seg_nodes[k], flows[k]
        landing, c, sticks = ends[k]
        prev = ends[k - 1]
        seg = f"segment {k}"
        t, X, V = unpack(U, k)
        tT, XT, VT = unpack(E, k)
        S, ST = end_time(U, k) - t, end_time(E, k) - tT
        ledger.check("duration", seg, "> 0", S, ST)
        claim_contains(sn["duration"], ST, f"the duration of {seg}")
        z0, z0T = h.state(t, X, V), h.state(tT, XT, VT)
        val, slp = stepped(h, z0)
        # The forces of the held contacts.
        fnodes = sn["forces"].items(exactly=len(helds[k]))
        for r, (fn, hc) in enumerate(zip(fnodes, helds[k])):
            fn.obj(("contact", "end_window", "pieces"))
            if fn["contact"].integer(0, J - 1) != hc:
                fn["contact"].fail(f"{fn['contact'].v}, expected {hc}")
            where = f"{seg}, force of contact {hc}"
            w = fn["end_window"].num()
            topF = hi(S)
            if not landing and c == hc:
                if not w > 0:
                    raise NotConfirmed(f"{fn['end_window'].path}: the window must be > 0")
                Iw = iv.mpf([lo(iv.mpf(lo(S)) - w), hi(S)])
                rate = dot(h.rate[r], h.advance(z0, Iw))
                rateT = dot(h.rate[r], h.advance(z0T, ST))
                ledger.check("force rate over the end window", where, "< 0", rate, rateT)
                topF = hi(iv.mpf(hi(S)) - w)
            elif w != 0:
                raise NotConfirmed(f"{fn['end_window'].path}: contact {hc} is not released at the end of {seg}")
            if 0 < topF:
                positive_pieces_refined(fn["pieces"], mp.mpf(0), topF, lambda s, r=r: val(h.force[r], s),
                                lambda I, r=r: slp(h.rate[r], I), f"the force of contact {hc} on {seg}", budget)
            else:
                fn["pieces"].items(at_most=MAX_PIECES)
        # Every other gap.
        others = [j for j in range(J) if j not in helds[k]]
        gnodes = sn["gaps"].items(exactly=len(others))
        for gn, j in zip(gnodes, others):
            gn.obj(("contact", "start", "start_window", "end_window", "pieces"))
            if gn["contact"].integer(0, J - 1) != j:
                gn["contact"].fail(f"{gn['contact'].v}, expected {j}")
            where = f"{seg}, gap of contact {j}"
            start = "open"
            if prev[1] == j and not (prev[0] and prev[2]):
                start = "departure" if prev[0] else "release"
            if gn["start"].text(("open", "release", "departure")) != start:
                raise NotConfirmed(f"{gn['start'].path}: '{gn['start'].v}', the gap of contact {j} starts at a {start}")
            g0 = [m.contacts[j][0][i] for i in range(n)] + [ZERO] * (n + 2)
            g1 = h.row_power(g0, 1)
            ws = gn["start_window"].num()
            bottom = mp.mpf(0)
            if start != "open":
                if not ws > 0:
                    raise NotConfirmed(f"{gn['start_window'].path}: the window must be > 0")
                order = 2 if start == "departure" else 3
                gk = h.row_power(g0, order)
                d = dot(gk, h.advance(z0, iv.mpf([0, ws])))
                dT = dot(gk, z0T)
                ledger.check("third derivative of the gap over the start window" if order == 3 else
                             "second derivative of the gap over the start window", where, "> 0", d, dT)
                bottom = mp.mpf(ws)
            elif ws != 0:
                raise NotConfirmed(f"{gn['start_window'].path}: the gap of contact {j} is open at the start of {seg}")
            we = gn["end_window"].num()
            topG = hi(S)
            if landing and c == j:
                if not we > 0:
                    raise NotConfirmed(f"{gn['end_window'].path}: the window must be > 0")
                Iw = iv.mpf([lo(iv.mpf(lo(S)) - we), hi(S)])
                ledger.check("gap velocity over the end window", where, "< 0", dot(g1, h.advance(z0, Iw)),
                             dot(g1, h.advance(z0T, ST)))
                topG = hi(iv.mpf(hi(S)) - we)
            elif we != 0:
                raise NotConfirmed(f"{gn['end_window'].path}: contact {j} does not land at the end of {seg}")
            if bottom < topG:
                e_j = m.contacts[j][2]
                positive_pieces_refined(gn["pieces"], bottom, topG, lambda s, g0=g0, e_j=e_j: val(g0, s) - e_j,
                                lambda I, g1=g1: slp(g1, I), f"the gap of contact {j} on {seg}", budget)
            else:
                gn["pieces"].items(at_most=MAX_PIECES)
        # The monodromy through the segment, and its end event.
        Eh = h.exp(ST)
        Mo = matmul([row[:2 * n] for row in Eh[:2 * n]], Mo)
        if k == count - 1:
            break
        tnT = end_time(E, k)
        if landing:
            land = f"landing at the end of segment {k}"
            zS, zST = h.advance(z0, S), h.advance(z0T, ST)
            vm, vmT = m.contact_of(zS[n:2 * n], c), m.contact_of(zST[n:2 * n], c)
            ledger.check("contact velocity before impact", land, "< 0", vm, vmT)
            claim_contains(sn["velocity_before"], vmT, f"the contact velocity before the {land}")
            Z = sorted(helds[k] + [c])
            for mask in range(1, 1 << len(Z)):
                sub = [Z[r] for r in range(len(Z)) if mask >> r & 1]
                if len(sub) < 2:
                    continue
                d = iv_det([[Wc[a][b] for b in sub] for a in sub])
                ledger.check("principal minor of W", f"{land}, contacts {set_text(sub)}", "> 0", d, d)
            imp = sn["impulses"].items(exactly=len(Z) - 1 if len(Z) > 1 else 0)
            if len(Z) > 1:
                Wi = iv_inverse([[Wc[a][b] for b in Z] for a in Z], f"the coupling of {set_text(Z)}")
                jz = Z.index(c)
                others_z = [r for r in range(len(Z)) if r != jz]
                for node_, r in zip(imp, others_z):
                    node_.obj(("contact", "value"))
                    if node_["contact"].integer(0, J - 1) != Z[r]:
                        node_["contact"].fail(f"{node_['contact'].v}, expected {Z[r]}")
                    x = Wi[r][jz]
                    ledger.check("impulse per unit speed", f"{land}, contact {Z[r]}", ">= 0", x, x)
                    claim_contains(node_["value"], x, f"the impulse per unit speed of contact {Z[r]}")
            # Saltation at the true orbit.
            Pz = proj[k]
            hn = flows[k + 1]
            Ve = zST[n:2 * n]
            zp = list(zST)
            for i in range(n):
                zp[n + i] = sum((Pz[i][l] * Ve[l] for l in range(n)), ZERO)
            fm = [sum((h.A[i][l] * zST[l] for l in range(h.N)), ZERO) for i in range(h.N)]
            fp = [sum((hn.A[i][l] * zp[l] for l in range(h.N)), ZERO) for i in range(h.N)]
            jump = [fp[i] - fm[i] for i in range(n)] + \
                [fp[n + i] - sum((Pz[i][l] * fm[n + l] for l in range(n)), ZERO) for i in range(n)]
            Sal = [[ZERO] * (2 * n) for _ in range(2 * n)]
            for i in range(n):
                Sal[i][i] = ONE
                for l in range(n):
                    Sal[n + i][n + l] = Pz[i][l]
            for i in range(2 * n):
                for l in range(n):
                    Sal[i][l] = Sal[i][l] + jump[i] * m.contacts[c][0][l] / vmT
            Mo = matmul(Sal, Mo)
            truth.events.append(("impact", tnT, vmT))
            truth.sequence.append("impact")
            truth.contacts.append(c)
            truth.events.append(("stick", tnT, vmT) if sticks else ("departure", tnT, None))
            truth.sequence.append("stick" if sticks else "departure")
            truth.contacts.append(c)
        else:
            truth.events.append(("release", tnT, None))
            truth.sequence.append("release")
            truth.contacts.append(c)
    for i in range(2 * n):
        for j in range(2 * n):
            claim_contains(mono_nodes[i][j], Mo[i][j], f"the monodromy entry ({i}, {j}) of the orbit")

    # The least period: for every prime ℓ dividing q the segments shifted by count/ℓ differ.
    for ell in prime_factors(q):
        if count % ell:
            continue
        hs = count // ell
        apart = False
        for k in range(count):
            k2 = (k + hs) % count
            if ends[k] != ends[k2] or helds[k] != helds[k2]:
                apart = True
                break
            tk, Xk, Vk = unpack(E, k)
            t2, X2, V2 = unpack(E, k2)
            dt = t2 + (qT if k + hs >= count else 0) - tk - (q // ell) * m.T
            if excludes_zero(dt) or any(excludes_zero(X2[i] - Xk[i]) or excludes_zero(V2[i] - Vk[i]) for i in range(n)):
                apart = True
                break
        if not apart:
            raise NotConfirmed(f"period: {q} is claimed, but the orbit repeats after {q // ell} forcing period(s)")

    # The multipliers: the restriction to the subspace held at the section.
    P = helds[-1]
    piv = []
    Cm = [[mid(m.contacts[h][0][i]) for i in range(n)] for h in P]
    for r in range(len(P)):
        best = max((i for i in range(n) if i not in piv), key=lambda i: abs(Cm[r][i]))
        if Cm[r][best] == 0:
            raise NotConfirmed("the contacts held at the section are dependent")
        piv.append(best)
        for r2 in range(r + 1, len(P)):
            f = Cm[r2][best] / Cm[r][best]
            Cm[r2] = [a - f * b for a, b in zip(Cm[r2], Cm[r])]
    Cpi = iv_inverse([[m.contacts[h][0][pv] for pv in piv] for h in P], "the contacts held at the section")
    free_modes = [i for i in range(n) if i not in piv]
    keep = [b * n + i for b in range(2) for i in free_modes]
    B = [[ZERO] * len(keep) for _ in range(2 * n)]
    for col, p in enumerate(keep):
        b, i = divmod(p, n)
        B[p][col] = ONE
        for a in range(len(P)):
            B[b * n + piv[a]][col] = -sum((Cpi[a][r] * m.contacts[P[r]][0][i] for r in range(len(P))), ZERO)
    if keep:
        MB = matmul(Mo, B)
        Mr = [[MB[p][col] for col in range(len(keep))] for p in keep]
        boxes = eigenvalues(Mr)
    else:
        boxes = []
    truth.multipliers = boxes
    truth.not_enclosed = boxes is None
    truth.set_note = True
    truth.section = (*unpack(E, 0), "the release")
    truth.min_box_width = max(hi(x) - lo(x) for x in U)
    landings = sum(1 for e in ends if e[0])

    def reason(node, text):
        interval_prefix(node, "", m)
        g = re.fullmatch(r"exactly one period-(\d+) sticking orbit of (\d+) modes held on sets of contacts through the "
                         r"release of contact (\d+) in a box of width (\S+) \(Krawczyk\): (\d+) segments, (\d+) plastic "
                         r"landing\(s\) and (\d+) release\(s\), every held force > 0 and every other gap > 0 between "
                         r"them", text)
        if not g:
            raise NotConfirmed(f"{node.path}: '{text[:120]}' is not a statement the checker verifies")
        check_count(node, "period", int(g.group(1)), q)
        check_count(node, "modes", int(g.group(2)), n)
        check_count(node, "released contact", int(g.group(3)), first)
        check_width(node, g.group(4), max(hi(x) - lo(x) for x in U), "the box")
        check_count(node, "segments", int(g.group(5)), count)
        check_count(node, "landings", int(g.group(6)), landings)
        check_count(node, "releases", int(g.group(7)), count - landings)
    truth.reason = reason
    return truth


# ---- One certificate --------------------------------------------------------------------------

CERT_KEYS = ("format", "verdict", "reason", "kind", "period", "model", "libraries", "precision_bits", "summary",
             "inequalities")
IMPACT_KEYS = ("unknowns", "midpoint", "box", "preconditioner", "krawczyk", "flights", "monodromy")
STICKING_KEYS = ("release", "flights", "sticking")


def check_structure(node, m):
    """The scene as written (docs/prove.md): a physical scene's mass and stiffness matrices, its
    contacts and its eigenpair boxes. Proves that each box holds exactly one eigenpair (λ, ψ) of
    K ψ = λ M ψ with ψ scaled to a unit component at contact 0 (Krawczyk's test on
    F(λ, ψ) = ((K − λM)ψ, σ_0 w_0ᵀψ − 1)), that M is positive definite (so the N disjoint boxes hold
    every eigenvalue) and the boxes ascend, and that the model's modal data contain the values
    docs/model.md §1.3 builds from the kept (lowest) modes: ω = √λ, m = ψᵀMψ, T_A = ψ(A)/m,
    T_B = 1/m, c = 1, and for contact j ≥ 1 c_j = σ_j w_jᵀψ, T_j = c_j/m; the damping ratios are
    the scene's, mode by mode."""
    node.obj(("mass", "stiffness", "forcing_dof", "contacts", "modes", "kept"), ("damping",))
    rows = node["mass"].items(at_least=1, at_most=MAX_MODES)
    N = len(rows)
    Mx = [[decimal(x) for x in r.items(exactly=N)] for r in rows]
    Kx = [[decimal(x) for x in r.items(exactly=N)] for r in node["stiffness"].items(exactly=N)]
    A = node["forcing_dof"].integer(0, N - 1)
    kept = node["kept"].integer(1, N)
    if kept != m.n:
        node["kept"].fail(f"{kept} kept modes, the model has {m.n}")
    contacts = []
    for cn in node["contacts"].items(exactly=len(m.contacts)):
        cn.obj(("dof", "partner", "side"))
        d, q = cn["dof"].integer(0, N - 1), cn["partner"].integer(-1, N - 1)
        if q == d:
            cn["partner"].fail("an impact pair of a DOF with itself")
        contacts.append((d, q, ONE if cn["side"].text(("below", "above")) == "below" else -ONE))
    for a in range(N):
        for b in range(a):
            for X, key in ((Mx, "mass"), (Kx, "stiffness")):
                if not (lo(X[a][b]) == lo(X[b][a]) and hi(X[a][b]) == hi(X[b][a])):
                    node[key].fail(f"not symmetric at ({a}, {b})")
    # M positive definite (interval Cholesky): det(K − λM) has degree N.
    L = [[ZERO] * N for _ in range(N)]
    for j in range(N):
        d = Mx[j][j] - sum((L[j][k] * L[j][k] for k in range(j)), ZERO)
        if not positive(d):
            raise NotConfirmed(f"{node['mass'].path}: not proven positive definite (pivot {j}: {show_iv(d)})")
        L[j][j] = iv.sqrt(d)
        for i in range(j + 1, N):
            L[i][j] = (Mx[i][j] - sum((L[i][k] * L[j][k] for k in range(j)), ZERO)) / L[j][j]
    d0, q0, s0 = contacts[0]

    def w(vec, d, q, sgn):
        return sgn * (vec[d] - (vec[q] if q >= 0 else ZERO))

    lam, psi = [], []
    for k, mn in enumerate(node["modes"].items(exactly=N)):
        mn.obj(("eigenvalue", "vector"))
        U = [decimal(mn["eigenvalue"])] + [decimal(x) for x in mn["vector"].items(exactly=N)]
        if not all(finite(x) for x in U):
            mn.fail("not finite")
        c = [mid(x) for x in U]

        def F(u):
            res = [sum(((Kx[a][b] - u[0] * Mx[a][b]) * u[1 + b] for b in range(N)), ZERO) for a in range(N)]
            return res + [w(u[1:], d0, q0, s0) - ONE]

        def J(u):
            rows_ = [[-sum((Mx[a][b] * u[1 + b] for b in range(N)), ZERO)] + [Kx[a][b] - u[0] * Mx[a][b] for b in range(N)]
                     for a in range(N)]
            last = [ZERO] + [s0 * ((ONE if b == d0 else ZERO) - (ONE if b == q0 else ZERO)) for b in range(N)]
            return rows_ + [last]

        try:
            Y = mp.inverse(mp.matrix([[mid(x) for x in row] for row in J([iv.mpf(x) for x in c])]))
        except ZeroDivisionError:
            raise NotConfirmed(f"{mn.path}: the eigenpair's Jacobian is singular at the box's midpoint")
        def krawczyk(c, U):
            Fc, JU = F([iv.mpf(x) for x in c]), J(U)
            out = []
            for p_ in range(P):
                acc = iv.mpf(c[p_]) - sum((iv.mpf(Y[p_, l]) * Fc[l] for l in range(P)), ZERO)
                for l in range(P):
                    e = (ONE if l == p_ else ZERO) - sum((iv.mpf(Y[p_, r]) * JU[r][l] for r in range(P)), ZERO)
                    acc += e * (U[l] - iv.mpf(c[l]))
                out.append(acc)
            return out

        P = N + 1
        Kr = krawczyk(c, U)
        if not all(lo(Kr[p_]) > lo(U[p_]) and hi(Kr[p_]) < hi(U[p_]) for p_ in range(P)):
            bad = next(p_ for p_ in range(P) if not (lo(Kr[p_]) > lo(U[p_]) and hi(Kr[p_]) < hi(U[p_])))
            raise NotConfirmed(f"{mn.path}: Krawczyk's test fails: the box does not provably hold one eigenpair of "
                               f"K ψ = λ M ψ (unknown {bad}: K = {show_iv(Kr[bad])} not inside {show_iv(U[bad])})")
        # The eigenpair in the box, enclosed tightly: Newton at 192 bits from the midpoint, then
        # Krawczyk's test on a box of relative radius 2^-120 around it inside U (its eigenpair is U's).
        E = [meet(Kr[p_], U[p_]) for p_ in range(P)]
        u = list(c)
        for _ in range(8):
            du = [sum((Y[p_, l] * mid(f) for l, f in enumerate(F([iv.mpf(x) for x in u]))), mp.mpf(0)) for p_ in range(P)]
            u = [u[p_] - du[p_] for p_ in range(P)]
        V = [iv.mpf([x - mp.mpf(2) ** -120 * (1 + abs(x)), x + mp.mpf(2) ** -120 * (1 + abs(x))]) for x in u]
        if all(inside(V[p_], U[p_]) for p_ in range(P)):
            KV = krawczyk(u, V)
            if all(lo(KV[p_]) > lo(V[p_]) and hi(KV[p_]) < hi(V[p_]) for p_ in range(P)):
                E = [meet(KV[p_], V[p_]) for p_ in range(P)]
        lam.append(E[0])
        psi.append(E[1:])
    if not positive(lam[0]) or any(not hi(lam[k]) < lo(lam[k + 1]) for k in range(N - 1)):
        raise NotConfirmed(f"{node['modes'].path}: the eigenvalue boxes are not positive and disjoint in ascending order")
    zeta = None
    if node.has("damping"):
        zeta = [decimal(x) for x in node["damping"].items(exactly=N)]
    for i in range(kept):
        v = psi[i]
        mi = sum((v[a] * Mx[a][b] * v[b] for a in range(N) for b in range(N)), ZERO)
        truths = [("frequencies", m.w_i[i], iv.sqrt(lam[i])), ("forcing", m.TA[i], v[A] / mi),
                  ("contact", m.TB[i], ONE / mi), ("shape", m.c[i], ONE)]
        for j in range(1, len(m.contacts)):
            d, q, sg = contacts[j]
            cj = w(v, d, q, sg)
            truths += [(f"more_contacts[{j - 1}].shape", m.contacts[j][0][i], cj),
                       (f"more_contacts[{j - 1}].contact", m.contacts[j][1][i], cj / mi)]
        for what, claimed, truth in truths:
            if not inside(truth, claimed):
                raise NotConfirmed(f"model.{what}[{i}] = {show_iv(claimed)} does not contain {show_iv(truth)}, the "
                                   f"value of mode {i} of the scene's matrices")
        z = zeta[i] if zeta is not None else ZERO
        zm = m.zeta[i] if m.zeta is not None else ZERO
        if not (inside(z, zm) and inside(zm, z)):
            raise NotConfirmed(f"model.damping[{i}] = {show_iv(zm)} is not the scene's damping ratio {show_iv(z)} of "
                               f"mode {i}")



# ---- Bifurcation points (docs/prove.md "Bifurcation points") ----------------------------------

class T2:
    """A value with its first and second derivatives in three variables (dt, dv, p), intervals:
    what the checker needs to differentiate the half-period map's Jacobian along the branch."""
    __slots__ = ("v", "g", "h")

    def __init__(self, v, g=None, h=None):
        self.v = v if isinstance(v, IV) else iv.mpf(v)
        self.g = g or [ZERO] * 3
        self.h = h or [[ZERO] * 3 for _ in range(3)]

    @staticmethod
    def lift(x):
        return x if isinstance(x, T2) else T2(x)

    def __add__(self, o):
        o = T2.lift(o)
        return T2(self.v + o.v, [a + b for a, b in zip(self.g, o.g)],
                  [[a + b for a, b in zip(r, q)] for r, q in zip(self.h, o.h)])

    __radd__ = __add__

    def __neg__(self):
        return T2(-self.v, [-a for a in self.g], [[-a for a in r] for r in self.h])

    def __sub__(self, o):
        return self + (-T2.lift(o))

    def __rsub__(self, o):
        return T2.lift(o) - self

    def __mul__(self, o):
        o = T2.lift(o)
        return T2(self.v * o.v, [a * o.v + self.v * b for a, b in zip(self.g, o.g)],
                  [[self.h[i][j] * o.v + self.g[i] * o.g[j] + self.g[j] * o.g[i] + self.v * o.h[i][j]
                    for j in range(3)] for i in range(3)])

    __rmul__ = __mul__

    def fn(self, f0, f1, f2):
        """f(self) from f, f', f'' at self.v."""
        return T2(f0, [f1 * a for a in self.g],
                  [[f2 * self.g[i] * self.g[j] + f1 * self.h[i][j] for j in range(3)] for i in range(3)])

    def __truediv__(self, o):
        o = T2.lift(o)
        inv = 1 / o.v
        return self * o.fn(inv, -inv * inv, 2 * inv * inv * inv)

    def __rtruediv__(self, o):
        return T2.lift(o) / self


def t_sin(x):
    s, c = iv.sin(x.v), iv.cos(x.v)
    return x.fn(s, c, -s)


def t_cos(x):
    s, c = iv.sin(x.v), iv.cos(x.v)
    return x.fn(c, -s, -c)


def t_sqrt(x):
    r = iv.sqrt(x.v)
    return x.fn(r, 1 / (2 * r), -1 / (4 * r * x.v))


def symmetric_model(node, m):
    """(Ω, F/f or the forcing as T2-ready intervals, Δ, r) of the symmetric two-sided one-DOF
    oscillator, or NotConfirmed: one undamped mode, contact 1 is contact 0 mirrored."""
    if m.n != 1 or m.zeta is not None or len(m.contacts) != 2:
        raise NotConfirmed(f"{node.path}: a pitchfork certificate is for one undamped mode and two contacts "
                           f"(the model has {m.n} mode(s), {len(m.contacts)} contact(s))")
    (c0, _, e0, r0, _), (c1, _, e1, r1, _) = m.contacts
    mirrored = hi(c0[0] + c1[0]) == 0 and lo(c0[0] + c1[0]) == 0
    if node.has("structure"):  # two stops on one DOF, on opposite sides: c_1 = −c_0 exactly
        cs = node["structure"].v["contacts"]
        mirrored = mirrored or (cs[0]["dof"] == cs[1]["dof"] and cs[0]["partner"] == cs[1]["partner"] == -1 and
                                cs[0]["side"] != cs[1]["side"])
    if not mirrored:
        raise NotConfirmed(f"{node.path}: contact 1 is not contact 0 mirrored (c_1 = −c_0)")
    t = node["model"].v
    if t["stop"] != t["more_contacts"][0]["stop"] or t["restitution"] != t["more_contacts"][0]["restitution"]:
        raise NotConfirmed(f"{node.path}: the two stops or restitutions differ: not symmetric")
    if not negative(e0):
        raise NotConfirmed(f"{node.path}: the clearance −e_0 is not positive")
    return c0[0], e0, r0


def pitchfork_at(m, c0, e0, r, P, frequency, root, fold=False):
    """The symmetric orbit and g = det(DH + I) at the parameter interval P, with dg/dp: (defined,
    v, g, dg/dp, det DH, τ, the flight (s ↦ (y, ẏ)) of the half period).
    The orbit from (T1)-(T2) in the time s = Ωt (ẍ + x = a' sin w's, a' = F/Ω², w' = ω/Ω, v' = v/Ω):
    k1 = (1 + r) tan(θ/2)/2, k2 = (1 − r)/(2w'), θ = π/w', (k1² + k2²)V² − 2Δk1V + Δ² − K² = 0,
    sin φ = (Δ − k1V)/K, cos φ = k2V/K (K = a'/(1 − w'²)); DH by the implicit function theorem on
    the flight written with the variables (dt, dv) of the start, p the parameter."""
    Wm = m.w_i[0]
    p = T2(P, [ZERO, ZERO, ONE])
    f = p if not frequency else T2(m.f)
    w = p if frequency else T2(m.w)
    F = T2(c0 * m.TA[0]) * f
    Delta = T2(-e0)
    a1, w1 = F / (Wm * Wm), w / Wm
    den = 1 - w1 * w1
    if not excludes_zero(den.v):
        return None
    Kamp = a1 / den
    theta = T2(iv.pi) / w1
    half = theta * T2(iv.mpf(0.5))
    tan_half = t_sin(half) / t_cos(half)
    k1 = T2(1 + r) * tan_half * T2(iv.mpf(0.5))
    k2 = T2(1 - r) / (T2(2) * w1)
    A, B, C = k1 * k1 + k2 * k2, T2(-2) * Delta * k1, Delta * Delta - Kamp * Kamp
    disc = B * B - T2(4) * A * C
    if fold:  # every real root V over P: −B/2A ± √max(disc, 0)/2A, and the flight of each
        if not positive(A.v):
            return None
        spread = iv.sqrt(iv.mpf([0, max(hi(disc.v), 0)])) / (2 * A.v)
        Vf = -B.v / (2 * A.v) + iv.mpf([-1, 1]) * spread
        U0v, U1v = Delta.v - k1.v * Vf, w1.v * k2.v * Vf
        yv, ydv, w1v, Dv = Delta.v - U0v, -(r * Vf) - U1v, w1.v, Delta.v

        def fold_flight(S):
            sw, cw, s1, c1 = iv.sin(w1v * S), iv.cos(w1v * S), iv.sin(S), iv.cos(S)
            return (U0v * cw + U1v / w1v * sw + yv * c1 + ydv * s1,
                    -(U0v * w1v) * sw + U1v * cw - yv * s1 + ydv * c1)

        # In the time t and the speed v = ΩV: A = A'/Ω², B = B'/Ω, C = C' (docs/prove.md), so the
        # discriminant in v is this one over Ω².
        return {"V": Vf * Wm, "g": disc.v / (Wm * Wm), "slope": disc.g[2] / (Wm * Wm), "det": ZERO, "theta": theta.v, "flight": fold_flight,
                "Delta": Dv}
    if not positive(disc.v) or not positive(A.v):
        return None
    sq = t_sqrt(disc)
    V = (-B + (sq if root > 0 else -sq)) / (T2(2) * A)
    if not positive(V.v):
        return None
    U0 = Delta - k1 * V           # K sin φ, in the time s
    U1 = w1 * k2 * V              # K w' cos φ
    # The start (time dt after the impact instant, speed V + dv): the forced part at s = dt and the
    # free part matching x = Δ, ẋ = −r(V + dv) there (the impact instant itself moved by dt).
    dt, dv = T2(ZERO, [ONE, ZERO, ZERO]), T2(ZERO, [ZERO, ONE, ZERO])

    def forced(s):
        return U0 * t_cos(w1 * s) + U1 / w1 * t_sin(w1 * s), -(U0 * w1) * t_sin(w1 * s) + U1 * t_cos(w1 * s)

    u_start, ud_start = forced(dt)
    y0, yd0 = Delta - u_start, -(T2(r) * (V + dv)) - ud_start

    def x_at(s):  # s: time since the unperturbed impact
        u, ud = forced(s)
        h = s - dt
        return (u + y0 * t_cos(h) + yd0 * t_sin(h), ud - y0 * t_sin(h) + yd0 * t_cos(h))

    x1, xd1 = x_at(theta)
    # ẍ at the landing: a' sin(w'(s)) − x with a' sin w's = (1 − w'²)(forced displacement).
    u1, _ = forced(theta)
    xdd = den * u1 - x1

    def dp(z, k):  # ∂z/∂(dt, dv)[k] as a (value, d/dp) pair along the branch
        return z.g[k], z.h[k][2]

    def pd(a, b):  # products and quotients of (value, d/dp) pairs
        return a[0] * b[0], a[1] * b[0] + a[0] * b[1]

    def qd(a, b):
        q = a[0] / b[0]
        return q, (a[1] - q * b[1]) / b[0]

    def neg(a):
        return -a[0], -a[1]

    def add(*zs):
        return sum((z[0] for z in zs), ZERO), sum((z[1] for z in zs), ZERO)

    arrival = (xd1.v, xd1.g[2])          # ẋ(θ⁻) = −V', with its d/dp
    acc = (xdd.v, xdd.g[2])
    tt = neg(qd(dp(x1, 0), arrival))
    tv = neg(qd(dp(x1, 1), arrival))
    vt = neg(add(dp(xd1, 0), pd(acc, tt)))
    vv = neg(add(dp(xd1, 1), pd(acc, tv)))
    one = (ONE, ZERO)
    g = add(pd(add(one, tt), add(one, vv)), neg(pd(tv, vt)))
    det = add(pd(tt, vv), neg(pd(tv, vt)))
    # The half-period flight in the original time t = s/Ω (for the gaps).
    W = Wm
    U0v, U1v, yv, ydv = U0.v, U1.v, Delta.v - U0.v, -(r * V.v) - U1.v
    w1v, Dv = w1.v, Delta.v

    def flight(S):
        sw, cw, s1, c1 = iv.sin(w1v * S), iv.cos(w1v * S), iv.sin(S), iv.cos(S)
        return (U0v * cw + U1v / w1v * sw + yv * c1 + ydv * s1,
                -(U0v * w1v) * sw + U1v * cw - yv * s1 + ydv * c1)

    return {"V": V.v * W, "g": g[0], "slope": g[1], "det": det[0], "theta": theta.v,
            "flight": flight, "Delta": Dv}


# The summary of a bifurcation certificate: every key it may hold, by the type of the point.
BIFURCATION_SUMMARY = ("verdict", "reason", "kind", "period", "bifurcation", "parameter", "located", "center",
                       "interval", "width", "box_width", "slope", "param", "events", "sequence", "section",
                       "multipliers", "stability", "modal_data")
BIFURCATION_SUMMARY_KEYS = {
    "pitchfork": BIFURCATION_SUMMARY + ("g_at_ends", "speed", "half_map_multipliers"),
    "fold": BIFURCATION_SUMMARY + ("g_at_ends", "speed"),
    "grazing": BIFURCATION_SUMMARY + ("curvature", "grazing_contact", "grazing_flight", "grazing_time",
                                      "impact_contacts", "symmetric"),
    "orbit-pitchfork": BIFURCATION_SUMMARY + ("impact_contacts", "symmetric"),
}


def bifurcation_summary(node, s, kind, name, P):
    """A bifurcation certificate's summary, read whole before any proof (an unknown or a missing key,
    a value of the wrong type: not a certificate), and its claims that the proof of the point does
    not reach: the kind of point, the parameter's key, the interval's centre (inside the interval)
    and width (the interval's, to one rounding), the modal data, and no orbit's events, sequence,
    section, multipliers or stability (a bifurcation proof claims none)."""
    s.obj(BIFURCATION_SUMMARY_KEYS[kind])
    label = "pitchfork" if kind == "orbit-pitchfork" else kind
    if s["bifurcation"].text(("pitchfork", "fold", "grazing")) != label:
        raise NotConfirmed(f"{s['bifurcation'].path}: '{s['bifurcation'].v}', the certificate proves a {label}")
    if s["param"].text() != f"excitation.{name}":
        raise NotConfirmed(f"{s['param'].path}: '{s['param'].v}', the certificate's parameter is excitation.{name}")
    s["located"].num()  # where the point was looked for (the request: information)
    if not lo(P) <= s["center"].num() <= hi(P):
        raise NotConfirmed(f"{s['center'].path} = {s['center'].v!r} is not in the interval {show_iv(P)}")
    # The width of the prover's double enclosure of the interval's decimal ends: at least the
    # interval's, and above it by a few units in the last place of its ends at most.
    width, ulp = hi(P) - lo(P), max(abs(lo(P)), abs(hi(P))) * mp.mpf(2) ** -52
    for key in ("width", "box_width"):
        w = s[key].num()
        if not width <= w * (1 + mp.mpf(2) ** -52) or not w <= width + 8 * ulp:
            raise NotConfirmed(f"{s[key].path} = {s[key].v!r}: the interval is {show(width)} wide")
    s["slope"].pair()
    for key in ("events", "sequence", "multipliers"):
        if s[key].items():
            raise NotConfirmed(f"{s[key].path}: a bifurcation certificate claims no orbit's {key}")
    if s["section"].v is not None:
        raise NotConfirmed(f"{s['section'].path}: a bifurcation certificate claims no orbit's section (null)")
    if s["stability"].text(("stable", "unstable", "undecided")) != "undecided":
        raise NotConfirmed(f"{s['stability'].path}: '{s['stability'].v}', a bifurcation certificate claims no "
                           "stability ('undecided')")
    claimed = s["modal_data"].text(("given", "enclosed"))
    if claimed != ("enclosed" if node.has("structure") else "given"):
        raise NotConfirmed(f"{s['modal_data'].path}: modal data '{claimed}' but the certificate "
                           f"{'carries' if node.has('structure') else 'has no'} structure")
    return s["period"].integer(1, 1 << 20)


# The reasons of bifurcation certificates (src/proof/*.cpp): `{slope}` is an interval "[a, b]"
# that must contain the checker's enclosure of the derivative it names.
BIFURCATION_REASONS = {
    "pitchfork": "exactly one {name} in [{lo}, {hi}] at which the symmetric orbit's half-period map has the multiplier "
                 "−1 (its period map the multiplier +1 with an antisymmetric eigenvector: the symmetry-breaking "
                 "pitchfork); det(DH + I) changes sign there and its derivative along the branch, {slope}, is nonzero "
                 "over the whole interval: the crossing is transversal",
    "fold": "exactly one {name} in [{lo}, {hi}] at which the two symmetric orbits merge (a fold of the symmetric branch: "
            "the discriminant of their quadratic changes sign there, and its derivative, {slope}, is nonzero over the "
            "whole interval: the fold is nondegenerate)",
    "grazing": "exactly one {name} in [{lo}, {hi}] at which flight {flight} of the orbit touches contact {contact} with "
               "zero velocity (a grazing): the minimum gap m on that flight is zero there and its derivative "
               "dm/d{name}, {slope}, is nonzero over the whole interval: the crossing is transversal (below the point "
               "the flight {below} the contact, above it it {above}){mirror}",
    "orbit-pitchfork": "exactly one {name} in [{lo}, {hi}] at which the symmetric orbit's antisymmetric block is "
                       "singular (its period map has the multiplier +1 with an antisymmetric eigenvector: the "
                       "symmetry-breaking pitchfork); the bordering μ (zero exactly there) has "
                       "dμ/d{name} = {slope}, nonzero over the whole interval: the crossing is transversal",
}
MIRROR = ("; the orbit is symmetric (proven as its half: the second half is the first mirrored), so at the same point "
          "flight 1 touches contact {other} likewise")


def bifurcation_reason(node, kind, E, **fields):
    """The reason of a bifurcation certificate is the prover's sentence for this point, with its
    kind, parameter, interval, flight and contact, and the derivative's interval in it contains the
    checker's enclosure E of that derivative (docs/prove.md)."""
    r = node["reason"]
    text = r.text()
    head, tail = BIFURCATION_REASONS[kind].format(slope="\0", **fields).split("\0")
    if not (text.startswith(head) and text.endswith(tail) and len(text) > len(head) + len(tail)):
        raise NotConfirmed(f"{r.path}: not the sentence of this {kind} ('{head[:60]}...')")
    middle = text[len(head):len(text) - len(tail)]
    g = re.fullmatch(r"\[([^,\[\]]+), ([^,\[\]]+)\]", middle)
    if not g:
        raise NotConfirmed(f"{r.path}: '{middle[:60]}' where the sentence has an interval [a, b]")
    C = iv.mpf([lo(decimal(r, g.group(1))), hi(decimal(r, g.group(2)))])
    if not inside(E, C):
        raise NotConfirmed(f"{r.path}: the derivative's interval {middle} does not contain the checker's enclosure "
                           f"{show_iv(E)}")


def check_bifurcation(node):
    """A bifurcation certificate: the parameter interval holds exactly one pitchfork of the
    symmetric orbit, crossed transversally, recomputed here (g = det(DH + I) of the half-period map
    changes sign between the interval's ends and dg/dp excludes 0 over it; the orbit exists over
    the whole interval: both gaps positive between the impacts)."""
    node.obj(CERT_KEYS[:-1] + ("bifurcation",), ("structure",))
    node["libraries"].text()
    node["precision_bits"].integer(1, 1 << 20)
    s = node["summary"]
    for key in ("verdict", "reason", "kind", "period"):
        if node[key].v != s[key].v or type(node[key].v) is not type(s[key].v):
            raise NotConfirmed(f"{node[key].path} = {node[key].v!r} and {s[key].path} = {s[key].v!r} differ")
    m = Model(node["model"])
    if node.has("structure"):
        check_structure(node["structure"], m)
    b = node["bifurcation"]
    if isinstance(b.v, dict) and b.v.get("type") in ("grazing", "orbit-pitchfork"):
        pitch = b.v.get("type") == "orbit-pitchfork"
        name = b["parameter"].text(("amplitude", "frequency"))
        ends = b["interval"].items(exactly=2)
        plo, phi = decimal(ends[0]), decimal(ends[1])
        if node["model"].v[name] != f"[{ends[0].v}, {ends[1].v}]":
            raise NotConfirmed(f"{node['model'][name].path} = {node['model'].v[name]!r}: not the interval "
                               f"{b['interval'].path} = {b['interval'].v}")
        if not hi(phi) - lo(plo) <= mp.mpf("1e-10") or not lo(plo) < hi(phi):
            raise NotConfirmed(f"{b['interval'].path}: {show(hi(phi) - lo(plo))} wide, not in (0, 1e-10]")
        pairs = (("interval", "interval"), ("parameter", "parameter"), ("impact_contacts", "impact_contacts"))
        if not pitch:
            pairs += (("contact", "grazing_contact"), ("flight", "grazing_flight"), ("symmetric", "symmetric"))
        for key, skey in pairs:
            if not s.has(skey):
                s.fail(f"no '{skey}'")
            if s[skey].v != b[key].v:
                raise NotConfirmed(f"{s[skey].path} = {s[skey].v!r} and {b[key].path} = {b[key].v!r} differ")
        P = iv.mpf([lo(plo), hi(phi)])
        period = bifurcation_summary(node, s, "orbit-pitchfork" if pitch else "grazing", name, P)
        if pitch and not s["symmetric"].boolean():
            raise NotConfirmed(f"{s['symmetric'].path}: false, the pitchfork proven is of a symmetric orbit")
        if pitch:
            return check_orbit_pitchfork(node, m, b, s, P, name)
        return check_grazing(node, m, b, s, P, name, period)
    b.obj(("type", "parameter", "interval", "root", "g_at_ends", "slope", "speed", "window"))
    kind = b["type"].text(("pitchfork", "fold"))
    fold = kind == "fold"
    name = b["parameter"].text(("amplitude", "frequency"))
    ends = b["interval"].items(exactly=2)
    plo, phi = decimal(ends[0]), decimal(ends[1])
    if node["model"].v[name] != f"[{ends[0].v}, {ends[1].v}]":
        raise NotConfirmed(f"{node['model'][name].path} = {node['model'].v[name]!r}: not the interval "
                           f"{b['interval'].path} = {b['interval'].v}")
    if not hi(phi) - lo(plo) <= mp.mpf("1e-10") or not lo(plo) < hi(phi):
        raise NotConfirmed(f"{b['interval'].path}: {show(hi(phi) - lo(plo))} wide, not in (0, 1e-10]")
    b["root"].integer(-1, 1)  # the prover's branch of its own quadratic (information)
    if not b["window"].num() > 0:  # the prover's window at the impacts (information)
        b["window"].fail("a window must be > 0")
    for key in ("interval", "parameter"):
        if s[key].v != b[key].v:
            raise NotConfirmed(f"{s[key].path} = {s[key].v!r} and {b[key].path} = {b[key].v!r} differ")
    if bifurcation_summary(node, s, kind, name, iv.mpf([lo(plo), hi(phi)])) != 1:
        raise NotConfirmed(f"{s['period'].path}: {s['period'].v}, the symmetric orbit has period 1")
    for g_node in (b["g_at_ends"], s["g_at_ends"]):
        for x in g_node.items(exactly=2):
            x.pair()
    if not fold:
        for x in s["half_map_multipliers"].items(exactly=2):
            x.pair()
    c0, e0, r = symmetric_model(node, m)
    frequency = name == "frequency"
    # The branch: the root of (T2) whose speed the certificate claims.
    claimed_speed = b["speed"].pair()
    at_lo = at_hi = over = None
    for root in (1, -1):
        over = pitchfork_at(m, c0, e0, r, iv.mpf([lo(plo), hi(phi)]), frequency, root, fold)
        if over is not None and (fold or inside(over["V"], claimed_speed)):
            at_lo = pitchfork_at(m, c0, e0, r, plo, frequency, root, fold)
            at_hi = pitchfork_at(m, c0, e0, r, phi, frequency, root, fold)
            break
        over = None
    if at_lo is None or at_hi is None or over is None:
        raise NotConfirmed(f"{b['interval'].path}: the symmetric orbit is not defined over the whole interval "
                           "(a discriminant, a speed or a denominator not positive)")
    gl, gh = at_lo["g"], at_hi["g"]
    g_name = "the discriminant of the symmetric orbits' quadratic" if fold else "det(DH + I)"
    if not ((positive(gl) and negative(gh)) or (negative(gl) and positive(gh))):
        raise NotConfirmed(f"{b['interval'].path}: {g_name} does not change sign over the interval "
                           f"({show_iv(gl)} at {ends[0].v}, {show_iv(gh)} at {ends[1].v}): no {kind} there")
    if not excludes_zero(over["slope"]):
        raise NotConfirmed(f"{b['interval'].path}: d/dp of {g_name} = {show_iv(over['slope'])} may vanish: "
                           "uniqueness and transversality not confirmed")
    # The claims contain the checker's enclosures: over the interval, the hull of 16 pieces (an
    # enclosure over the whole interval at once overestimates by its dependency effects).
    cuts = [lo(plo) + (hi(phi) - lo(plo)) * k / 16 for k in range(17)]
    parts = [pitchfork_at(m, c0, e0, r, iv.mpf([cuts[k], cuts[k + 1]]), frequency, root, fold) for k in range(16)]
    if any(q is None for q in parts):
        raise NotConfirmed(f"{b['interval'].path}: the symmetric orbit is not defined over a piece of the interval")

    def hull(key):
        return iv.mpf([min(lo(q[key]) for q in parts), max(hi(q[key]) for q in parts)])

    # For a fold, V is every real root over each piece (both merging orbits): the hull encloses the
    # speed of every orbit that merges, over the whole interval.
    over = dict(over, slope=hull("slope"), V=hull("V"), det=hull("det"))
    claims = ((b["g_at_ends"][0], gl, f"{g_name} at the lower end"),
              (b["g_at_ends"][1], gh, f"{g_name} at the upper end"),
              (b["slope"], over["slope"], f"d/dp of {g_name}"),
              (s["g_at_ends"][0], gl, f"{g_name} at the lower end"),
              (s["g_at_ends"][1], gh, f"{g_name} at the upper end"),
              (s["slope"], over["slope"], f"d/dp of {g_name}"))
    # Every claim contains the checker's enclosure (never a mere overlap): for a fold, the speed
    # claim contains the speeds of both merging orbits over the whole interval.
    speed_what = "the speed of every merging orbit over the interval" if fold else "the speed"
    claims += ((b["speed"], over["V"], speed_what), (s["speed"], over["V"], speed_what))
    if fold and s.has("half_map_multipliers"):  # a claim no fold makes, which nothing here would check
        raise NotConfirmed(f"{s['half_map_multipliers'].path}: a fold's certificate claims no multipliers of the "
                           "half-period map (a pitchfork's does)")
    if not fold:
        # At the point det(DH + I) = 0 (its sign change, confirmed above): −1 is a multiplier of DH
        # there, which the first entry claims (it was not checked: [2, 2] was confirmed).
        claims += ((s["half_map_multipliers"][0], iv.mpf(-1), "the multiplier −1 of DH at the point"),
                   (s["half_map_multipliers"][1], -over["det"], "the other multiplier of DH"))
    for claim, E, what in claims:
        claim_contains(claim, E, what)
    bifurcation_reason(node, kind, over["slope"], name=name, lo=ends[0].v, hi=ends[1].v)
    # The orbit over the whole interval: Δ − y > 0 and y + Δ > 0 on the open flight (time s = Ωt),
    # windows at the impacts where ẏ < 0 (y leaves +Δ downwards and reaches −Δ downwards).
    th, fl, Dv = over["theta"], over["flight"], over["Delta"]
    eps = lo(th) / 64
    for _ in range(16):
        if negative(fl(iv.mpf([0, eps]))[1]) and negative(fl(iv.mpf([lo(th) - eps, hi(th)]))[1]):
            break
        eps /= 2
    else:
        raise NotConfirmed(f"{node.path}: the velocity at the impacts is not confirmed negative")
    for gap, a, z in ((lambda y: Dv - y, eps, hi(th)), (lambda y: y + Dv, mp.mpf(0), lo(th) - eps)):
        stack = [(a, z)]
        pieces = 0
        while stack:
            u, v = stack.pop()
            pieces += 1
            if pieces > 200000:
                raise NotConfirmed(f"{node.path}: a gap not confirmed positive between the impacts")
            if positive(gap(fl(iv.mpf([u, v]))[0])):
                continue
            if v - u < lo(th) * mp.mpf(2) ** -30:
                raise NotConfirmed(f"{node.path}: a gap not confirmed positive near s = {show(u)}")
            c = (u + v) / 2
            stack += [(u, c), (c, v)]
    return 4


# ---- Grazing -----------------------------------------------------------------------------------

def graze_flight(m, f, w, t0, X, V, s):
    """The free flight from (t0, X, V) over s with the amplitude f and the forcing frequency w
    variables too (written again for a grazing): per mode U = P sin ωt + Q cos ωt solving
    Ü + 2σU̇ + ω_i²U = T_A f sin ωt, plus e^{−σs}(a cos ω_d s + b sin ω_d s) matching X, V at t0."""
    L = D.lift
    f, w, t0, s = L(f), L(w), L(t0), L(s)
    t1 = t0 + s
    s0, c0, s1, c1 = dsin(w * t0), dcos(w * t0), dsin(w * t1), dcos(w * t1)
    Xo, Vo = [], []
    for i in range(m.n):
        z = m.zeta[i] if m.zeta is not None else ZERO
        sg, wd = L(z * m.w_i[i]), L(m.w_i[i] * iv.sqrt(1 - z * z))
        wi = L(m.w_i[i])
        det = wi * wi - w * w
        dmp = L(2) * sg * w
        den = det * det + dmp * dmp
        load = f * L(m.TA[i])
        P, Q = load * det / den, -(load * dmp / den)
        U0, Ud0 = P * s0 + Q * c0, w * (P * c0 - Q * s0)
        U1, Ud1 = P * s1 + Q * c1, w * (P * c1 - Q * s1)
        a = L(X[i]) - U0
        b = (L(V[i]) - Ud0 + a * sg) / wd
        e = dexp(-(s * sg))
        cd, sd = dcos(s * wd), dsin(s * wd)
        Xo.append(U1 + e * (a * cd + b * sd))
        Vo.append(Ud1 + e * ((b * wd - a * sg) * cd - (a * wd + b * sg) * sd))
    return Xo, Vo


class Grazing:
    """The orbit of a grazing certificate: unknowns u = (t_j, X_j, V_j) per impact (one impact and
    its mirror image for a symmetric orbit), the parameter p, the tangency time s on flight J."""

    def __init__(self, m, name, hits, symmetric, J, l, period=1):
        self.m, self.freq, self.hits, self.sym, self.J, self.l = m, name == "frequency", hits, symmetric, J, l
        self.q = period  # forcing periods of the orbit (the certificate's period)
        self.count = 1 if symmetric else len(hits)
        self.per = 2 * m.n + 1
        self.N = self.count * self.per

    def fw(self, p):
        return (self.m.f, p) if self.freq else (p, self.m.w)

    def part(self, u, j):
        n, k = self.m.n, j * self.per
        return u[k], u[k + 1:k + 1 + n], u[k + 1 + n:k + 1 + 2 * n]

    def duration(self, u, j, p):
        _, w = self.fw(p)
        if self.sym:
            return D.lift(iv.pi) / D.lift(w)
        k = (j + 1) % self.count
        end = D.lift(self.part(u, k)[0])
        if j == self.count - 1:
            end = end + D.lift(2 * self.q * iv.pi) / D.lift(w)
        return end - D.lift(self.part(u, j)[0])

    def flight(self, u, j, p, s):
        t, X, V = self.part(u, j)
        f, w = self.fw(p)
        return graze_flight(self.m, f, w, t, X, V, s)

    def gap(self, X, l):
        return self.m.contact_of([D.lift(x) for x in X], l) - D(self.m.contacts[l][2])

    def residual(self, u, p, s=None):
        m, out = self.m, []
        for j in range(self.count):
            t, X, V = self.part(u, j)
            Xe, Ve = self.flight(u, j, p, self.duration(u, j, p))
            if self.sym:
                b = 1 - self.hits[0]
                Vp = m.impact(Ve, b)
                out.append(self.gap(X, self.hits[0]))
                out += [D.lift(Xe[i]) + D.lift(X[i]) for i in range(m.n)]
                out += [D.lift(Vp[i]) + D.lift(V[i]) for i in range(m.n)]
            else:
                k = (j + 1) % self.count
                _, Xn, Vn = self.part(u, k)
                Vp = m.impact(Ve, self.hits[k])
                out.append(self.gap(X, self.hits[j]))
                out += [D.lift(Xe[i]) - D.lift(Xn[i]) for i in range(m.n)]
                out += [D.lift(Vp[i]) - D.lift(Vn[i]) for i in range(m.n)]
        if s is not None:
            Xe, Ve = self.flight(u, self.J, p, s)
            out.append(m.contact_of(Ve, self.l) if not isinstance(Ve[0], D) else
                       sum((D(ci) * v for ci, v in zip(m.contacts[self.l][0], Ve)), D(ZERO)))
            out.append(self.gap(Xe, self.l))
        return out

    def gap_at(self, U, P, j, l, S):
        """(γ, γ̇, γ̈) of contact l at s ∈ S on flight j, over the box (U, P)."""
        m = self.m
        Xe, Ve = self.flight(U, j, P, S)
        Xe, Ve = [value(x) for x in Xe], [value(v) for v in Ve]
        t = value(D.lift(self.part(U, j)[0]) + D.lift(S))
        f, w = self.fw(P)
        load = f * iv.sin(w * t)
        z = m.zeta or [ZERO] * m.n
        acc = [m.TA[i] * load - m.w_i[i] ** 2 * Xe[i] - 2 * z[i] * m.w_i[i] * Ve[i] for i in range(m.n)]
        c = m.contacts[l][0]
        dot = lambda Y: sum((ci * y for ci, y in zip(c, Y)), ZERO)  # noqa: E731
        return dot(Xe) - m.contacts[l][2], dot(Ve), dot(acc)


def krawczyk_mp(F_point, J_box, x, X, extra=None):
    """K(X) = x − C F(x) + (I − C J(X))(X − x) [− (C ∂F/∂p)(P − p̃) with extra = (column, P − p̃)],
    C the inverse of J's midpoint (here, at 192 bits): (K, C, an upper bound of ‖I − C J‖∞)."""
    n = len(x)
    A = mp.matrix(n, n)
    for a in range(n):
        for b in range(n):
            A[a, b] = mid(J_box[a][b])
    C = mp.inverse(A)
    K, delta = [], mp.mpf(0)
    for a in range(n):
        v = x[a]
        rowsum = ZERO
        for l in range(n):
            v = v - iv.mpf(C[a, l]) * F_point[l]
            row = (ONE if a == l else ZERO) - sum((iv.mpf(C[a, j]) * J_box[j][l] for j in range(n)), ZERO)
            v = v + row * (X[l] - x[l])
            rowsum = rowsum + iv.mpf(max(abs(lo(row)), abs(hi(row))))  # outward-rounded sum
        if extra is not None:
            col, dP = extra
            v = v - sum((iv.mpf(C[a, j]) * col[j] for j in range(n)), ZERO) * dP
        delta = max(delta, hi(rowsum))
        K.append(v)
    return K, C, delta


def mirrored_model(node, m, hits, where):
    """A symmetric orbit's model: contact 1 is contact 0 mirrored (c_1 = −c_0 and T_1 = −T_0 exactly,
    or two stops on one DOF on opposite sides by the structure), equal stops and restitutions."""
    if len(m.contacts) != 2 or len(hits) != 2 or hits[0] == hits[1] or node["period"].v != 1:
        raise NotConfirmed(f"{where.path}: a symmetric orbit has two impacts on two contacts in one period")
    (c0, T0, e0, r0, _), (c1, T1, e1, r1, _) = m.contacts
    exact = all(lo(x + y) == 0 == hi(x + y) for x, y in zip(c0 + T0, c1 + T1))
    mirrored = False
    if node.has("structure"):
        cs = node["structure"].v["contacts"]
        mirrored = len(cs) == 2 and cs[0]["dof"] == cs[1]["dof"] and cs[0]["partner"] == cs[1]["partner"] == -1 \
            and cs[0]["side"] != cs[1]["side"]
    t = node["model"].v
    if not (exact or mirrored) or t["stop"] != t["more_contacts"][0]["stop"] or \
            t["restitution"] != t["more_contacts"][0]["restitution"]:
        raise NotConfirmed(f"{where.path}: the model is not mirrored (contact 1 is not contact 0 mirrored)")


def bisect(node, pred, a, z, what, depth=40):
    """pred(u, v) on pieces of [a, z], halving the pieces where it fails (up to `depth`)."""
    stack, count = [(a, z, 0)], 0
    while stack:
        u, v, d = stack.pop()
        count += 1
        if count > 200000:
            raise NotConfirmed(f"{node.path}: {what}: not confirmed (too many pieces)")
        if pred(u, v):
            continue
        if d >= depth:
            raise NotConfirmed(f"{node.path}: {what}: not confirmed near s = {show(u)}")
        c = (u + v) / 2
        stack += [(u, c, d + 1), (c, v, d + 1)]


def orbit_gaps(node, G, U, P, window=None):
    """The orbit of G is an orbit for every p ∈ P and u ∈ U: durations, impact velocities, windows at
    the impacts, every gap positive between them (bisection, mean-value form) except contact G.l's
    on flight G.J over `window`."""
    m, hits, sym = G.m, G.hits, G.sym
    k_count = len(m.contacts)
    for j in range(G.count):
        cj = hits[j]
        ck = (1 - cj) if sym else hits[(j + 1) % G.count]
        Sj = value(G.duration(U, j, P))
        after = G.gap_at(U, P, j, cj, iv.mpf(0))[1]
        before = G.gap_at(U, P, j, ck, Sj)[1]
        if not (positive(Sj) and positive(after) and negative(before)):
            raise NotConfirmed(f"{node.path}: flight {j}: duration {show_iv(Sj)}, velocity after {show_iv(after)}, "
                               f"before {show_iv(before)}: not those of an impacting orbit")
        e0 = e1 = lo(Sj) / 16
        for _ in range(30):
            if positive(G.gap_at(U, P, j, cj, iv.mpf([0, e0]))[1]):
                break
            e0 /= 2
        else:
            raise NotConfirmed(f"{node.path}: flight {j}: the velocity after the impact not confirmed positive")
        for _ in range(30):
            if negative(G.gap_at(U, P, j, ck, iv.mpf([lo(Sj) - e1, hi(Sj)]))[1]):
                break
            e1 /= 2
        else:
            raise NotConfirmed(f"{node.path}: flight {j}: the velocity before the impact not confirmed negative")
        for c in range(k_count):
            a, z = (e0 if c == cj else mp.mpf(0)), (lo(Sj) - e1 if c == ck else hi(Sj))
            ranges = [(a, z)]
            if window is not None and j == G.J and c == G.l:
                if not (a < window[0] and window[1] < z):
                    raise NotConfirmed(f"{node.path}: the window meets the impacts' windows")
                ranges = [(a, window[0]), (window[1], z)]
            for u0, v0 in ranges:
                if u0 < v0:
                    bisect(node, lambda u, v, j=j, c=c: positive(_gap_form(G, U, P, j, c, u, v)), u0, v0,
                           f"the gap of contact {c} on flight {j}")


def anti_times(G, a, b, p):
    """M(a, p) b: the antisymmetric block A − Bσ' of the whole orbit's Jacobian (A, B: of flight 0's
    equations in the impact states u_0 and u_1 = σ(u_0) = (t_0 + T/2, −X_0, −V_0), σ' = diag(1, −I, −I))
    applied to b, written again here: ∂(X, V)(t_1)/∂t_0 = −Φ(s)(V_0, Ẍ(t_0)), ∂/∂(X_0, V_0) = Φ(s) per
    mode (Φ = [[h1, h2], [−ω_i² h2, h3]], s = T/2), ∂/∂t_1 = (V, Ẍ)(t_1); the impact's projection on the
    velocity; −I on (X_1, V_1)."""
    m, n, L = G.m, G.m.n, D.lift
    ca = G.hits[0]
    cb = 1 - ca
    f, w = (L(z) for z in G.fw(p))
    t0, X0, V0 = L(a[0]), [L(x) for x in a[1:1 + n]], [L(v) for v in a[1 + n:1 + 2 * n]]
    sT = L(iv.pi) / w
    Xe, Ve = graze_flight(m, f, w, t0, X0, V0, sT)
    l0, l1 = f * dsin(w * t0), f * dsin(w * (t0 + sT))
    bt, bx, bv = L(b[0]), [L(x) for x in b[1:1 + n]], [L(v) for v in b[1 + n:1 + 2 * n]]
    out = [sum((D(c) * x for c, x in zip(m.contacts[ca][0], bx)), D(ZERO))]
    dv = []
    for i in range(n):
        z = m.zeta[i] if m.zeta is not None else ZERO
        sg, wd, w2 = L(z * m.w_i[i]), L(m.w_i[i] * iv.sqrt(1 - z * z)), L(m.w_i[i] ** 2)
        e = dexp(-(sT * sg))
        sd, cd = dsin(wd * sT), dcos(wd * sT)
        h1, h2, h3 = e * (cd + sg / wd * sd), e * sd / wd, e * (cd - sg / wd * sd)
        acc0 = L(m.TA[i]) * l0 - w2 * X0[i] - L(2) * sg * V0[i]
        acc1 = L(m.TA[i]) * l1 - w2 * Xe[i] - L(2) * sg * Ve[i]
        At, Bt = -(h1 * V0[i] + h2 * acc0), Ve[i]
        out.append((At - Bt) * bt + (h1 - L(1)) * bx[i] + h2 * bv[i])
        Dt0, Dt1 = -(h3 * acc0 - w2 * h2 * V0[i]), acc1
        dv.append((Dt0 - Dt1) * bt - w2 * h2 * bx[i] + h3 * bv[i])
    c, T, e_, r, W = m.contacts[cb]
    cdv = sum((D(ci) * d for ci, d in zip(c, dv)), D(ZERO))
    k = cdv * D(-(1 + r) / W)
    for i in range(n):
        out.append(dv[i] + k * D(T[i]) - bv[i])
    return out


def check_orbit_pitchfork(node, m, b, s, P, name):
    """A symmetric orbit's pitchfork (docs/prove.md "Bifurcation points"), recomputed: the parametric
    Krawczyk test on (R_sym, M b + μ e_k, ℓ·b − 1) in (a, b, μ) over the interval, Krawczyk's test on
    (R_sym, M b, ℓ·b − 1) in (a, b, p), dp/dμ = −(J⁻¹)_{p,k} enclosed and nonzero from ‖I − CJ‖∞ < 1,
    the orbit's gaps."""
    b.obj(("type", "parameter", "interval", "impact_contacts", "normal", "row", "midpoint", "box", "slope"))
    hits = [h.integer(0, len(m.contacts) - 1) for h in b["impact_contacts"].items(exactly=2)]
    mirrored_model(node, m, hits, b["impact_contacts"])
    G = Grazing(m, name, hits, True, 0, 0)
    h = G.N
    ell = [x.point() for x in b["normal"].items(exactly=h)]
    k = b["row"].integer(0, h - 1)
    boxes = b["box"].items(exactly=2 * h + 1)
    X = [x.pair() for x in boxes]
    mids = b["midpoint"].items(exactly=2 * h)
    xm = [x.point() for x in mids] + [ZERO]
    for j in range(2 * h + 1):
        if not inside(xm[j], X[j]):
            raise NotConfirmed(f"{boxes[j].path}: the midpoint is not in the box")
    pm = iv.mpf(mid(P))

    def residual(a, bb, mu, p):
        out = G.residual(a, p)
        mb = anti_times(G, a, bb, p)
        mb[k] = mb[k] + D.lift(mu)
        return [D.lift(r) for r in out] + mb + [sum((D(l_) * D.lift(x) for l_, x in zip(ell, bb)), D(ZERO)) - D(ONE)]

    # (1) For every p ∈ P one (a, b, μ) in the box: the parametric test.
    F = [value(r) for r in residual(xm[:h], xm[h:2 * h], xm[2 * h], pm)]
    Vd = [variable(X[j], j) for j in range(2 * h + 1)]
    R = residual(Vd[:h], Vd[h:2 * h], Vd[2 * h], variable(P, 2 * h + 1))
    J = [[r.g.get(c, ZERO) for c in range(2 * h + 1)] for r in R]
    col = [r.g.get(2 * h + 1, ZERO) for r in R]
    K, _, _ = krawczyk_mp(F, J, xm, X, (col, P - pm))
    for j in range(2 * h + 1):
        if not (lo(X[j]) < lo(K[j]) and hi(K[j]) < hi(X[j])):
            raise NotConfirmed(f"{boxes[j].path}: the parametric Krawczyk test fails (K = {show_iv(K[j])}): no unique "
                               "symmetric orbit and antisymmetric vector in the box confirmed over the interval")
    # (2) Exactly one (a, b, p) with μ = 0: the pitchfork.
    xe = xm[:2 * h] + [pm]
    Xe = X[:2 * h] + [P]
    Fe = [value(r) for r in residual(xe[:h], xe[h:2 * h], ZERO, pm)]
    Ve = [variable(Xe[j], j) for j in range(2 * h + 1)]
    Re = residual(Ve[:h], Ve[h:2 * h], ZERO, Ve[2 * h])
    Je = [[r.g.get(c, ZERO) for c in range(2 * h + 1)] for r in Re]
    Ke, Ce, delta = krawczyk_mp(Fe, Je, xe, Xe)
    for j in range(2 * h + 1):
        if not (lo(Xe[j]) < lo(Ke[j]) and hi(Ke[j]) < hi(Xe[j])):
            raise NotConfirmed(f"{b['box'].path}: Krawczyk's test with μ = 0 fails at unknown {j} "
                               f"(K = {show_iv(Ke[j])}): no unique pitchfork in the box confirmed")
    # (3) dp/dμ = −(J⁻¹)_{p, h + k}.
    if not delta < 1:
        raise NotConfirmed(f"{b['box'].path}: ‖I − CJ‖∞ ≤ {show(delta)}, not below 1")
    r_, pr = h + k, 2 * h
    spread = iv.mpf(delta) / (1 - iv.mpf(delta)) * max(abs(Ce[i, r_]) for i in range(2 * h + 1))
    dpdmu = -(iv.mpf(Ce[pr, r_]) + iv.mpf([-hi(spread), hi(spread)]))
    if not excludes_zero(dpdmu):
        raise NotConfirmed(f"{b['slope'].path}: dp/dμ = {show_iv(dpdmu)} may vanish: transversality not confirmed")
    claim_contains(b["slope"], 1 / dpdmu, "dμ/dp")
    claim_contains(s["slope"], 1 / dpdmu, "dμ/dp")
    ends = b["interval"].items(exactly=2)
    bifurcation_reason(node, "orbit-pitchfork", 1 / dpdmu, name=name, lo=ends[0].v, hi=ends[1].v)
    # (4) The symmetric orbit is an orbit over the box.
    orbit_gaps(node, G, X[:h], P)
    return 4


def check_grazing(node, m, b, s, P, name, period=1):
    """A grazing certificate (docs/prove.md "Bifurcation points"), recomputed: Krawczyk on the orbit
    over the interval (for every p one orbit in the box), Krawczyk on the orbit with its tangency
    (exactly one (u, s, p) in the box), dm/dp = 1/(J⁻¹)_{last,last} enclosed and nonzero from
    ‖I − CJ‖∞ < 1 over the box, γ̇ of opposite signs at the ends of the tangency's time box, γ̈ > 0
    on the window, and the orbit an orbit (durations, impact velocities, every gap positive
    outside the window)."""
    b.obj(("type", "parameter", "interval", "contact", "flight", "impact_contacts", "symmetric", "unknowns",
           "midpoint", "box", "window", "slope", "curvature", "grazing_time"))
    k_count = len(m.contacts)
    hits = [h.integer(0, k_count - 1) for h in b["impact_contacts"].items(at_least=1, at_most=MAX_FLIGHTS)]
    sym = b["symmetric"].boolean()
    l = b["contact"].integer(0, k_count - 1)
    if sym:
        mirrored_model(node, m, hits, b['symmetric'])
    G = Grazing(m, name, hits, sym, 0, l, period)
    G.J = b["flight"].integer(0, G.count - 1)
    N = G.N
    boxes = b["box"].items(exactly=N + 1)
    X = [x.pair() for x in boxes]
    mids = b["midpoint"].items(exactly=N + 1)
    xm = [iv.mpf(x.num()) for x in mids]
    names = [f"{v}_{j}" + (f"[{i}]" if v != "t" else "") for j in range(G.count)
             for v, count in (("t", 1), ("X", m.n), ("V", m.n)) for i in range(count)] + ["s"]
    for x, want in zip(b["unknowns"].items(exactly=N + 1), names):
        if x.text() != want:
            raise NotConfirmed(f"{x.path}: '{x.v}', the unknown there is {want}")
    for k in range(N + 1):
        if not inside(xm[k], X[k]):
            raise NotConfirmed(f"{mids[k].path}: the midpoint is not in the box")
    U, S = X[:N], X[N]
    pm = iv.mpf(mid(P))
    # (1) The orbit over P: the parametric Krawczyk test.
    Fp = [value(r) for r in G.residual(xm[:N], pm)]
    Ud = [variable(U[k], k) for k in range(N)]
    Pd = variable(P, N)
    R = G.residual(Ud, Pd)
    J = [[r.g.get(c, ZERO) for c in range(N)] for r in R]
    col = [r.g.get(N, ZERO) for r in R]
    K, _, _ = krawczyk_mp(Fp, J, xm[:N], U, (col, P - pm))
    for k in range(N):
        if not (lo(U[k]) < lo(K[k]) and hi(K[k]) < hi(U[k])):
            raise NotConfirmed(f"{boxes[k].path}: Krawczyk's test on the orbit over the interval fails "
                               f"(K = {show_iv(K[k])}): no unique orbit in the box confirmed")
    # (2) The orbit with its tangency: exactly one (u, s, p) in the box.
    x = xm[:N] + [xm[N], pm]
    Xb = U + [S, P]
    Fe = [value(r) for r in G.residual(x[:N], x[N + 1], x[N])]
    Vd = [variable(Xb[k], k) for k in range(N + 2)]
    Re = G.residual(Vd[:N], Vd[N + 1], Vd[N])
    Je = [[r.g.get(c, ZERO) for c in range(N + 2)] for r in Re]
    Ke, Ce, delta = krawczyk_mp(Fe, Je, x, Xb)
    for k in range(N + 2):
        if not (lo(Xb[k]) < lo(Ke[k]) and hi(Ke[k]) < hi(Xb[k])):
            raise NotConfirmed(f"{b['box'].path}: Krawczyk's test on the orbit with its tangency fails at unknown {k} "
                               f"(K = {show_iv(Ke[k])}): no unique grazing in the box confirmed")
    # (3) dm/dp over P: (J⁻¹)_{last,last} ∈ C_ll ± δ/(1 − δ) max_i |C_il|.
    if not delta < 1:
        raise NotConfirmed(f"{b['box'].path}: ‖I − CJ‖∞ ≤ {show(delta)}, not below 1")
    last = N + 1
    spread = iv.mpf(delta) / (1 - iv.mpf(delta)) * max(abs(Ce[i, last]) for i in range(N + 2))
    inv = iv.mpf(Ce[last, last]) + iv.mpf([-hi(spread), hi(spread)])
    if not excludes_zero(inv):
        raise NotConfirmed(f"{b['slope'].path}: dp/dm = {show_iv(inv)} may vanish: transversality not confirmed")
    slope = 1 / inv
    claim_contains(b["slope"], slope, "dm/dp, the minimum gap's derivative")
    claim_contains(s["slope"], slope, "dm/dp, the minimum gap's derivative")
    # γ̇ < 0 at S's lower end and > 0 at its upper end, for every orbit of the box.
    ga = G.gap_at(U, P, G.J, l, iv.mpf(lo(S)))[1]
    gb = G.gap_at(U, P, G.J, l, iv.mpf(hi(S)))[1]
    if not (negative(ga) and positive(gb)):
        raise NotConfirmed(f"{b['box'].path}: the gap velocity at the ends of the tangency's time box, {show_iv(ga)} "
                           f"and {show_iv(gb)}, not confirmed negative then positive")
    curv = G.gap_at(U, P, G.J, l, S)[2]
    claim_contains(b["curvature"], curv, "the gap's second derivative at the grazing")
    claim_contains(s["curvature"], curv, "the gap's second derivative at the grazing")
    tg = value(D.lift(G.part(U, G.J)[0]) + D.lift(S))
    claim_contains(b["grazing_time"], tg, "the grazing time")
    claim_contains(s["grazing_time"], tg, "the grazing time")
    # The window: γ̈ > 0 on it (convex: one minimum, at s(p) ∈ S).
    wa, wb = (x.num() for x in b["window"].items(exactly=2))
    if not (wa < lo(S) and hi(S) < wb):
        raise NotConfirmed(f"{b['window'].path}: the window does not contain the tangency's time box")

    bisect(node, lambda u, v: positive(G.gap_at(U, P, G.J, l, iv.mpf([u, v]))[2]), wa, wb,
           "the gap's convexity on the window")
    ends = b["interval"].items(exactly=2)
    opens = positive(slope)
    if not (opens or negative(slope)):
        raise NotConfirmed(f"{b['slope'].path}: the sign of dm/dp is not confirmed")
    bifurcation_reason(node, "grazing", slope, name=name, lo=ends[0].v, hi=ends[1].v, flight=G.J, contact=l,
                       below="crosses" if opens else "clears", above="clears" if opens else "crosses",
                       mirror=MIRROR.format(other=1 - l) if sym else "")
    # (4) The orbit is an orbit over the box.
    orbit_gaps(node, G, U, P, (wa, wb))
    return 5


def _gap_form(G, U, P, j, c, u, v):
    """The gap on [u, v] by the mean-value form γ(mid) + γ̇([u, v])([u, v] − mid)."""
    I, cm = iv.mpf([u, v]), iv.mpf((u + v) / 2)
    return G.gap_at(U, P, j, c, cm)[0] + G.gap_at(U, P, j, c, I)[1] * (I - cm)


def check(node):
    """Checks one certificate; returns how many inequalities were recomputed."""
    if not isinstance(node.v, dict):
        node.fail(f"expected a certificate (an object), got {kind_of(node.v)}")
    if node.v.get("format") != FORMAT:
        node.fail(f"format: expected '{FORMAT}'")
    verdict = node["verdict"].text(("proven", "not-proven"))
    if verdict != "proven":
        raise NotConfirmed(f"{node['verdict'].path}: the certificate claims no proof ('{verdict}': "
                           f"{node['reason'].text()[:200] if node.has('reason') else ''})")
    kind = node["kind"].text(("impact", "sticking", "bifurcation"))
    if kind == "bifurcation":
        return check_bifurcation(node)
    # A sticking orbit of several modes carries the unknowns of its Krawczyk test.
    modes = kind == "sticking" and isinstance(node.v.get("unknowns"), list)
    held_set = modes and "segments" in node.v
    if held_set:
        node.obj(CERT_KEYS + HELD_SET_KEYS, ("structure",))
    elif modes:
        node.obj(CERT_KEYS + STICKING_MODES_KEYS, ("structure",))
    else:
        node.obj(CERT_KEYS + (IMPACT_KEYS if kind == "impact" else STICKING_KEYS),
                 (("tail",) if kind == "sticking" else ("impact_contacts", "tangent", "spectral_bound")) + ("structure",))
    node["libraries"].text()  # the interval library's versions (information)
    node["precision_bits"].integer(1, 1 << 20)
    s = node["summary"]
    s.obj(SUMMARY_KEYS, ("stability_note", "requested_period", "modal_data"))
    for key in ("verdict", "reason", "kind", "period"):
        if node[key].v != s[key].v or type(node[key].v) is not type(s[key].v):
            raise NotConfirmed(f"{node[key].path} = {node[key].v!r} and {s[key].path} = {s[key].v!r} differ")
    m = Model(node["model"])
    if node.has("structure"):
        check_structure(node["structure"], m)
    claimed = s["modal_data"].text(("given", "enclosed")) if s.has("modal_data") else "given"
    if claimed != ("enclosed" if node.has("structure") else "given"):
        raise NotConfirmed(f"{s['modal_data'].path if s.has('modal_data') else s.path}: modal data '{claimed}' "
                           f"but the certificate {'carries' if node.has('structure') else 'has no'} structure")
    summary_shape(s, m.n)
    ledger = Ledger(node["inequalities"])
    if kind == "impact":
        truth = check_impact(node, m, ledger)
    elif held_set:
        truth = check_held_set(node, m, ledger)
    elif modes:
        truth = check_sticking_modes(node, m, ledger)
    else:
        truth = check_sticking(node, m, ledger)
    check_summary(node, s, truth, m)
    return ledger.finish()


def check_document(data):
    """The checker on a file's bytes: (exit code, one line)."""
    try:
        if len(data) > MAX_BYTES:
            raise NotACertificate(f"the file: more than {MAX_BYTES >> 20} MiB")
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as e:
            raise NotACertificate(f"the file: not UTF-8 text (byte {e.start})")
        try:
            doc = json.loads(text, object_pairs_hook=unique_keys, parse_constant=reject_constant)
        except RecursionError:
            raise NotACertificate("the file: JSON nested too deeply")
        except ValueError as e:
            raise NotACertificate(f"the file: not JSON ({str(e).splitlines()[0][:200]})")
        root = Node(doc)
        if isinstance(doc, dict) and "certificates" in doc:
            root.obj(("certificates",), ("branch",))
            if root.has("branch"):
                root["branch"].text()
            certs = root["certificates"].items(at_least=1, at_most=MAX_CERTIFICATES)
            count = sum(check(c) for c in certs)
            return 0, f"confirmed: {len(certs)} certificates, every claim checked ({count} inequalities recomputed)"
        count = check(root)
        return 0, f"confirmed: every claim checked ({count} inequalities recomputed)"
    except NotACertificate as e:
        return 2, f"not a certificate: {one_line(e)}"
    except NotConfirmed as e:
        return 1, f"not confirmed: {one_line(e)}"
    except RecursionError:
        return 2, "not a certificate: nested too deeply"
    except MemoryError:
        return 1, "not confirmed: the checker ran out of memory"
    except Exception as e:  # a checker bug: never a traceback, never "confirmed"
        return 1, f"not confirmed: the checker failed ({type(e).__name__}: {one_line(e)})"


def one_line(e):
    return " ".join(str(e).split())[:2000]


def unique_keys(pairs):
    out = {}
    for k, v in pairs:
        if k in out:
            raise NotACertificate(f"the key '{k[:60]}' appears twice in an object")
        out[k] = v
    return out


def reject_constant(name):
    raise NotACertificate(f"the file: '{name}' is not a JSON number (bounds must be finite)")


def main(argv):
    args = [a for a in argv[1:] if a != "--json"]
    as_json = "--json" in argv[1:]
    if len(args) != 1 or args[0].startswith("-") and args[0] != "-":
        print("usage: vibro_check_proof.py CERT.json [--json]", file=sys.stderr)
        return 2
    path = args[0]
    try:
        if os.path.isdir(path):
            raise OSError("a directory")
        with open(path, "rb") as fh:
            data = fh.read(MAX_BYTES + 1)
        code, line = check_document(data)
    except OSError as e:
        code, line = 2, f"not a certificate: {path}: {e.strerror or e}"
    except KeyboardInterrupt:
        print("vibro_check_proof: interrupted; nothing was confirmed", file=sys.stderr)
        return 130
    if as_json:
        verdict = line.split(":", 1)[0]
        print(json.dumps({"verdict": verdict, "reason": line.split(": ", 1)[1] if ": " in line else line}))
    else:
        print(line)
    return code


if __name__ == "__main__":
    sys.setrecursionlimit(10000)
    sys.exit(main(sys.argv))
