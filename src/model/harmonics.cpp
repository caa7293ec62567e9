// Commensurability of a sum of harmonics and the checks of its lists (docs/harmonics.md).
#include "vibro/harmonics.hpp"

#include <cmath>
#include <numeric>

#include <fmt/format.h>

#include "vibro/scene.hpp"

namespace vibro {
namespace {

// The best rational approximation p/q of x > 0 with q ≤ qmax (continued fraction convergents).
std::pair<long long, long long> Rational(double x, long long qmax) {
  long long p0 = 0, q0 = 1, p1 = 1, q1 = 0;
  double r = x;
  std::pair<long long, long long> best{std::llround(x), 1};
  for (int it = 0; it < 64; ++it) {
    const double a = std::floor(r);
    if (a > 1e15) break;
    const auto ai = static_cast<long long>(a);
    const long long p2 = ai * p1 + p0, q2 = ai * q1 + q0;
    if (q2 > qmax) break;
    best = {p2, q2};
    if (std::abs(static_cast<double>(p2) / static_cast<double>(q2) - x) <= kRatioTolerance * x) break;
    p0 = p1;
    q0 = q1;
    p1 = p2;
    q1 = q2;
    const double frac = r - a;
    if (frac <= 0) break;
    r = 1 / frac;
  }
  return best;
}

}  // namespace

CommonPeriod FindCommonPeriod(const std::vector<double>& w) {
  CommonPeriod out;
  if (w.empty()) return out;
  // ω_h/ω_0 = p_h/q_h; with L = lcm(q_h), n_h = p_h L/q_h and ω_b = ω_0/L, then reduced by gcd(n_h).
  std::vector<std::pair<long long, long long>> ratio;
  long long L = 1;
  for (size_t h = 0; h < w.size(); ++h) {
    const double x = w[h] / w[0];
    const auto pq = Rational(x, kMaxDenominator);
    if (pq.first <= 0 ||
        !(std::abs(static_cast<double>(pq.first) / static_cast<double>(pq.second) - x) <= kRatioTolerance * x)) {
      out.why = fmt::format(
          "ω_{}/ω_0 = {} is no ratio p/q with q ≤ {} (within {:g}): the frequencies must be commensurate", h,
          x, kMaxDenominator, kRatioTolerance);
      return out;
    }
    ratio.push_back(pq);
    L = std::lcm(L, pq.second);
    if (L > kMaxMultiple) break;
  }
  std::vector<long long> n;
  long long g = 0;
  for (const auto& [p, q] : ratio) {
    n.push_back(p * (L / q));
    g = std::gcd(g, n.back());
  }
  for (auto& k : n) k /= g;
  for (size_t h = 0; h < n.size(); ++h)
    if (L > kMaxMultiple || n[h] > kMaxMultiple) {
      out.why = fmt::format(
          "the common period holds more than {} periods of a harmonic (multiples of the base pulsation "
          "above {}): the frequencies are too far from simple ratios",
          kMaxMultiple, kMaxMultiple);
      return out;
    }
  out.commensurate = true;
  out.base = w[0] / static_cast<double>(n[0]);
  for (const long long k : n) out.multiples.push_back(static_cast<int>(k));
  return out;
}

std::vector<InputIssue> ValidateHarmonics(const std::vector<HarmonicSpec>& hs, long forcing_size) {
  std::vector<InputIssue> out;
  const auto show = [](double v) { return fmt::format("{}", v); };
  std::vector<double> w;
  bool frequencies_ok = true;
  for (size_t h = 0; h < hs.size(); ++h) {
    const HarmonicSpec& s = hs[h];
    const std::string at = fmt::format("[{}]", h);
    if (!(std::isfinite(s.amplitude) && s.amplitude >= 0))
      out.push_back({"excitation.amplitude" + at, show(s.amplitude), fmt::format("f_{} ≥ 0 and finite", h)});
    if (!(std::isfinite(s.frequency) && s.frequency > 0)) {
      out.push_back({"excitation.frequency" + at, show(s.frequency),
                     fmt::format("ω_{} > 0 and finite", h)});
      frequencies_ok = false;
    }
    if (!std::isfinite(s.phase) || std::abs(s.phase) > 1e6)
      out.push_back({"excitation.phase" + at, show(s.phase), fmt::format("|ψ_{}| ≤ 1e6 rad and finite", h)});
    if (s.vector.size() > 0) {
      if (s.vector.size() != forcing_size)
        out.push_back({fmt::format("excitation.vectors[{}]", h), "",
                       fmt::format("one component per {} ({} expected, got {})",
                                   forcing_size >= 0 ? "DOF or listed mode" : "DOF", forcing_size,
                                   s.vector.size())});
      else if (!s.vector.allFinite() || s.vector.cwiseAbs().maxCoeff() == 0)
        out.push_back({fmt::format("excitation.vectors[{}]", h), "",
                       "finite components, not all zero"});
    }
    w.push_back(s.frequency);
  }
  if (frequencies_ok && hs.size() > 1) {
    const CommonPeriod cp = FindCommonPeriod(w);
    if (!cp.commensurate) out.push_back({"excitation.frequency", "", cp.why});
  }
  return out;
}

}  // namespace vibro
