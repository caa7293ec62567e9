// A grazing of an impacting orbit, proven (docs/prove.md "Bifurcation points").
//
// The orbit's unknowns u = (t_j, X_j, V_j) per impact j (as in impact_proof.cpp: the time and the
// modal state just after impact j) satisfy F(u, p) = 0 (on the contact at each impact, the flight
// of eqs (13)-(14) and docs/model.md §7 to the next, the restitution law (10)-(12)), p the amplitude
// or the forcing frequency. On flight J (from impact J), the gap of contact l,
// γ(s; u, p) = c_lᵀX(t_J + s) − e_l, has a local minimum m(p) at s(p): the grazing is m(p) = 0.
// The extended system E(u, s, p) = (F, γ̇, γ) = 0 (N + 2 equations in N + 2 unknowns) is proven to
// have exactly one zero in the box U × S × P by Krawczyk's test, P = [p_lo, p_hi] ≤ 1e-10 wide.
// Exactly one grazing parameter in P, crossed transversally:
//  (1) Krawczyk on F(u, P) = 0 alone over U: for every p ∈ P exactly one orbit u(p) ∈ U;
//  (2) γ̈ > 0 over a window W ⊇ S (every p ∈ P, u ∈ U) and γ̇ < 0 at S's lower end, > 0 at its
//      upper end: the minimum s(p) on W is unique and lies in S;
//  (3) every matrix J of the extended Jacobian over the box has ‖I − CJ‖∞ ≤ δ < 1 (C the
//      preconditioner), so J⁻¹ e_last ∈ C e_last ± δ/(1 − δ)‖C e_last‖∞; along the family,
//      E(u(p), s(p), p) = (0, 0, m(p)) gives dp/dm = (J⁻¹)_{last,last}: when that excludes 0,
//      dm/dp = 1/(J⁻¹)_{last,last} is enclosed and nonzero over all of P, so m is strictly monotone
//      on P: the zero that Krawczyk's test proves is the only one and the crossing is transversal;
//  (4) the orbit is an orbit: every flight has a positive duration, leaves its contact with a
//      positive gap velocity and reaches the next with a negative one, and every gap is positive
//      between the impacts (certified positivity) except contact l's on W, where it is convex.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "proof/grazing_proof.hpp"
#include "proof/orbit_family.hpp"

namespace vibro::proof {
using namespace family;

Outcome ProveGrazing(const IntervalModel& model, bool mirrored, const ImpactGuess& guess, bool frequency,
                     double located, double bracket, const Budget& budget, std::string& interval_text) {
  Outcome out;
  const char* name = frequency ? "frequency" : "amplitude";
  Setup g;
  g.m = &model;
  g.n = model.n;
  g.count = static_cast<int>(guess.times.size());
  g.q = guess.period;
  g.frequency = frequency;
  g.hits = guess.contacts.empty() ? std::vector<int>(static_cast<std::size_t>(g.count), 0) : guess.contacts;
  if (g.count == 0) {
    out.reason = "the orbit found has no impact: a grazing is proven for impacting orbits";
    return out;
  }
  if (g.N() + 2 > kMaxUnknowns) {
    out.reason = fmt::format("{} impacts and {} mode(s): {} unknowns, more than the {} the prover takes", g.count, g.n,
                             g.N() + 2, kMaxUnknowns);
    return out;
  }
  // A symmetric orbit of a mirrored model: proven as its half (the two grazings, of contact l on
  // one half and of the other contact on the mirrored half, are then one).
  if (model.contact_count() == 2 && g.count == 2 && g.q == 1 && g.hits[0] != g.hits[1]) {
    const auto& k0 = model.contacts[0];
    const auto& k1 = model.contacts[1];
    bool exact = true;
    for (int i = 0; i < g.n; ++i) {
      const auto z = static_cast<std::size_t>(i);
      const Interval c = k0.shape[z] + k1.shape[z], t = k0.contact[z] + k1.contact[z];
      exact = exact && c.lo() == 0 && c.hi() == 0 && t.lo() == 0 && t.hi() == 0;
    }
    const double T = 2 * M_PI / (frequency ? located : model.frequency.mid());
    bool image = std::abs(guess.times[1] - guess.times[0] - T / 2) < 1e-4 * T;
    for (int i = 0; i < g.n; ++i)
      image = image && std::abs(guess.X[1](i) + guess.X[0](i)) < 1e-4 * (1 + std::abs(guess.X[0](i))) &&
              std::abs(guess.V[1](i) + guess.V[0](i)) < 1e-4 * (1 + std::abs(guess.V[0](i)));
    if ((exact || mirrored) && k0.stop_text == k1.stop_text && k0.restitution_text == k1.restitution_text && image) {
      g.symmetric = true;
      g.count = 1;
      g.hits.resize(1);
    }
  }
  std::vector<double> u0;
  for (int j = 0; j < g.count; ++j) {
    u0.push_back(guess.times[static_cast<std::size_t>(j)]);
    for (int i = 0; i < g.n; ++i) u0.push_back(guess.X[static_cast<std::size_t>(j)](i));
    for (int i = 0; i < g.n; ++i) u0.push_back(guess.V[static_cast<std::size_t>(j)](i));
  }
  // The flight and contact that come nearest to a tangency: the interior local minimum of a gap
  // (sampled) of least value.
  const std::vector<Interval> U0(u0.begin(), u0.end());
  const Interval p0(located);
  double best = std::numeric_limits<double>::infinity(), s0 = 0;
  for (int j = 0; j < g.count; ++j) {
    const double S = Duration(g, U0, j, p0).mid();
    constexpr int kSamples = 400;
    std::vector<double> gap(kSamples + 1);
    for (int l = 0; l < model.contact_count(); ++l) {
      for (int k = 0; k <= kSamples; ++k) gap[static_cast<std::size_t>(k)] = GapAt(g, U0, p0, j, l, Interval(S * k / kSamples)).value.mid();
      for (int k = 1; k < kSamples; ++k) {
        const double y = gap[static_cast<std::size_t>(k)];
        if (y <= gap[static_cast<std::size_t>(k - 1)] && y <= gap[static_cast<std::size_t>(k + 1)] && std::abs(y) < best) {
          best = std::abs(y);
          s0 = S * k / kSamples;
          g.flight = j;
          g.contact = l;
        }
      }
    }
  }
  if (!std::isfinite(best)) {
    out.reason = "no free flight of the orbit has an interior minimum of a gap: no grazing near the located point";
    return out;
  }
  std::vector<double> x0 = u0;
  x0.push_back(s0);
  x0.push_back(located);
  const auto solved = Newton(g, x0);
  if (!solved) {
    out.reason = fmt::format("Newton on the orbit with a tangency of contact {} on flight {} does not converge from the "
                             "located point: no grazing found to prove", g.contact, g.flight);
    return out;
  }
  const std::vector<double> x = *solved;
  const std::size_t N = g.N();
  const double pstar = x[N + 1], sstar = x[N];
  const double slack = bracket + 1e-10 * (1 + std::abs(located));
  const double center = bracket > 0 && std::abs(pstar - located) <= slack ? pstar : located;
  // The family's tangent dx/dp (F = 0, γ̇ = 0 with p given), for the box's radii.
  std::vector<double> dxdp(N + 1, 0.0);
  {
    std::vector<Interval> xi(x.begin(), x.end());
    const auto lin = Linearize(g, xi, xi, true);
    Eigen::MatrixXd A(static_cast<Eigen::Index>(N + 1), static_cast<Eigen::Index>(N + 1));
    Eigen::VectorXd b(static_cast<Eigen::Index>(N + 1));
    for (std::size_t a = 0; a <= N; ++a) {
      for (std::size_t c = 0; c <= N; ++c) A(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(c)) = lin.J[a][c].mid();
      b(static_cast<Eigen::Index>(a)) = -lin.J[a][N + 1].mid();
    }
    const Eigen::VectorXd d = A.fullPivLu().solve(b);
    for (std::size_t a = 0; a <= N && d.allFinite(); ++a) dxdp[a] = d(static_cast<Eigen::Index>(a));
  }
  double top = model.frequency.hi() + (frequency ? 1.0 : 0.0);
  for (const auto& w : model.omega) top = std::max(top, w.hi());
  const double step = 0.25 / top;
  std::string last;
  for (double half = 1e-12 * (1 + std::abs(center)); 2 * half <= 1e-10 && !budget.passed(); half *= 4) {
    const std::string lo = Dec(center - half), hi = Dec(center + half);
    const Interval P = Union(Interval::Decimal(lo), Interval::Decimal(hi));
    if (!(P.lo() < pstar && pstar < P.hi())) {
      last = fmt::format("the tangency of contact {} on flight {} is at {} = {} (Newton), outside [{}, {}]: no grazing "
                         "is proven there", g.contact, g.flight, name, Dec(pstar), lo, hi);
      continue;
    }
    const double reach = std::max(P.hi() - pstar, pstar - P.lo());
    std::vector<Interval> X;
    KrawczykTest fam, ext;
    bool boxed = false;
    for (double r0 = 1e-13; r0 <= 1e-9 && !boxed; r0 *= 10) {
      X.clear();
      for (std::size_t a = 0; a <= N; ++a) {
        const double rad = r0 * (1 + std::abs(x[a])) + 2 * std::abs(dxdp[a]) * reach;
        X.push_back(Interval::Hull(x[a] - rad, x[a] + rad));
      }
      X.push_back(P);
      const std::vector<Interval> Uu(X.begin(), X.begin() + static_cast<std::ptrdiff_t>(N));
      std::vector<double> xu(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(N));
      std::vector<Interval> UP = Uu;
      xu.push_back(pstar);
      UP.push_back(P);
      fam = Krawczyk(g, xu, UP, false);
      if (!fam.inside) {
        last = fmt::format("Krawczyk's test on the orbit over {} in [{}, {}] fails (unknown {}): no unique orbit proven "
                           "over the interval", name, lo, hi, fam.worst);
        continue;
      }
      // The tangency's time box: wide enough that γ̇ has its signs at its ends for every orbit of U
      // (γ̇ at s* over the box is that wide, and γ̈ turns it into time).
      const Gap mid = GapAt(g, Uu, P, g.flight, g.contact, Interval(sstar));
      const double rad_s = X[N].hi() - sstar + 2 * (mid.rate.hi() - mid.rate.lo()) / std::abs(mid.acceleration.mid());
      X[N] = Interval::Hull(sstar - rad_s, sstar + rad_s);
      ext = Krawczyk(g, x, X, true);
      if (!ext.inside) {
        last = fmt::format("Krawczyk's test on the orbit with its tangency fails (unknown {} of {}): no unique grazing "
                           "proven in [{}, {}]", ext.worst, N + 2, lo, hi);
        continue;
      }
      const Gap a = GapAt(g, Uu, P, g.flight, g.contact, Interval(X[N].lo()));
      const Gap b = GapAt(g, Uu, P, g.flight, g.contact, Interval(X[N].hi()));
      if (!a.rate.Negative() || !b.rate.Positive()) {
        last = fmt::format("the gap velocity at the ends of the tangency's time box is {} and {}: not proven of "
                           "opposite signs", a.rate.ToString(), b.rate.ToString());
        continue;
      }
      boxed = true;
    }
    if (!boxed) continue;
    const std::vector<Interval> Uu(X.begin(), X.begin() + static_cast<std::ptrdiff_t>(N));
    // (3) dm/dp over P.
    const auto Nl = static_cast<Eigen::Index>(N + 1);
    double cmax = 0;
    for (Eigen::Index a = 0; a <= Nl; ++a) cmax = std::max(cmax, std::abs(ext.C(a, Nl)));
    if (!(ext.delta < 1)) {
      last = fmt::format("‖I − CJ‖∞ ≤ {} over the box: not below 1", ext.delta);
      continue;
    }
    const Interval dl(ext.delta);
    const double spread = (dl / (Interval(1.0) - dl) * Interval(cmax)).hi();
    const Interval inv = Interval(ext.C(Nl, Nl)) + Interval::Hull(-spread, spread);
    if (inv.Contains(0.0)) {
      last = fmt::format("dp/dm (the inverse of the minimum gap's derivative) is {} over the box: not proven nonzero",
                         inv.ToString());
      continue;
    }
    const Interval slope = Interval(1.0) / inv;
    // (2) The window: γ̈ > 0 on W ⊇ S, for every p and orbit of the box.
    const Interval Sj = Duration(g, Uu, g.flight, P);
    std::optional<double> wlo, whi;
    for (double ww = std::min(0.05 * Sj.lo(), 0.45 * std::min(sstar, Sj.lo() - sstar)); ww > 1e-6 * Sj.lo(); ww /= 2) {
      const double a = std::max(sstar - ww, 0.0), b = std::min(sstar + ww, Sj.lo());
      if (!(a < X[N].lo() && X[N].hi() < b)) break;
      bool convex = true;
      constexpr int kPieces = 32;
      for (int k = 0; k < kPieces && convex; ++k)
        convex = GapAt(g, Uu, P, g.flight, g.contact, Interval::Hull(a + (b - a) * k / kPieces, a + (b - a) * (k + 1) / kPieces))
                     .acceleration.Positive();
      if (convex) {
        wlo = a;
        whi = b;
        break;
      }
    }
    if (!wlo) {
      last = "the gap is not proven convex on a window around the tangency";
      continue;
    }
    // (4) The orbit is an orbit, for every p and u of the box.
    const std::string fail = OrbitGaps(g, Uu, P, budget, step, *wlo, *whi);
    if (!fail.empty()) {
      last = fail;
      continue;
    }
    const Gap at = GapAt(g, Uu, P, g.flight, g.contact, X[N]);
    // Claims: widened a little beyond the prover's enclosures, so that they contain the checker's
    // own (computed otherwise: docs/prove.md, every claim must contain it).
    const auto widen = [](const Interval& v, double rel) {
      const double m = rel * std::max(std::abs(v.lo()), std::abs(v.hi())) + (v.hi() - v.lo());
      return Interval::Hull(v.lo() - m, v.hi() + m);
    };
    const Interval slope_claim = widen(slope, 1e-6), curvature = widen(at.acceleration, 1e-6);
    const Interval time = widen(Uu[g.t(g.flight)] + X[N], 1e-12);
    Json box = Json::array(), names = Json::array();
    for (std::size_t a = 0; a <= N; ++a) box.push_back(Pair(X[a]));
    for (int j = 0; j < g.count; ++j) {
      names.push_back(fmt::format("t_{}", j));
      for (int i = 0; i < g.n; ++i) names.push_back(fmt::format("X_{}[{}]", j, i));
      for (int i = 0; i < g.n; ++i) names.push_back(fmt::format("V_{}[{}]", j, i));
    }
    names.push_back("s");
    interval_text = "[" + lo + ", " + hi + "]";
    out.proven = true;
    const bool opens = slope.Positive();
    out.reason = fmt::format(
        "exactly one {} in [{}, {}] at which flight {} of the orbit touches contact {} with zero velocity (a grazing): "
        "the minimum gap m on that flight is zero there and its derivative dm/d{}, {}, is nonzero over the whole "
        "interval: the crossing is transversal (below the point the flight {} the contact, above it it {})",
        name, lo, hi, g.flight, g.contact, name, slope.ToString(), opens ? "crosses" : "clears",
        opens ? "clears" : "crosses");
    Json hits = Json::array();
    for (int h : g.hits) hits.push_back(h);
    if (g.symmetric) {
      hits.push_back(1 - g.hits[0]);
      out.reason += fmt::format("; the orbit is symmetric (proven as its half: the second half is the first mirrored), so "
                                "at the same point flight 1 touches contact {} likewise", 1 - g.contact);
    }
    out.summary = {{"bifurcation", "grazing"},
                   {"parameter", name},
                   {"located", located},
                   {"center", center},
                   {"interval", Json::array({lo, hi})},
                   {"width", P.hi() - P.lo()},
                   {"box_width", P.hi() - P.lo()},
                   {"slope", Pair(slope_claim)},
                   {"curvature", Pair(curvature)},
                   {"grazing_contact", g.contact},
                   {"grazing_flight", g.flight},
                   {"grazing_time", Pair(time)},
                   {"impact_contacts", hits},
                   {"symmetric", g.symmetric},
                   {"period", g.q}};
    out.certificate = {{"bifurcation",
                        {{"type", "grazing"},
                         {"parameter", name},
                         {"interval", Json::array({lo, hi})},
                         {"contact", g.contact},
                         {"flight", g.flight},
                         {"impact_contacts", hits},
                         {"symmetric", g.symmetric},
                         {"unknowns", names},
                         {"midpoint", std::vector<double>(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(N + 1))},
                         {"box", box},
                         {"window", Json::array({*wlo, *whi})},
                         {"slope", Pair(slope_claim)},
                         {"curvature", Pair(curvature)},
                         {"grazing_time", Pair(time)}}}};
    return out;
  }
  out.reason = last.empty() ? "the time limit was reached" : last;
  return out;
}

}  // namespace vibro::proof
