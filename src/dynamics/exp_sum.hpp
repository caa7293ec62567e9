// Real functions written as finite sums of complex exponentials, F(σ) = Re Σ_m B_m e^{μ_m σ}:
// every linear flow of the model (a mode, damped or not, a harmonic forcing term, a constant, the
// relaxation of a compliant stop's surface) is one, and so are its derivatives and its integral.
// The compliant contact phase (dynamics/compliant_contact.hpp, docs/compliant.md) writes its gap,
// gap rate and contact force this way and locates their roots with the certified stepping of
// dynamics/root_finder.hpp: |F'''| over [u, u + H] is bounded by Σ|B_m||μ_m|³ max(e^{Re μ_m u},
// e^{Re μ_m (u+H)}).
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

#include "dynamics/root_finder.hpp"

namespace vibro::detail {

struct ExpSum {
  using C = std::complex<double>;
  std::vector<C> B, mu;

  void Add(C b, C m) {
    B.push_back(b);
    mu.push_back(m);
  }
  void Append(const ExpSum& o, double scale = 1.0) {
    for (size_t i = 0; i < o.B.size(); ++i) Add(o.B[i] * scale, o.mu[i]);
  }
  // The d-th derivative at σ.
  double Value(double s, int d = 0) const {
    C sum(0.0, 0.0);
    for (size_t i = 0; i < B.size(); ++i) {
      C f = B[i] * std::exp(mu[i] * s);
      for (int k = 0; k < d; ++k) f *= mu[i];
      sum += f;
    }
    return sum.real();
  }
  // F^(d), F^(d+1), F^(d+2) at σ in one pass.
  JetT<double> Jet(double s, int d = 0) const {
    C a(0.0, 0.0), b(0.0, 0.0), c(0.0, 0.0);
    for (size_t i = 0; i < B.size(); ++i) {
      C f = B[i] * std::exp(mu[i] * s);
      for (int k = 0; k < d; ++k) f *= mu[i];
      a += f;
      f *= mu[i];
      b += f;
      c += f * mu[i];
    }
    return {a.real(), b.real(), c.real()};
  }
  // A bound on |F^(d)| over [u, u + H], with a relative margin for the rounding of the sum.
  double Bound(double u, double H, int d) const {
    double M = 0;
    for (size_t i = 0; i < B.size(); ++i) {
      const double r = mu[i].real();
      const double grow = std::exp(std::max(r * u, r * (u + H)));
      M += std::abs(B[i]) * std::pow(std::abs(mu[i]), d) * grow;
    }
    return M * (1 + 1e-9);
  }
  // ∫_0^σ F.
  double Integral(double s) const {
    C sum(0.0, 0.0);
    for (size_t i = 0; i < B.size(); ++i) sum += B[i] * Phi(mu[i], s);
    return sum.real();
  }
  // ∫_0^σ F G for two real sums (the dashpot's dissipation ∫ c ġ² dt): F G = Re(F) Re(G) with
  // Re z = (z + z̄)/2, so the product is ½ Re Σ B_m (C_l e^{(μ_m+ν_l)σ} + C̄_l e^{(μ_m+ν̄_l)σ}).
  static double IntegralOfProduct(const ExpSum& f, const ExpSum& g, double s) {
    C sum(0.0, 0.0);
    for (size_t i = 0; i < f.B.size(); ++i)
      for (size_t k = 0; k < g.B.size(); ++k)
        sum += f.B[i] * (g.B[k] * Phi(f.mu[i] + g.mu[k], s) +
                         std::conj(g.B[k]) * Phi(f.mu[i] + std::conj(g.mu[k]), s));
    return 0.5 * sum.real();
  }

  // ∫_0^σ e^{μt} dt = (e^{μσ} − 1)/μ, accurately for small |μσ| (σ(1 + μσ/2 + …)).
  static C Phi(C m, double s) {
    const C z = m * s;
    if (std::abs(z) < 1e-3) {
      C term(s, 0.0), sum(0.0, 0.0);
      for (int k = 1; k < 12; ++k) {
        sum += term;
        term *= z / static_cast<double>(k + 1);
      }
      return sum;
    }
    return (std::exp(z) - 1.0) / m;
  }
};

// First root in (0, end] of F, with F(0) ≥ 0 (a start at a root of F is divided out: the first
// step goes to where the cubic lower bound F(0) + F'(0)h + F''(0)h²/2 − M h³/6 first vanishes, from
// F'(0) > 0 or F'(0) = 0 < F''(0)); the certified stepping of root_finder.hpp from there.
// found = false: F stays positive over (0, end]. A start with F(0) ≤ 0 that the jet does not lift
// (F'(0) < 0, or F'(0) = 0 with F''(0) ≤ 0) is a root at 0.
struct ExpRoot {
  bool found;
  double sigma;
};
// double_zero: the start is a double root of F by construction (F = F' = 0, F'' > 0: a force-rule
// exit, where body and surface part with the same velocity): F'(0) is taken as 0.
inline ExpRoot FirstExpRoot(const ExpSum& F, double end, double scale, bool double_zero = false) {
  const double h_cap = std::max(end, 1e-300);
  const auto probe = [&](double u, double H, double) {
    ProbeT<double> p;
    p.jet = F.Jet(u);
    p.M = F.Bound(u, H, 3);
    return p;
  };
  const JetT<double> j0 = F.Jet(0.0);
  double start = 0;
  // "At a root" within the rounding of the sum: |F(0)| below a few ulps of its terms.
  double terms = 0;
  for (size_t i = 0; i < F.B.size(); ++i) terms += std::abs(F.B[i]);
  const double zero_tol = 64 * std::numeric_limits<double>::epsilon() * std::max(terms, scale);
  if (!(j0.g > zero_tol)) {
    // A slope within the rounding of the rate's terms is a zero slope (a start where F and F'
    // vanish together, e.g. a force-rule exit: body and surface part with the same velocity).
    double rate_terms = 0;
    for (size_t i = 0; i < F.B.size(); ++i) rate_terms += std::abs(F.B[i] * F.mu[i]);
    const bool flat = double_zero || std::abs(j0.g1) <= 64 * std::numeric_limits<double>::epsilon() * rate_terms;
    const bool lifts = (j0.g1 > 0 && !flat) || (flat && j0.g2 > 0);
    if (!lifts) return {true, 0.0};
    // p(h) = h (g1 + g2 h/2 − M h²/6) (+ g0 ≥ −zero_tol): positive up to the quadratic's first root.
    double H = end;
    for (int it = 0; it < 60; ++it) {
      const double M = F.Bound(0.0, H, 3);
      const double a = M / 6, b = -j0.g2 / 2, c = flat ? 0.0 : -j0.g1;  // a h² + b h + c = 0, first positive root
      double r;
      if (a == 0) r = b < 0 ? -c / b : H;
      else r = (-b + std::sqrt(std::max(0.0, b * b - 4 * a * c))) / (2 * a);
      if (!(r > 0)) return {true, 0.0};
      if (r <= H) {
        start = 0.5 * r;
        break;
      }
      start = 0.5 * H;
      break;
    }
    if (!(F.Value(start) > 0)) {
      // The lift is lost to rounding (a touch within the sum's ulps): the root is at the start.
      return {true, 0.0};
    }
  }
  const auto res = FirstRootPolled<double>(probe, start, end, h_cap, [] { return false; }, 1000000);
  return {res.result.found, res.result.sigma};
}

}  // namespace vibro::detail
