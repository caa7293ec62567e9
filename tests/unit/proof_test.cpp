// The prover's interval layer (src/proof/interval.cpp on Arb), its closed-form enclosures and its
// certified tests, against truths computed another way: decimals that doubles cannot hold, libm at
// sample points, conservation of energy, finite differences, known spectra.
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <complex>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "proof/enclosure.hpp"
#include "proof/interval.hpp"
#include "proof/jet.hpp"
#include "proof/positivity.hpp"
#include "proof/proof_common.hpp"
#include "vibro/stop_request.hpp"

namespace vibro::proof {
namespace {

TEST(Interval, DecimalsAreEnclosedExactlyNotAsTheirNearestDouble) {
  const Interval x = Interval::Decimal("1.1");
  // The double nearest 1.1 is 1.100000000000000088…: not in the enclosure of the decimal 1.1,
  // which lies between it and the double below.
  EXPECT_FALSE(x.Contains(1.1));
  EXPECT_TRUE(Interval::Hull(std::nextafter(1.1, 0.0), 1.1).Contains(x));
  EXPECT_LE(x.width(), 2.3e-16);  // the ends, rounded outwards to doubles, are neighbours
  EXPECT_THROW(Interval::Decimal("1.1abc"), std::invalid_argument);
  EXPECT_THROW(Interval::Decimal("[1 +/- 2]"), std::invalid_argument);
  EXPECT_THROW(Interval::Decimal(""), std::invalid_argument);
}

TEST(Interval, ElementaryFunctionsEncloseLibmAtEveryPoint) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-50, 50);
  for (int k = 0; k < 2000; ++k) {
    const double x = u(rng);
    // libm is within 1 ulp: the enclosure of the exact value meets [libm − 2ulp, libm + 2ulp].
    for (const auto& [enc, ref] : {std::pair{Sin(Interval(x)), std::sin(x)}, std::pair{Cos(Interval(x)), std::cos(x)}}) {
      EXPECT_LE(enc.lo(), std::nextafter(std::nextafter(ref, 2.0), 2.0)) << x;
      EXPECT_GE(enc.hi(), std::nextafter(std::nextafter(ref, -2.0), -2.0)) << x;
      EXPECT_LT(enc.width(), 1e-15);
    }
  }
  // Over an interval: sin on [0, 4] is [sin 4, 1].
  const Interval s = Sin(Interval::Hull(0, 4));
  EXPECT_TRUE(s.Contains(1.0));
  EXPECT_TRUE(s.Contains(std::sin(4.0)));
  EXPECT_FALSE(s.Contains(-0.8));
  // π is not a double: its enclosure lies strictly between the doubles around it.
  EXPECT_FALSE(Interval::Pi().Contains(M_PI));
  EXPECT_TRUE(Interval::Hull(M_PI, std::nextafter(M_PI, 4.0)).Contains(Interval::Pi()));
  EXPECT_LT(Sqrt(Interval(2.0)).lo(), 1.4142135623730951);
  EXPECT_GT(Sqrt(Interval(2.0)).hi(), 1.4142135623730949);
}

IntervalModel OneDof(const std::string& f, const std::string& r = "0.75", const std::string& w = "10") {
  return IntervalModel::FromDecimals({"1"}, {"1"}, {"1"}, {"1"}, "1", r, f, w);
}

TEST(Enclosure, UnforcedFlightConservesEnergyInsideItsEnclosure) {
  // f = 0: X(s) = X cos s + V sin s, so X(s)² + V(s)² = X² + V² (ω_1 = 1) for every s.
  const auto m = OneDof("0");
  for (double s : {0.1, 1.0, 7.3, 100.0}) {
    const auto e = Flight(m, Interval(0.3), {Interval(0.7)}, {Interval(-1.2)}, Interval(s));
    const Interval energy = Sqr(e.X[0]) + Sqr(e.V[0]);
    EXPECT_TRUE(energy.Contains(Sqr(Interval(0.7)) + Sqr(Interval(1.2)))) << s;
    EXPECT_LE(energy.width(), 4.5e-16);
  }
}

TEST(Enclosure, TheGradientOfAFlightMatchesFiniteDifferences) {
  const auto m = OneDof("1.1");
  const double t0 = 0.2, x = 1.0, v = 0.3, s = 0.55, h = 1e-6;
  const auto value = [&](double a, double b, double c, double d) {
    return Flight(m, Interval(a), {Interval(b)}, {Interval(c)}, Interval(d)).X[0].mid();
  };
  std::vector<Dual> u{Dual::Variable(t0, 0, 4), Dual::Variable(x, 1, 4), Dual::Variable(v, 2, 4), Dual::Variable(s, 3, 4)};
  const auto e = Flight(m, u[0], {u[1]}, {u[2]}, u[3]);
  const double fd[4] = {(value(t0 + h, x, v, s) - value(t0 - h, x, v, s)) / (2 * h),
                        (value(t0, x + h, v, s) - value(t0, x - h, v, s)) / (2 * h),
                        (value(t0, x, v + h, s) - value(t0, x, v - h, s)) / (2 * h),
                        (value(t0, x, v, s + h) - value(t0, x, v, s - h)) / (2 * h)};
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(e.X[0].d[static_cast<std::size_t>(k)].mid(), fd[k], 1e-8) << k;
  // ∂X/∂s is the velocity at the end.
  EXPECT_NEAR(e.X[0].d[3].mid(), e.V[0].v.mid(), 1e-14);
}

TEST(Enclosure, TheImpactLawReversesAndScalesTheContactVelocity) {
  const auto m = OneDof("1.1");
  const auto after = Impact(m, std::vector<Interval>{Interval(-2.0)});
  EXPECT_TRUE(after[0].Contains(1.5));  // ẋ_B⁺ = −r ẋ_B⁻, r = 0.75
  EXPECT_LT(after[0].width(), 1e-30);
}

// The second-order jet of the frequency segments (jet.hpp) against closed-form derivatives:
// f(x) = e^{−x/3} sin(x²)/(2 + cos x), f' and f'' written out by hand, at points (thin) and over an
// interval, where every derivative at every point must lie in the enclosure.
TEST(Jet2, EnclosesTheFirstAndSecondDerivativesOfAClosedForm) {
  const auto f = [](const Jet2& x) { return Exp(-(x / Jet2(3.0))) * Sin(x * x) / (Jet2(2.0) + Cos(x)); };
  const auto exact = [](double x) {
    // f = u v / w: u = e^{−x/3}, v = sin x², w = 2 + cos x.
    const double u = std::exp(-x / 3), du = -u / 3, ddu = u / 9;
    const double v = std::sin(x * x), dv = 2 * x * std::cos(x * x), ddv = 2 * std::cos(x * x) - 4 * x * x * std::sin(x * x);
    const double w = 2 + std::cos(x), dw = -std::sin(x), ddw = -std::cos(x);
    const double g = u * v, dg = du * v + u * dv, ddg = ddu * v + 2 * du * dv + u * ddv;
    const double d1 = (dg * w - g * dw) / (w * w);
    const double d2 = (ddg * w - g * ddw) / (w * w) - 2 * dw * (dg * w - g * dw) / (w * w * w);
    return std::array<double, 3>{g / w, d1, d2};
  };
  for (double x : {0.3, 1.1, 2.7}) {
    const Jet2 y = f(Jet2::Variable(Interval(x)));
    const auto e = exact(x);
    EXPECT_NEAR(y.v.mid(), e[0], 1e-13);
    EXPECT_NEAR(y.d1.mid(), e[1], 1e-12);
    EXPECT_NEAR(y.d2.mid(), e[2], 1e-11);
    EXPECT_LT(y.d2.hi() - y.d2.lo(), 1e-12);
  }
  const Jet2 over = f(Jet2::Variable(Interval::Hull(1.0, 1.01)));
  for (int k = 0; k <= 100; ++k) {
    const auto e = exact(1.0 + 0.01 * k / 100);
    EXPECT_TRUE(over.d1.Contains(e[1]) && over.d2.Contains(e[2])) << k;
  }
}

TEST(Positivity, ProvesAPositiveFunctionAndLocatesTheFailureOfAnother) {
  const Budget deadline(60, nullptr);
  // (s − 2)² ± 1e-6 on [0, 3]: positive with a narrow dip at 2, or negative within 1e-3 of 2.
  const auto slope = [](const Interval& s) { return Interval(2.0) * (s - Interval(2.0)); };
  const auto up = [](double s) { return Sqr(Interval(s) - Interval(2.0)) + Interval(1e-6); };
  const auto down = [](double s) { return Sqr(Interval(s) - Interval(2.0)) - Interval(1e-6); };
  const auto ok = ProvePositive(0.0, 3.0, 0.1, 40, deadline, up, slope);
  EXPECT_TRUE(ok.proven) << ok.reason;
  ASSERT_FALSE(ok.pieces.empty());
  EXPECT_EQ(ok.pieces.front().first, 0.0);
  EXPECT_EQ(ok.pieces.back().second, 3.0);
  for (std::size_t k = 1; k < ok.pieces.size(); ++k) EXPECT_EQ(ok.pieces[k - 1].second, ok.pieces[k].first);
  const auto bad = ProvePositive(0.0, 3.0, 0.1, 40, deadline, down, slope);
  EXPECT_FALSE(bad.proven);
  EXPECT_NEAR(bad.failed_at, 2.0, 1.1e-3);
  EXPECT_FALSE(bad.reason.empty());
}

TEST(Spectrum, StabilityIsClaimedOnlyAwayFromTheUnitCircle) {
  using M = std::vector<std::vector<Interval>>;
  const double c = 0.5 * std::cos(1.0), s = 0.5 * std::sin(1.0);
  const auto rotation = Multipliers(M{{c, -s}, {s, c}});  // 0.5 e^{±i}
  EXPECT_EQ(rotation.stability, "stable");
  const auto saddle = Multipliers(M{{2.0, 0.0}, {0.0, 0.1}});
  EXPECT_EQ(saddle.stability, "unstable");
  const auto circle = Multipliers(M{{std::cos(1.0), -std::sin(1.0)}, {std::sin(1.0), std::cos(1.0)}});
  EXPECT_EQ(circle.stability, "undecided");
  const auto wide = Multipliers(M{{Interval::Hull(0.9, 1.1), 0.0}, {0.0, 0.5}});
  EXPECT_EQ(wide.stability, "undecided");
  // 3 × 3 (Rump's method): eigenvalues 0.2, 0.5 ± 0.3i, enclosed, stable.
  const double a = 0.5, b = 0.3;
  const auto three = Multipliers(M{{0.2, 0.0, 0.0}, {0.0, a, -b}, {0.0, b, a}});
  ASSERT_TRUE(three.enclosed);
  EXPECT_EQ(three.stability, "stable");
  int found = 0;
  for (const auto& mu : three.multipliers) {
    const double re = 0.5 * (mu["re"][0].get<double>() + mu["re"][1].get<double>());
    const double im = 0.5 * (mu["im"][0].get<double>() + mu["im"][1].get<double>());
    found += std::abs(std::complex<double>(re, im) - std::complex<double>(0.2, 0)) < 1e-12 ||
             std::abs(std::complex<double>(re, std::abs(im)) - std::complex<double>(a, b)) < 1e-12;
  }
  EXPECT_EQ(found, 3);
}

// A proof's budget (budget.hpp): the stop request ends it, the time limit ends it and the runs its
// orbit search starts (they poll ProcessStopFlag(), which is the watchdog's flag inside Watch).
// The tube's pencil (docs/prove.md, "The scene as written"): M = diag(2, 1), K = [[4, -1], [-1, 1]],
// det(K − λM) = 2λ² − 6λ + 3, so λ = (3 ∓ √3)/2 and φ ∝ (1, 4 − 2λ) (first row: (4 − 2λ)φ_0 = φ_1).
TEST(Spectrum, ThePencilsEigenpairsEncloseTheClosedForm) {
  const std::vector<std::vector<Interval>> M = {{2.0, 0.0}, {0.0, 1.0}}, K = {{4.0, -1.0}, {-1.0, 1.0}};
  const double s3 = std::sqrt(3.0);
  const std::vector<double> approx = {(3 - s3) / 2, (3 + s3) / 2};
  // Starting vectors (columns), as a double eigensolver would give them.
  const std::vector<std::vector<double>> vectors = {{1.0, 1.0}, {4 - 2 * approx[0], 4 - 2 * approx[1]}};
  auto pairs = PencilEigenpairs(K, M, approx, vectors);
  ASSERT_TRUE(pairs.has_value());
  ASSERT_EQ(pairs->size(), 2u);
  std::sort(pairs->begin(), pairs->end(), [](const auto& x, const auto& y) { return x.value.re.mid() < y.value.re.mid(); });
  for (std::size_t k = 0; k < 2; ++k) {
    const Interval exact = (Interval(3.0) + Interval(k == 0 ? -1.0 : 1.0) * Sqrt(Interval(3.0))) / Interval(2.0);
    const auto& p = (*pairs)[k];
    // The exact eigenvalue lies in the enclosure, which is tight (at the working precision, 128 bits).
    const Interval d = p.value.re - exact;
    EXPECT_TRUE(d.Contains(0.0)) << d.ToString();
    EXPECT_LT(Abs(d).hi(), 1e-30) << d.ToString();
    EXPECT_TRUE(p.value.im.Contains(0.0));
    // The enclosed direction: φ_1/φ_0 = 4 − 2λ (a complex quotient of the enclosures).
    const auto& v = p.vector;
    const Interval den = Sqr(v[0].re) + Sqr(v[0].im);
    const Interval ratio = (v[1].re * v[0].re + v[1].im * v[0].im) / den - (Interval(4.0) - Interval(2.0) * exact);
    EXPECT_TRUE(ratio.Contains(0.0)) << ratio.ToString();
    EXPECT_LT(Abs(ratio).hi(), 1e-28) << ratio.ToString();
  }
  // A repeated eigenvalue (M = I, K = I) is not certified simple: no enclosure.
  const std::vector<std::vector<Interval>> I = {{1.0, 0.0}, {0.0, 1.0}};
  EXPECT_FALSE(PencilEigenpairs(I, I, {1.0, 1.0}, {{1.0, 0.0}, {0.0, 1.0}}).has_value());
  // A singular mass matrix: no enclosure.
  const std::vector<std::vector<Interval>> S = {{1.0, 1.0}, {1.0, 1.0}};
  EXPECT_FALSE(PencilEigenpairs(K, S, approx, vectors).has_value());
}

TEST(Budget, AStopRequestAndTheTimeLimitEndTheProofAndTheRunsOfItsSearch) {
  std::atomic<bool> stop{false};
  const Budget stoppable(60, &stop);
  EXPECT_FALSE(stoppable.passed());
  stop.store(true);
  EXPECT_TRUE(stoppable.passed());
  EXPECT_TRUE(stoppable.interrupted());
  EXPECT_FALSE(stoppable.expired());

  const Budget short_budget(0.05, nullptr);
  const std::atomic<bool>* outside = ProcessStopFlag();
  bool seen = false;
  const auto start = std::chrono::steady_clock::now();
  short_budget.Watch([&] {
    // As a transient polls between its events: the flag comes up once the time is over.
    const std::atomic<bool>* flag = ProcessStopFlag();
    ASSERT_NE(flag, outside);
    while (!flag->load() && std::chrono::steady_clock::now() - start < std::chrono::seconds(60))
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    seen = flag->load();
  });
  EXPECT_TRUE(seen);
  EXPECT_TRUE(short_budget.expired());
  EXPECT_FALSE(short_budget.interrupted());
  EXPECT_EQ(ProcessStopFlag(), outside);  // restored after the search
}

// Every request is bounded in memory: a positivity test that would need more pieces than a
// certificate may hold, and an orbit with more unknowns than the prover takes, end not proven.
TEST(Budget, ProofsAreBoundedInPiecesAndUnknowns) {
  const Budget budget(60, nullptr);
  const auto one = [](double) { return Interval(1.0); };
  const auto flat = [](const Interval&) { return Interval(0.0); };
  const auto wide = ProvePositive(0.0, 1e12, 1e-3, 40, budget, one, flat);
  EXPECT_FALSE(wide.proven);
  EXPECT_NE(wide.reason.find("pieces"), std::string::npos) << wide.reason;
  const auto model = IntervalModel::FromDecimals({"1"}, {"1"}, {"1"}, {"1"}, "1", "0.75", "1.1", "10");
  ImpactGuess guess;
  guess.period = 64;
  for (int j = 0; j < 64; ++j) {
    guess.times.push_back(0.1 + j * 2 * M_PI / 10);
    guess.X.push_back(Eigen::VectorXd::Constant(1, 1.0));
    guess.V.push_back(Eigen::VectorXd::Constant(1, 0.28));
  }
  ProofRequest request;
  const auto out = ProveImpactOrbit(model, guess, request, budget);  // 64 × 3 = 192 unknowns
  EXPECT_FALSE(out.proven);
  EXPECT_NE(out.reason.find("192 unknowns"), std::string::npos) << out.reason;
}

}  // namespace
}  // namespace vibro::proof
