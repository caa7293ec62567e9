// Certified first-root location for the trigonometric sums of the exact engine (docs/model.md §2.1).
//
// At a point u with g(u) > 0, g(u+h) ≥ p(h) = g + g'h + g''h²/2 − M h³/6 whenever M bounds
// |g'''| over [u, u+h]. Stepping to the first positive root of p never skips a root of g (g ≥ p > 0
// before it), converges with order ≥ 1.5 even at a tangency, and passes a near-tangent minimum
// in a few steps. This is what makes near-grazing impacts impossible to miss.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "dynamics/scalar.hpp"

namespace vibro::detail {

template <class S>
struct JetT {
  S g, g1, g2;  // g(u), g'(u), g''(u)
};

template <class S>
struct RootSearchT {
  bool found;  // a root in [start, end]
  S sigma;     // the root (found) or `end`
  int steps;
};

// First root in (0, H] of p(h) = g + g1 h + g2 h²/2 − M h³/6 with g > 0, M ≥ 0; returns a point
// h ≤ the root with p(h) ≥ 0 (H if p > 0 on the whole interval, then with `none` = true).
template <class S>
S FirstCubicRoot(const S& g, const S& g1, const S& g2, const S& M, const S& H, bool& none) {
  const auto p = [&](const S& h) -> S { return g + h * (g1 + h * (S(0.5) * g2 - h * M / 6)); };
  // p is monotone between the roots of p'(h) = g1 + g2 h − M h²/2.
  S cuts[3];
  int nc = 0;
  if (M > 0) {
    const S disc = g2 * g2 + S(2) * M * g1;
    if (disc > 0) {
      const S sq = Real<S>::sqrt(disc);
      const S r1 = (g2 - sq) / M, r2 = (g2 + sq) / M;
      if (r1 > 0 && r1 < H) cuts[nc++] = r1;
      if (r2 > 0 && r2 < H) cuts[nc++] = r2;
    }
  } else if (g2 != 0) {
    const S r = -g1 / g2;
    if (r > 0 && r < H) cuts[nc++] = r;
  }
  cuts[nc++] = H;
  S lo(0);
  // p(lo), known without evaluating p again: the first Newton step starts at lo. At lo = 0 it is g
  // to the bit when g', g'' and M are finite (0·y = ±0 and g + ±0 = g; x − x = 0 tests finiteness);
  // at a cut it is the value just computed there.
  const bool finite = g1 - g1 == S(0) && g2 - g2 == S(0) && M - M == S(0);
  S plo = finite ? g : p(S(0));
  // Likewise p'(0) = g1 + 0·(…) is g1, but for the sign of a zero, which the step does not read
  // (p' = ±0 bisects): the first step from 0 needs no M, so its division starts before the probe's
  // bound is ready (docs/performance.md, "The first Newton step without M").
  bool at_zero = finite;
  for (int i = 0; i < nc; ++i) {
    S hi = cuts[i];
    const S phi = p(hi);
    if (phi > 0) {
      lo = hi;
      plo = phi;
      at_zero = false;
      continue;
    }
    // Safeguarded Newton on a monotone stretch, p(lo) > 0 ≥ p(hi).
    const S kEps = Eps<S>();
    S x = lo;
    for (int it = 0; it < 200 && hi - lo > 4 * kEps * hi; ++it) {
      const S px = it == 0 ? plo : p(x);
      (px > 0 ? lo : hi) = x;
      const S dp = it == 0 && at_zero ? g1 : S(g1 + x * (g2 - S(0.5) * M * x));
      S next = dp != 0 ? S(x - px / dp) : S(S(0.5) * (lo + hi));
      // Newton from the unsafe side (p ≤ 0) moving by a few ulps: the root is at hi to rounding,
      // and the scan below finds the point just under it. (Closing the bracket from lo instead
      // took ~25 halvings per call: every Newton step from the safe side overshoots hi then.)
      if (!(px > 0) && dp != 0 && next <= x && x - next <= 8 * kEps * x) break;
      if (!(next > lo && next < hi)) next = S(0.5) * (lo + hi);
      if (next == x) break;
      x = next;
    }
    // Newton may converge from the unsafe side: take the largest point found just below hi
    // where p is still positive.
    for (S d = 4 * kEps * hi; hi - d > lo; d *= 4) {
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

template <class S>
struct ProbeT {
  JetT<S> jet;  // g, g', g'' at u
  S M;          // bound on |g'''| over [u, u + H]
  // Optional second lower bound over a longer window [u, u + far_H] (used when far_H > H):
  // g(u + h) ≥ far.g + far.g1 h + far.g2 h²/2 − far_M h³/6 there. The exact engine builds it by
  // bounding the fast modes by their amplitude instead of their Taylor remainder
  // (dynamics/exact_engine.hpp, AddFarBound), so that they stop dictating the step far from the
  // stop (docs/performance.md).
  JetT<S> far{S(0), S(0), S(0)};
  S far_M{0};
  S far_H{0};
};

using Jet = JetT<double>;
using Probe = ProbeT<double>;
using RootSearch = RootSearchT<double>;

// First root of g in [start, end]. `probe(u, H, rest)` returns the jet at u and a bound on |g'''|
// over [u, u + H], and optionally a second lower bound over [u, u + far_H], far_H ≤ rest = end − u;
// steps are capped at h_cap (the bound may grow with H) or far_H. Each lower bound is positive up
// to its first root, so stepping to the larger of the two first roots skips no root of g. g(start) > 0 expected: a
// start with g ≤ 0 is reported as a root at `start`. `stop()` is polled every 1024 steps: when it
// returns true (a stop request or a work limit) the search gives up with `stopped` set.
template <class S>
struct PolledRootSearch {
  RootSearchT<S> result;
  bool stopped = false;
};

template <class S, class ProbeFn, class StopFn>
PolledRootSearch<S> FirstRootPolled(const ProbeFn& probe, const S& start, const S& end,
                                    const S& h_cap, const StopFn& stop, int max_steps = 100000) {
  const S kEps = Eps<S>();
  const S tiny(std::numeric_limits<double>::min());
  S u = start;
  for (int steps = 0; steps < max_steps; ++steps) {
    if ((steps & 1023) == 1023 && stop()) return {{false, u, steps}, true};
    if (u >= end) return {{false, end, steps}, false};
    const S rest = end - u;
    const S H = rest < h_cap ? rest : h_cap;
    const ProbeT<S> pr = probe(u, H, rest);
    const JetT<S>& j = pr.jet;
    if (!(j.g > 0)) return {{true, u, steps}, false};
    bool none = false;
    S h = FirstCubicRoot<S>(j.g, j.g1, j.g2, pr.M, H, none);
    S reach = H;
    if (pr.far_H > H && pr.far.g > 0) {
      bool far_none = false;
      const S far_H = pr.far_H < rest ? pr.far_H : rest;
      const S h_far = FirstCubicRoot<S>(pr.far.g, pr.far.g1, pr.far.g2, pr.far_M, far_H, far_none);
      if (h_far > (none ? H : h)) {
        h = h_far;
        none = far_none;
        reach = far_H;
      }
    }
    if (none) {
      u = (reach == rest) ? end : S(u + reach);
      continue;
    }
    if (h <= 4 * kEps * (u > tiny ? u : tiny)) return {{true, u + h, steps}, false};
    u += h;
  }
  return {{true, u, max_steps}, false};  // stalled at a tangency: g → 0⁺ without crossing
}

// `probe(u, H)` without the second bound.
template <class ProbeFn>
RootSearch FirstRoot(const ProbeFn& probe, double start, double end, double h_cap,
                     int max_steps = 100000) {
  return FirstRootPolled<double>([&](double u, double H, double) { return probe(u, H); }, start, end,
                                 h_cap, [] { return false; }, max_steps)
      .result;
}

}  // namespace vibro::detail
