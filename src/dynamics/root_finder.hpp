// Certified first-root location for the trigonometric sums of the exact engine (MODEL §2.1).
//
// At a point u with g(u) > 0, g(u+h) ≥ p(h) = g + g'h + g''h²/2 − M h³/6 whenever M bounds
// |g'''| over [u, u+h]. Stepping to the first positive root of p never skips a root of g (g ≥ p > 0
// before it), converges with order ≥ 1.5 even at a tangency, and passes a near-tangent minimum
// in a few steps. This is what makes near-grazing impacts impossible to miss.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

namespace vibro::detail {

struct Jet {
  double g, g1, g2;  // g(u), g'(u), g''(u)
};

struct RootSearch {
  bool found;    // a root in [start, end]
  double sigma;  // the root (found) or `end`
  int steps;
};

// First root in (0, H] of p(h) = g + g1 h + g2 h²/2 − M h³/6 with g > 0, M ≥ 0; returns a point
// h ≤ the root with p(h) ≥ 0 (H if p > 0 on the whole interval, then with `none` = true).
inline double FirstCubicRoot(double g, double g1, double g2, double M, double H, bool& none) {
  const auto p = [&](double h) { return g + h * (g1 + h * (0.5 * g2 - h * M / 6.0)); };
  // p is monotone between the roots of p'(h) = g1 + g2 h − M h²/2.
  double cuts[3];
  int nc = 0;
  if (M > 0) {
    const double disc = g2 * g2 + 2.0 * M * g1;
    if (disc > 0) {
      const double sq = std::sqrt(disc);
      const double r1 = (g2 - sq) / M, r2 = (g2 + sq) / M;
      if (r1 > 0 && r1 < H) cuts[nc++] = r1;
      if (r2 > 0 && r2 < H) cuts[nc++] = r2;
    }
  } else if (g2 != 0) {
    const double r = -g1 / g2;
    if (r > 0 && r < H) cuts[nc++] = r;
  }
  cuts[nc++] = H;
  double lo = 0.0;
  for (int i = 0; i < nc; ++i) {
    double hi = cuts[i];
    if (p(hi) > 0) {
      lo = hi;
      continue;
    }
    // Safeguarded Newton on a monotone stretch, p(lo) > 0 ≥ p(hi).
    constexpr double kEps = std::numeric_limits<double>::epsilon();
    double x = lo;
    for (int it = 0; it < 100 && hi - lo > 4.0 * kEps * hi; ++it) {
      const double px = p(x);
      (px > 0 ? lo : hi) = x;
      const double dp = g1 + x * (g2 - 0.5 * M * x);
      double next = dp != 0 ? x - px / dp : 0.5 * (lo + hi);
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      if (next == x) break;
      x = next;
    }
    // Newton may converge from the unsafe side: take the largest point found just below hi
    // where p is still positive.
    for (double d = 4.0 * kEps * hi; hi - d > lo; d *= 4.0) {
      if (p(hi - d) > 0) {
        lo = hi - d;
        break;
      }
    }
    none = false;
    return lo;
  }
  none = true;
  return H;
}

struct Probe {
  Jet jet;   // g, g', g'' at u
  double M;  // bound on |g'''| over [u, u + H]
};

// First root of g in [start, end]. `probe(u, H)` returns the jet at u and a bound on |g'''| over
// [u, u + H]; steps are capped at h_cap (the bound may grow with H). g(start) > 0 expected: a
// start with g ≤ 0 is reported as a root at `start`.
template <class ProbeFn>
RootSearch FirstRoot(const ProbeFn& probe, double start, double end, double h_cap,
                     int max_steps = 100000) {
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  double u = start;
  for (int steps = 0; steps < max_steps; ++steps) {
    if (u >= end) return {false, end, steps};
    const double H = std::min(h_cap, end - u);
    const Probe pr = probe(u, H);
    const Jet& j = pr.jet;
    const double M = pr.M;
    if (!(j.g > 0)) return {true, u, steps};
    bool none = false;
    const double h = FirstCubicRoot(j.g, j.g1, j.g2, M, H, none);
    if (none) {
      u = (H == end - u) ? end : u + H;
      continue;
    }
    if (h <= 4.0 * kEps * std::max(u, std::numeric_limits<double>::min()))
      return {true, u + h, steps};
    u += h;
  }
  return {true, u, max_steps};  // stalled at a tangency: g → 0⁺ without crossing
}

}  // namespace vibro::detail
