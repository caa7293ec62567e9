"""Closed forms of the symmetric two-sided 1-DOF impact oscillator, in mpmath at 50 digits.

    x'' + w1^2 x = a sin(w t),     stops at x = -D (below) and x = +D (above), restitution r at both.

Notation (docs/contacts_reference.md, "Closed forms"): theta = w1 pi / w, U = a / (w1^2 - w^2),
T = 2 pi / w. Independent of vibro's C++ and of reference.py: only mpmath.

* symmetric_orbits(w1, a, D, r, w): the symmetric period-1 orbits with one impact on each stop
  (x(t + T/2) = -x(t)), from the quadratic (T2) in the arrival speed V; 0 <= r < 1 (r = 0: the
  "leave" orbit, valid when the body leaves the stop at once).
* sticking_orbit(w1, a, D, w): r = 0, the symmetric orbit that sticks on each stop: release phase,
  landing time, landing reaction and sticking proportion (T3).
* lower_limit(w1, D, w): the amplitude a at which the landing reaches the next release phase
  (sticking proportion -> 0), (T4), valid only when cot(w1 pi / (2 w)) > 0 (the sign trap).

Running this file checks every formula against a direct propagation of the closed-form flight and
an independent Taylor integration (mpmath.odefun) and prints the results.
"""
import mpmath as mp

mp.mp.dps = 50


class Orbit:
    """One impact per stop: impact at +D at time phi/w with arrival speed V (x' = V before,
    -r V after), free flight of exactly T/2 to -D (arrival x' = -V)."""

    def __init__(self, V, phi, w1, a, D, r, w):
        self.V, self.phi, self.w1, self.a, self.D, self.r, self.w = V, phi, w1, a, D, r, w

    def t_impact(self):
        """Time of the impact on +D in [0, T)."""
        return mp.fmod(self.phi, 2 * mp.pi) / self.w

    def __repr__(self):
        return f"Orbit(V={mp.nstr(self.V, 15)}, phi={mp.nstr(self.phi, 15)})"


def _mp(*xs):
    return [mp.mpf(x) if not isinstance(x, mp.mpf) else x for x in xs]


def flight(x0, v0, t0, w1, a, w, s):
    """Closed-form free flight of x'' + w1^2 x = a sin(w t) from (x0, v0) at t0, after time s:
    returns (x, x')."""
    U = a / (w1**2 - w**2)
    A = x0 - U * mp.sin(w * t0)
    B = v0 - U * w * mp.cos(w * t0)
    x = A * mp.cos(w1 * s) + B / w1 * mp.sin(w1 * s) + U * mp.sin(w * (t0 + s))
    v = -A * w1 * mp.sin(w1 * s) + B * mp.cos(w1 * s) + U * w * mp.cos(w * (t0 + s))
    return x, v


def symmetric_orbits(w1, a, D, r, w):
    """(T1)-(T2): U sin(phi) = D - V (1+r) tan(theta/2)/(2 w1), U cos(phi) = V (1-r)/(2 w),
    => (k1^2 + k2^2) V^2 - 2 D k1 V + D^2 - U^2 = 0. Returns the orbits with V > 0, largest V
    first (admissibility, i.e. no stop reached inside the flight, is checked separately)."""
    w1, a, D, r, w = _mp(w1, a, D, r, w)
    theta = w1 * mp.pi / w
    U = a / (w1**2 - w**2)
    k1 = (1 + r) * mp.tan(theta / 2) / (2 * w1)
    k2 = (1 - r) / (2 * w)
    A2, A1, A0 = k1**2 + k2**2, -2 * D * k1, D**2 - U**2
    disc = A1**2 - 4 * A2 * A0
    if disc < 0:
        return []
    roots = sorted({(-A1 + mp.sqrt(disc)) / (2 * A2), (-A1 - mp.sqrt(disc)) / (2 * A2)}, reverse=True)
    out = []
    for V in roots:
        if V <= 0:
            continue
        phi = mp.atan2((D - k1 * V) / U, k2 * V / U)
        out.append(Orbit(V, phi, w1, a, D, r, w))
    return out


def half_period_map(orb):
    """Propagates the closed-form flight from just after the impact on +D over T/2: returns
    (x, x') on arrival, which must be (-D, -V)."""
    t0 = orb.phi / orb.w
    return flight(orb.D, -orb.r * orb.V, t0, orb.w1, orb.a, orb.w, mp.pi / orb.w)


def full_period_map(orb):
    """Two flights and the impact on -D in between, from just after the impact on +D: the state
    after the impact on +D one period later. Returns (x, x' after that impact, arrival speed)."""
    t0 = orb.phi / orb.w
    x, v = flight(orb.D, -orb.r * orb.V, t0, orb.w1, orb.a, orb.w, mp.pi / orb.w)
    v = -orb.r * v                                     # impact on -D
    x, v = flight(x, v, t0 + mp.pi / orb.w, orb.w1, orb.a, orb.w, mp.pi / orb.w)
    return x, -orb.r * v, v


def flight_clearance(orb, samples=4000):
    """Smallest D - |x(s)| over the interior of the half-period flight (sampled, then each
    sampled minimum refined by mpmath.findroot on x'): > 0 iff the flight reaches no stop before
    T/2 (admissibility)."""
    t0, h = orb.phi / orb.w, mp.pi / orb.w
    f = lambda s: flight(orb.D, -orb.r * orb.V, t0, orb.w1, orb.a, orb.w, s)
    vals = [orb.D - abs(f(h * k / samples)[0]) for k in range(1, samples)]
    best = min(vals)
    for k in range(1, samples - 2):
        if vals[k] <= vals[k - 1] and vals[k] <= vals[k + 1]:   # local minimum: refine on x' = 0
            try:
                s = mp.findroot(lambda s: f(s)[1], h * (k + 1) / samples)
                if 0 < s < h:
                    best = min(best, orb.D - abs(f(s)[0]))
            except (ValueError, ZeroDivisionError):
                pass
    return best


def taylor_half_flight(orb, dps=30):
    """Independent check: integrates x'' = a sin(w t) - w1^2 x with mpmath's Taylor-series ODE
    solver from just after the impact on +D over T/2; returns (x, x') on arrival."""
    with mp.workdps(dps):
        t0 = orb.phi / orb.w
        sol = mp.odefun(lambda t, y: [y[1], orb.a * mp.sin(orb.w * t) - orb.w1**2 * y[0]],
                        t0, [orb.D, -orb.r * orb.V])
        return sol(t0 + mp.pi / orb.w)


def admissible(orb):
    """An orbit of (T2) is a motion iff its flight stays strictly between the stops and, for
    r = 0, the body leaves the stop at once (free acceleration at +D points away from it)."""
    if flight_clearance(orb) <= 0:
        return False
    return orb.r > 0 or orb.a * mp.sin(orb.phi) - orb.w1**2 * orb.D < 0


# ---------------------------------------------------------------------------------------------
# Stability of the symmetric orbit, its fold and its symmetry-breaking pitchfork (T5)
#
# With the symmetry S(x, x') = (-x, -x') and the forcing's sign change over half a period, the
# impact map over one period is G o G, where G maps an impact on +D (phase phi, arrival speed V)
# to the next impact on -D, reflected by S: G(phi, V) = (phi + w s - pi, -x'(s)) with s the flight
# time to -D. The symmetric orbit is a fixed point of G (s = T/2); the Floquet multipliers of the
# period-1 orbit are the squares of DG's eigenvalues, det DG = r^2 (one impact). Hence a complex
# pair of multipliers has modulus r^2, no multiplier reaches -1 (DG would need eigenvalues +-i,
# det 1), and a multiplier reaches +1 in two ways:
#   DG eigenvalue +1: tr DG = 1 + r^2, the fold of the symmetric family (the discriminant of (T2)
#                     vanishes: U^2 (k1^2 + k2^2) = D^2 k2^2);
#   DG eigenvalue -1: tr DG = -(1 + r^2), a pitchfork: the orbit loses its symmetry and two
#                     mirror-image asymmetric orbits branch off.


def half_map_jacobian(orb):
    """DG at the symmetric orbit, in closed form (implicit differentiation of x(s; phi, V) = -D
    at s = T/2 along the flight from (D, -r V) at phase phi)."""
    w1, a, D, r, w, V, phi = orb.w1, orb.a, orb.D, orb.r, orb.w, orb.V, orb.phi
    U = a / (w1**2 - w**2)
    s = mp.pi / w
    c, sn = mp.cos(w1 * s), mp.sin(w1 * s)
    x_phi = -U * mp.cos(phi) * c + U * w * mp.sin(phi) / w1 * sn + U * mp.cos(phi + w * s)
    x_V = -r / w1 * sn
    v_phi = U * w1 * mp.cos(phi) * sn + U * w * mp.sin(phi) * c - U * w * mp.sin(phi + w * s)
    v_V = -r * c
    v_end, acc_end = -V, w1**2 * D - a * mp.sin(phi)
    s_phi, s_V = -x_phi / v_end, -x_V / v_end
    return mp.matrix([[1 + w * s_phi, w * s_V],
                      [-(v_phi + acc_end * s_phi), -(v_V + acc_end * s_V)]])


def half_map(orb, phi, V):
    """G(phi, V) by propagation of the closed-form flight (for a finite-difference check of DG)."""
    w1, a, D, r, w = orb.w1, orb.a, orb.D, orb.r, orb.w
    f = lambda s: flight(D, -r * V, phi / w, w1, a, w, s)
    s = mp.findroot(lambda s: f(s)[0] + D, mp.pi / w)
    return phi + w * s - mp.pi, -f(s)[1]


def floquet_multipliers(orb):
    """The multipliers of the period-1 orbit: the squares of DG's eigenvalues."""
    return [e**2 for e in mp.eig(half_map_jacobian(orb))[0]]


def pitchfork_amplitude(w1, D, r, w, lo, hi):
    """The forcing amplitude a in [lo, hi] at which the stable symmetric orbit (largest V) loses
    its symmetry: tr DG = -(1 + r^2). The sign of tr DG + 1 + r^2 must change in [lo, hi]."""
    w1, D, r, w = _mp(w1, D, r, w)

    def g(a):
        orb = symmetric_orbits(w1, a, D, r, w)[0]
        J = half_map_jacobian(orb)
        return J[0, 0] + J[1, 1] + 1 + r**2

    return mp.findroot(g, (mp.mpf(lo), mp.mpf(hi)), solver="anderson")


def fold_frequency(w1, a, D, r, lo, hi):
    """The forcing frequency w in [lo, hi] at which the two symmetric orbits of (T2) meet: the
    discriminant U^2 (k1^2 + k2^2) - D^2 k2^2 vanishes."""
    w1, a, D, r = _mp(w1, a, D, r)

    def disc(w):
        U = a / (w1**2 - w**2)
        k1 = (1 + r) * mp.tan(w1 * mp.pi / w / 2) / (2 * w1)
        k2 = (1 - r) / (2 * w)
        return U**2 * (k1**2 + k2**2) - D**2 * k2**2

    return mp.findroot(disc, (mp.mpf(lo), mp.mpf(hi)), solver="anderson")


# ---------------------------------------------------------------------------------------------
# One-sided orbits and grazing of the other stop (T6)
#
# An orbit that hits only the upper stop +D, once every q periods: impact at phase phi with arrival
# speed V (x' = V before, -r V after), a free flight of q T back to +D arriving with x' = V. Its
# lowest point min x over the flight does not depend on where the lower stop is, as long as the
# flight does not reach it: the lower stop at -D2 is grazed exactly when -D2 = min x.


def one_sided_orbit(w1, a, D, r, w, q, phi0, V0):
    """The orbit of period q with one impact on +D, by mpmath.findroot on (phi, V) from the guess
    (phi0, V0): flight(D, -r V) over q T ends at (D, V)."""
    w1, a, D, r, w = _mp(w1, a, D, r, w)
    span = 2 * mp.pi * q / w

    def residual(phi, V):
        x, v = flight(D, -r * V, phi / w, w1, a, w, span)
        return [x - D, v - V]

    phi, V = mp.findroot(residual, (mp.mpf(phi0), mp.mpf(V0)))
    return Orbit(V, phi, w1, a, D, r, w), span


def flight_minimum(orb, span, samples=4000):
    """The lowest point of the flight from just after the impact on +D over `span` (sampled, each
    sampled minimum refined on x' = 0): (min x, its time after the impact)."""
    t0 = orb.phi / orb.w
    f = lambda s: flight(orb.D, -orb.r * orb.V, t0, orb.w1, orb.a, orb.w, s)
    xs = [f(span * k / samples)[0] for k in range(samples + 1)]
    best = (min(xs), None)
    for k in range(1, samples):
        if xs[k] <= xs[k - 1] and xs[k] <= xs[k + 1]:
            s = mp.findroot(lambda s: f(s)[1], span * k / samples)
            if 0 < s < span and f(s)[0] <= best[0]:
                best = (f(s)[0], s)
    return best


# ---------------------------------------------------------------------------------------------
# r = 0 with sticking (T3) and the lower limit (T4)


class StickingOrbit:
    def __init__(self, phi_r, s_l, lam_l, SP, v_l):
        self.phi_r, self.s_l, self.lam_l, self.SP, self.v_l = phi_r, s_l, lam_l, SP, v_l

    def __repr__(self):
        return (f"StickingOrbit(phi_r={mp.nstr(self.phi_r, 15)}, s_l={mp.nstr(self.s_l, 15)}, "
                f"lambda_l={mp.nstr(self.lam_l, 15)}, SP={mp.nstr(self.SP, 15)})")


def release_phase(w1, a, D):
    """Stuck at +D the reaction (force of the stop on the body, pushing down) is
    lambda(t) = a sin(w t) - w1^2 D; release where it crosses 0 downwards:
    phi_r = pi - asin(w1^2 D / a) (needs a > w1^2 D)."""
    w1, a, D = _mp(w1, a, D)
    if a <= w1**2 * D:
        raise ValueError("a <= w1^2 D: the body never leaves the stop")
    return mp.pi - mp.asin(w1**2 * D / a)


def landing_from_release(w1, a, D, w, smax=None):
    """(T3): flight from rest at +D released at phase phi_r; first root s_l > 0 of x(s) = -D,
    located by a sampled sign change refined by bisection-safeguarded findroot. Returns (s_l, x'(s_l))
    or None if there is none before smax (default 2T)."""
    w1, a, D, w = _mp(w1, a, D, w)
    phi_r = release_phase(w1, a, D)
    t0 = phi_r / w
    smax = smax if smax is not None else 4 * mp.pi / w
    g = lambda s: flight(D, 0, t0, w1, a, w, s)[0] + D      # gap to the lower stop
    n = 4000
    prev = g(smax / n)
    for k in range(2, n + 1):
        s = smax * k / n
        cur = g(s)
        if cur <= 0:
            lo, hi = smax * (k - 1) / n, s
            sl = mp.findroot(g, (lo, hi), solver="anderson")
            if not (lo <= sl <= hi):
                sl = mp.findroot(g, (lo, hi), solver="bisect")
            return sl, flight(D, 0, t0, w1, a, w, sl)[1]
        prev = cur
    return None


def sticking_orbit(w1, a, D, w):
    """r = 0: symmetric orbit sticking on each stop. Landing reaction at -D:
    lambda_l = -w1^2 D - a sin(phi_r + w s_l) (> 0: it sticks); symmetric period-1 iff s_l < T/2;
    sticking proportion SP = 1 - w s_l / pi."""
    w1, a, D, w = _mp(w1, a, D, w)
    phi_r = release_phase(w1, a, D)
    land = landing_from_release(w1, a, D, w)
    if land is None:
        return None
    s_l, v_l = land
    lam_l = -w1**2 * D - a * mp.sin(phi_r + w * s_l)
    return StickingOrbit(phi_r, s_l, lam_l, 1 - w * s_l / mp.pi, v_l)


def lower_limit(w1, D, w):
    """(T4): sqrt(a^2 - w1^4 D^2) = w w1 D cot(w1 pi / (2 w)): the amplitude at which the flight
    from the release lands exactly at the next release phase (s_l = T/2, SP -> 0). Valid only if
    cot(w1 pi/(2 w)) > 0: otherwise the squared equation has a spurious root (returned with
    valid=False so that the trap can be shown)."""
    w1, D, w = _mp(w1, D, w)
    c = mp.cot(w1 * mp.pi / (2 * w))
    a = mp.sqrt((w * w1 * D * c)**2 + w1**4 * D**2)
    return a, c > 0


# ---------------------------------------------------------------------------------------------


def _check():
    ok = True

    def report(name, err, tol):
        nonlocal ok
        good = err <= tol
        ok = ok and good
        print(f"  {'ok ' if good else 'BAD'} {name}: {mp.nstr(err, 3)} (tolerance {mp.nstr(tol, 3)})")

    print("symmetric period-1 orbits, one impact per stop")
    expected = {(1, 1, 1, 0.8, 2.5): [mp.mpf("1.79902274247141"), mp.mpf("1.24820079806749")]}
    for params in [(1, 1, 1, 0.8, 2.5), (1, 2, 1, 0.8, 3), (1.3, 1.5, 0.5, 0.6, 2),
                   (1, 0.6, 1, 0.8, 0.9), (1, 4, 1, 0, 2.5), (1, 8, 1, 0, 4)]:
        orbs = symmetric_orbits(*params)
        print(params, orbs)
        for i, o in enumerate(orbs):
            if params in expected:
                report(f"V[{i}] against the published 15 digits", abs(o.V - expected[params][i]), mp.mpf("1e-14"))
            x, v = half_period_map(o)
            report("closed-form flight arrives at -D", abs(x + o.D), mp.mpf("1e-45"))
            report("... with x' = -V", abs(v + o.V), mp.mpf("1e-45"))
            x, v_after, v_arr = full_period_map(o)
            report("one period returns to itself (x, x'+)", abs(x - o.D) + abs(v_after + o.r * o.V), mp.mpf("1e-44"))
            xt, vt = taylor_half_flight(o)
            report("Taylor integration (odefun) agrees", abs(xt + o.D) + abs(vt + o.V), mp.mpf("1e-25"))
            print(f"    clearance inside the flight: {mp.nstr(flight_clearance(o), 5)}")
            if o.r == 0:
                # leave orbit: at +D the free acceleration must point away from the stop
                acc = o.a * mp.sin(o.phi) - o.w1**2 * o.D
                print(f"    r = 0: free acceleration at +D = {mp.nstr(acc, 8)} (< 0: leaves at once)")

    print("r = 0 sticking orbits")
    for params in [(1, 10, 1, 1.4), (1, 3, 1, 2.5), (1, 5, 1, 0.8)]:
        so = sticking_orbit(*params)
        print(params, so)
    print("lower limit (T4)")
    a_lim, valid = lower_limit(1, 1, 1.4)
    report("a_lim(w = 1.4) against the published value", abs(a_lim - mp.mpf("1.20604795195716")), mp.mpf("1e-14"))
    for sgn in (-1, 1):
        so = sticking_orbit(1, a_lim * (1 + sgn * mp.mpf("1e-6")), 1, 1.4)
        print(f"  a = a_lim (1 {sgn:+d}e-6): SP = {mp.nstr(so.SP, 6)}")
    so = sticking_orbit(1, a_lim, 1, 1.4)
    report("at a_lim the landing is at T/2", abs(so.s_l - mp.pi / mp.mpf(1.4)), mp.mpf("1e-40"))
    for w in (0.8, 0.6):
        a_sp, valid = lower_limit(1, 1, w)
        so = sticking_orbit(1, a_sp, 1, w)
        print(f"  w = {w}: cot < 0, T4 returns a = {mp.nstr(a_sp, 10)} (valid={valid}); "
              f"there s_l - T/2 = {mp.nstr(so.s_l - mp.pi / w, 6) if so else 'no landing'}")
    print("all checks passed" if ok else "SOME CHECKS FAILED")
    return ok


if __name__ == "__main__":
    raise SystemExit(0 if _check() else 1)
