// The symmetry-breaking pitchfork of the symmetric two-sided one-DOF oscillator, proven
// (docs/prove.md "Bifurcation points").
//
// The model (modal coordinate y = c_0 X): ÿ + Ω² y = F sin ωt, F = c_0 T_A f, stops at y = ±Δ
// (Δ = −e_0; contact 1 is contact 0 mirrored: c_1 = −c_0, e_1 = e_0, r_1 = r_0), no damping. The
// symmetric orbit lands on +Δ at t_0 with speed v, leaves with −r v, and lands on −Δ at t_0 + τ,
// τ = π/ω, with speed v: with U(t) = K sin ωt, K = F/(Ω² − ω²), U_0 = U(t_0), U_1 = U'(t_0), the
// free part y − U satisfies (c = cos Ωτ, s = sin Ωτ)
//   −(1 + c) U_0 − (s/Ω) U_1 = −Δ(1 + c) + r v s/Ω,      Ω s U_0 − (1 + c) U_1 = −v + r v c + Δ Ω s,
// linear in (U_0, U_1) for each v: U_0 = p_0 + p_1 v, U_1 = q_0 + q_1 v; and (U_0/K)² + (U_1/(Kω))² = 1
// is a quadratic A v² + B v + C = 0 whose root (sign σ of its square root) is the branch.
//
// The half-period map H: (t, v) at +Δ ↦ (t' − τ, v') at −Δ mirrored (the full period's map is H∘H);
// DH by the implicit function theorem on x(t') = −Δ. At the pitchfork H has the multiplier −1
// (the period map the multiplier +1, with an antisymmetric eigenvector), so the function proven to
// cross zero is g(p) = det(DH + I) along the branch, p the amplitude or the forcing frequency:
// exactly one zero in [p_lo, p_hi] when g(p_lo), g(p_hi) have opposite signs and g' (forward
// derivatives in interval arithmetic over the whole interval) excludes 0; the same g' ≠ 0 is the
// transversality of the crossing. The orbit is an orbit over the whole interval: the quadratic's
// discriminant and v are positive, and both gaps are positive between the impacts (certified
// positivity, with windows at the impacts where the velocity has its sign).
//
// The fold of the symmetric orbit (ProveSymmetricFold, at the end of this file) is the zero of the
// quadratic's discriminant, where its two roots merge.
#include <cmath>
#include <functional>
#include <optional>

#include <fmt/format.h>

#include "proof/bifurcation_proof.hpp"

namespace vibro::proof {
namespace {

// An interval and its derivative with respect to the parameter (forward mode).
struct D {
  Interval v, d;
};
D K(const Interval& x) { return {x, Interval(0.0)}; }
D operator+(const D& a, const D& b) { return {a.v + b.v, a.d + b.d}; }
D operator-(const D& a, const D& b) { return {a.v - b.v, a.d - b.d}; }
D operator-(const D& a) { return {-a.v, -a.d}; }
D operator*(const D& a, const D& b) { return {a.v * b.v, a.d * b.v + a.v * b.d}; }
D operator/(const D& a, const D& b) {
  const Interval q = a.v / b.v;
  return {q, (a.d - q * b.d) / b.v};
}
D Sin(const D& a) { return {Sin(a.v), Cos(a.v) * a.d}; }
D Cos(const D& a) { return {Cos(a.v), -(Sin(a.v) * a.d)}; }
D Sqrt(const D& a) {
  const Interval s = Sqrt(a.v);
  return {s, a.d / (Interval(2.0) * s)};
}

// The symmetric orbit and g = det(DH + I) at the parameter `p` (an interval), with derivatives.
struct Branch {
  bool defined = false;  // Ω² − ω², the 2 × 2 determinant, A and the discriminant are nonzero/positive
  bool quadratic = false;  // the quadratic is set up (A > 0): disc, A, B, p0, p1, q0, q1 hold
  D disc, v, U0, U1, g, detDH, K, tau, omega, Omega, Delta, r;
  D A, B, p0, p1, q0, q1;
};

Branch Evaluate(const IntervalModel& m, bool frequency, const Interval& p, int root) {
  Branch b;
  const D one = K(Interval(1.0)), two = K(Interval(2.0));
  const D a = frequency ? K(m.amplitude) : D{p, Interval(1.0)};
  const D w = frequency ? D{p, Interval(1.0)} : K(m.frequency);
  const D W = K(m.omega[0]), c0 = K(m.shape[0]), Delta = K(-m.stop), r = K(m.restitution);
  const D F = c0 * K(m.forcing[0]) * a;
  const D den = W * W - w * w;
  if (den.v.Contains(0.0)) return b;
  const D Kamp = F / den, tau = K(Interval::Pi()) / w;
  const D c = Cos(W * tau), s = Sin(W * tau), cp = one + c;
  const D det2 = cp * cp + s * s;  // of [[−(1+c), −s/Ω], [Ω s, −(1+c)]]
  if (!det2.v.Positive()) return b;
  // (U_0, U_1) from the two equations: Cramer on [[a11, a12], [a21, a22]].
  const D a11 = -cp, a12 = -(s / W), a21 = W * s, a22 = -cp;
  const auto solve = [&](const D& r1, const D& r2, D& x, D& y) {
    x = (r1 * a22 - a12 * r2) / det2;
    y = (a11 * r2 - a21 * r1) / det2;
  };
  D p0, q0, p1, q1;
  solve(-(Delta * cp), Delta * W * s, p0, q0);
  solve(r * s / W, r * c - one, p1, q1);
  const D A = p1 * p1 + (q1 / w) * (q1 / w);
  const D B = two * (p0 * p1 + q0 * q1 / (w * w));
  const D C = p0 * p0 + (q0 / w) * (q0 / w) - Kamp * Kamp;
  if (!A.v.Positive()) return b;
  b.disc = B * B - K(Interval(4.0)) * A * C;
  b.quadratic = true;
  b.A = A;
  b.B = B;
  b.p0 = p0;
  b.p1 = p1;
  b.q0 = q0;
  b.q1 = q1;
  b.tau = tau;
  b.omega = w;
  b.Omega = W;
  b.Delta = Delta;
  b.r = r;
  if (!b.disc.v.Positive()) return b;
  const D sq = Sqrt(b.disc);
  b.v = (-B + (root > 0 ? sq : -sq)) / (two * A);
  b.U0 = p0 + p1 * b.v;
  b.U1 = q0 + q1 * b.v;
  // DH at the orbit: y0, ẏ0 the free part just after the impact at +Δ, h = τ the flight.
  const D U2 = -(w * w * b.U0);
  const D y0 = Delta - b.U0, yd0 = -(r * b.v) - b.U1;
  const D ch = c, sh = s;
  const D dy0t = -b.U1, dyd0t = -U2;
  const D dyt = dy0t * ch + dyd0t * sh / W + (y0 * W * sh - yd0 * ch);
  const D dyv = -(r * sh / W);
  const D dydt = dy0t * (-(W * sh)) + dyd0t * ch + (y0 * W * W * ch + yd0 * W * sh);
  const D dydv = -(r * ch);
  const D arrival = -b.v;                       // ẋ(t'⁻): the speed v towards −Δ
  const D yt = -Delta + b.U0;                   // the free part at t' (U(t') = −U_0)
  const D xdd = w * w * b.U0 - W * W * yt;      // ẍ(t'⁻) = Ü(t') − Ω²(y − U)(t')
  const D tt = -(dyt / arrival), tv = -(dyv / arrival);
  const D vt = -(dydt + xdd * tt), vv = -(dydv + xdd * tv);
  b.g = (one + tt) * (one + vv) - tv * vt;
  b.detDH = tt * vv - tv * vt;
  b.K = Kamp;
  b.tau = tau;
  b.omega = w;
  b.Omega = W;
  b.Delta = Delta;
  b.r = r;
  b.defined = b.v.v.Positive();
  return b;
}

// The displacement and velocity of the flight from +Δ at time s after the impact (parameter over
// the interval of the branch `b`): y(s) = U_0 cos ωs + (U_1/ω) sin ωs + y0 cos Ωs + (ẏ0/Ω) sin Ωs.
struct Flight {
  Interval y, yd;
};
Flight FlightAt(const Branch& b, const Interval& s) {
  const Interval& w = b.omega.v;
  const Interval& W = b.Omega.v;
  const Interval y0 = b.Delta.v - b.U0.v, yd0 = -(b.r.v * b.v.v) - b.U1.v;
  const Interval sw = Sin(w * s), cw = Cos(w * s), sW = Sin(W * s), cW = Cos(W * s);
  return {b.U0.v * cw + b.U1.v / w * sw + y0 * cW + yd0 / W * sW,
          -(b.U0.v * w * sw) + b.U1.v * cw - y0 * W * sW + yd0 * cW};
}

// Both gaps positive between the impacts, for every parameter of the branch's interval: the
// velocity negative in a window just after and just before the impacts (its width returned in
// eps), then each gap proven positive over the rest of the flight. Empty when proven, else why not.
std::string GapsPositive(const Branch& bp, const Budget& budget, double& eps) {
  const Interval tau = bp.tau.v;
  eps = tau.lo() / 64;
  bool windows = false;
  for (int k = 0; k < 12 && !windows; ++k, eps /= 2) {
    const auto start = FlightAt(bp, Interval::Hull(0.0, eps));
    const auto end = FlightAt(bp, Interval::Hull(tau.lo() - eps, tau.hi()));
    windows = start.yd.Negative() && end.yd.Negative();
    if (windows) break;
  }
  if (!windows) return "the velocity just after and just before the impacts is not proven negative";
  const auto upper = ProvePositive(
      eps, tau.hi(), tau.lo() / 32, 30, budget, [&](double s) { return bp.Delta.v - FlightAt(bp, Interval(s)).y; },
      [&](const Interval& s) { return -FlightAt(bp, s).yd; });
  const auto lower = ProvePositive(
      0.0, tau.lo() - eps, tau.lo() / 32, 30, budget,
      [&](double s) { return FlightAt(bp, Interval(s)).y + bp.Delta.v; },
      [&](const Interval& s) { return FlightAt(bp, s).yd; });
  if (!upper.proven || !lower.proven)
    return "a gap is not proven positive between the impacts: " + (upper.proven ? lower.reason : upper.reason);
  return "";
}

std::string Dec(double x) { return fmt::format("{}", x); }

// The point's parameter by Newton (in the midpoints) on the scalar whose zero it is, from `located`,
// kept within `bracket` (the uncertainty of the location that `continue` reports) of it; `located`
// itself when the bracket is 0 or Newton leaves it.
double Refine(const std::function<std::optional<D>(double)>& f, double located, double bracket) {
  if (!(bracket > 0)) return located;
  double p = located;
  for (int it = 0; it < 40; ++it) {
    const auto y = f(p);
    if (!y || !y->v.finite() || !y->d.finite()) return located;
    const double step = y->v.mid() / y->d.mid();
    if (!std::isfinite(step)) return located;
    p -= step;
    if (!(std::abs(p - located) <= bracket + 1e-10 * (1 + std::abs(located)))) return located;
    if (std::abs(step) <= 1e-16 * (1 + std::abs(p))) break;
  }
  return p;
}

}  // namespace

bool SymmetricTwoSided(const IntervalModel& m, bool mirrored, std::string& why) {
  if (m.n != 1) why = fmt::format("the model has {} modes (the pitchfork is proven for one mode)", m.n);
  else if (m.damped()) why = "the model is damped (the pitchfork is proven for an undamped model)";
  else if (m.contact_count() != 2) why = fmt::format("the model has {} contact(s), not two", m.contact_count());
  else {
    const auto& k = m.contacts[1];
    const Interval c = m.shape[0] + k.shape[0];
    if (!(c.lo() == 0 && c.hi() == 0) && !(c.Contains(0.0) && mirrored))
      why = "contact 1 is not contact 0 mirrored (c_1 = −c_0)";
    else if (k.stop_text != m.stop_text) why = "the two stops are not symmetric (e_1 ≠ e_0)";
    else if (k.restitution_text != m.restitution_text) why = "the two restitutions differ";
    else if (!(-m.stop).Positive()) why = "the clearance is not positive (−e_0 ≤ 0)";
  }
  return why.empty();
}

Outcome ProvePitchfork(const IntervalModel& model, bool mirrored, bool frequency, double located, double bracket,
                       const Budget& budget, std::string& interval_text) {
  Outcome out;
  const char* name = frequency ? "frequency" : "amplitude";
  std::string why;
  if (!SymmetricTwoSided(model, mirrored, why)) {
    out.reason = "the pitchfork is proven for the symmetric two-sided one-DOF oscillator only: " + why;
    return out;
  }
  // The branch of the quadratic: the root whose g is nearest 0 at the located value.
  int root = 0;
  double best = INFINITY;
  for (const int sg : {1, -1}) {
    const auto b = Evaluate(model, frequency, Interval(located), sg);
    if (b.defined && std::abs(b.g.v.mid()) < best) {
      best = std::abs(b.g.v.mid());
      root = sg;
    }
  }
  if (root == 0) {
    out.reason = fmt::format("no symmetric orbit at {} = {}: nothing to prove", name, Dec(located));
    return out;
  }
  // Intervals around the located value (refined within its bracket), widened while ≤ 1e-10 wide.
  const double center = Refine(
      [&](double p) -> std::optional<D> {
        const auto b = Evaluate(model, frequency, Interval(p), root);
        return b.defined ? std::optional<D>(b.g) : std::nullopt;
      },
      located, bracket);
  std::string last;
  for (double half = 1e-12 * (1 + std::abs(center)); 2 * half <= 1e-10 && !budget.passed(); half *= 4) {
    const std::string lo = Dec(center - half), hi = Dec(center + half);
    const Interval plo = Interval::Decimal(lo), phi = Interval::Decimal(hi);
    const Interval P = Union(plo, phi);
    const auto bl = Evaluate(model, frequency, plo, root), bh = Evaluate(model, frequency, phi, root);
    const auto bp = Evaluate(model, frequency, P, root);
    if (!bl.defined || !bh.defined || !bp.defined) {
      last = fmt::format("the symmetric orbit is not defined over {} in [{}, {}] (a discriminant, a speed or a "
                         "denominator is not proven positive)", name, lo, hi);
      continue;
    }
    const bool opposite = (bl.g.v.Positive() && bh.g.v.Negative()) || (bl.g.v.Negative() && bh.g.v.Positive());
    if (!opposite) {
      last = fmt::format("det(DH + I) has no proven sign change over {} in [{}, {}] (enclosures {} and {}): no "
                         "pitchfork is proven there", name, lo, hi, bl.g.v.ToString(), bh.g.v.ToString());
      continue;
    }
    if (bp.g.d.Contains(0.0)) {
      last = fmt::format("d det(DH + I)/d{} over [{}, {}] is {}: it is not proven nonzero", name, lo, hi,
                         bp.g.d.ToString());
      continue;
    }
    // Both gaps positive between the impacts, for every parameter of the interval.
    double eps = 0;
    if (auto gaps = GapsPositive(bp, budget, eps); !gaps.empty()) {
      last = std::move(gaps);
      continue;
    }
    interval_text = "[" + lo + ", " + hi + "]";
    out.proven = true;
    out.reason = fmt::format(
        "exactly one {} in [{}, {}] at which the symmetric orbit's half-period map has the multiplier −1 (its "
        "period map the multiplier +1 with an antisymmetric eigenvector: the symmetry-breaking pitchfork); "
        "det(DH + I) changes sign there and its derivative along the branch, {}, is nonzero over the whole "
        "interval: the crossing is transversal",
        name, lo, hi, bp.g.d.ToString());
    const Interval other = -bp.detDH.v;  // the other multiplier of DH at the point: det DH / (−1)
    out.summary = {{"bifurcation", "pitchfork"},
                   {"parameter", name},
                   {"located", located},
                   {"center", center},
                   {"interval", Json::array({lo, hi})},
                   {"width", phi.hi() - plo.lo()},
                   {"box_width", phi.hi() - plo.lo()},
                   {"g_at_ends", Json::array({Pair(bl.g.v), Pair(bh.g.v)})},
                   {"slope", Pair(bp.g.d)},
                   {"speed", Pair(bp.v.v)},
                   {"half_map_multipliers", Json::array({Json::array({-1, -1}), Pair(other)})},
                   {"period", 1}};
    out.certificate = {{"bifurcation",
                        {{"type", "pitchfork"},
                         {"parameter", name},
                         {"interval", Json::array({lo, hi})},
                         {"root", root},
                         {"g_at_ends", Json::array({Pair(bl.g.v), Pair(bh.g.v)})},
                         {"slope", Pair(bp.g.d)},
                         {"speed", Pair(bp.v.v)},
                         {"window", eps}}}};
    return out;
  }
  out.reason = last.empty() ? "the time limit was reached" : last;
  return out;
}


// The fold of the symmetric orbit: the two roots of the quadratic merge (the stable and the unstable
// symmetric orbits meet; H has the multiplier +1 there). Its parameters are the zeros of the
// discriminant disc(p): exactly one in [p_lo, p_hi] when disc changes sign between the ends and
// disc' excludes 0 over the interval; disc' = −4A ∂Q/∂p at the double root, so disc' ≠ 0 is the
// fold's transversality (the branch turns back with nonzero curvature). The orbits exist over the
// interval: for every real root v (in −B/2A ± √max(disc, 0)/2A), v > 0 and both gaps are positive.
Outcome ProveSymmetricFold(const IntervalModel& model, bool mirrored, bool frequency, double located,
                           double bracket, const Budget& budget, std::string& interval_text) {
  Outcome out;
  const char* name = frequency ? "frequency" : "amplitude";
  std::string why;
  if (!SymmetricTwoSided(model, mirrored, why)) {
    out.reason = "the fold is proven for the symmetric two-sided one-DOF oscillator only: " + why;
    return out;
  }
  const double center = Refine(
      [&](double p) -> std::optional<D> {
        const auto b = Evaluate(model, frequency, Interval(p), 1);
        return b.quadratic ? std::optional<D>(b.disc) : std::nullopt;
      },
      located, bracket);
  std::string last;
  for (double half = 1e-12 * (1 + std::abs(center)); 2 * half <= 1e-10 && !budget.passed(); half *= 4) {
    const std::string lo = Dec(center - half), hi = Dec(center + half);
    const Interval plo = Interval::Decimal(lo), phi = Interval::Decimal(hi);
    const Interval P = Union(plo, phi);
    const auto bl = Evaluate(model, frequency, plo, 1), bh = Evaluate(model, frequency, phi, 1);
    auto bp = Evaluate(model, frequency, P, 1);
    if (!bl.quadratic || !bh.quadratic || !bp.quadratic) {
      last = fmt::format("the symmetric orbit's quadratic is not defined over {} in [{}, {}]", name, lo, hi);
      continue;
    }
    const bool opposite =
        (bl.disc.v.Positive() && bh.disc.v.Negative()) || (bl.disc.v.Negative() && bh.disc.v.Positive());
    if (!opposite) {
      last = fmt::format("the discriminant has no proven sign change over {} in [{}, {}] (enclosures {} and {}): no "
                         "fold is proven there", name, lo, hi, bl.disc.v.ToString(), bh.disc.v.ToString());
      continue;
    }
    if (bp.disc.d.Contains(0.0)) {
      last = fmt::format("d disc/d{} over [{}, {}] is {}: it is not proven nonzero", name, lo, hi, bp.disc.d.ToString());
      continue;
    }
    // Every real root over the interval: v ∈ −B/2A ± √max(disc, 0)/2A.
    const Interval two_a = Interval(2.0) * bp.A.v;
    const double top = std::max(bp.disc.v.hi(), 0.0);
    const Interval spread = Sqrt(Interval::Hull(0.0, top)) / two_a;
    const Interval v = -bp.B.v / two_a + Interval::Hull(-1.0, 1.0) * spread;
    if (!v.Positive()) {
      last = "the speed of the merging orbits is not proven positive";
      continue;
    }
    bp.v.v = v;
    bp.U0.v = bp.p0.v + bp.p1.v * v;
    bp.U1.v = bp.q0.v + bp.q1.v * v;
    double eps = 0;
    if (auto gaps = GapsPositive(bp, budget, eps); !gaps.empty()) {
      last = std::move(gaps);
      continue;
    }
    // The claimed speed: of both merging orbits over the whole interval (every real root of the
    // quadratic), widened by 1e-12 of itself so that it contains the checker's own enclosure of
    // those speeds, computed otherwise (docs/prove.md: every claim must contain it, never merely
    // overlap it).
    const double margin = 1e-12 * std::max(std::abs(v.lo()), std::abs(v.hi()));
    const Interval speed = Interval::Hull(v.lo() - margin, v.hi() + margin);
    interval_text = "[" + lo + ", " + hi + "]";
    out.proven = true;
    out.reason = fmt::format(
        "exactly one {} in [{}, {}] at which the two symmetric orbits merge (a fold of the symmetric branch: the "
        "discriminant of their quadratic changes sign there, and its derivative, {}, is nonzero over the whole "
        "interval: the fold is nondegenerate)",
        name, lo, hi, bp.disc.d.ToString());
    out.summary = {{"bifurcation", "fold"},
                   {"parameter", name},
                   {"located", located},
                   {"center", center},
                   {"interval", Json::array({lo, hi})},
                   {"width", phi.hi() - plo.lo()},
                   {"box_width", phi.hi() - plo.lo()},
                   {"g_at_ends", Json::array({Pair(bl.disc.v), Pair(bh.disc.v)})},
                   {"slope", Pair(bp.disc.d)},
                   {"speed", Pair(speed)},
                   {"period", 1}};
    out.certificate = {{"bifurcation",
                        {{"type", "fold"},
                         {"parameter", name},
                         {"interval", Json::array({lo, hi})},
                         {"root", 0},
                         {"g_at_ends", Json::array({Pair(bl.disc.v), Pair(bh.disc.v)})},
                         {"slope", Pair(bp.disc.d)},
                         {"speed", Pair(speed)},
                         {"window", eps}}}};
    return out;
  }
  out.reason = last.empty() ? "the time limit was reached" : last;
  return out;
}

}  // namespace vibro::proof
