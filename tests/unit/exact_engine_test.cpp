// Exact engine: the oscillator kernel against textbook closed forms (long double), event location
// at a near-grazing crossing, and the physical invariants of the automaton.
#include <cmath>

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <memory>
#include <vector>

#include "dynamics/exact_engine.hpp"
#include "dynamics/model_t.hpp"
#include "dynamics/oscillator.hpp"
#include "support.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

using detail::Flow;
using detail::Oscillator;

// Textbook undamped solution (docs/model.md §2, absolute form), long double, ν ≠ ω.
void Textbook(LD nu, LD w, LD F, LD phase, LD q0, LD v0, LD s, LD& q, LD& v) {
  const LD U0 = F * std::sin(phase) / (nu * nu - w * w), dU0 = F * w * std::cos(phase) / (nu * nu - w * w);
  const LD a = q0 - U0, b = (v0 - dU0) / nu;
  q = F * std::sin(phase + w * s) / (nu * nu - w * w) + a * std::cos(nu * s) + b * std::sin(nu * s);
  v = F * w * std::cos(phase + w * s) / (nu * nu - w * w) - a * nu * std::sin(nu * s) +
      b * nu * std::cos(nu * s);
}

TEST(Oscillator, UndampedMatchesTextbookFormula) {
  for (double nu : {0.3, 1.0, 2.7})
    for (double s : {1e-6, 0.01, 0.7, 5.0, 40.0}) {
      const Oscillator o{nu, 0.0, 1.3};
      const auto st = Flow(o, 1.9, 0.4, 0.2, -0.5, s);
      LD q, v;
      Textbook(nu, 1.9, 1.3, 0.4, 0.2, -0.5, s, q, v);
      EXPECT_NEAR(st.dq, static_cast<double>(q - 0.2L), 1e-14 * (1 + s));
      EXPECT_NEAR(st.v, static_cast<double>(v), 1e-14 * (1 + s));
    }
}

TEST(Oscillator, ExactResonanceIsTheSecularLimit) {
  // docs/model.md §8: at ν = ω the forced response from rest is F[sin ωs cos φ − ωs cos(φ + ωs)]/(2ω²).
  const double w = 1.7, F = 0.9, phase = 0.3;
  for (double s : {1e-5, 0.5, 3.0, 30.0}) {
    const auto st = Flow({w, 0.0, F}, w, phase, 0.0, 0.0, s);
    const LD expected = F * (std::sin(w * s) * std::cos(phase) - w * s * std::cos(phase + w * s)) /
                        (2.0L * w * w);
    EXPECT_NEAR(st.dq, static_cast<double>(expected), 1e-14 * (1 + s * s));
    // Near resonance the result is continuous (no cancellation blow-up).
    const auto near = Flow({w * (1 + 1e-12), 0.0, F}, w, phase, 0.0, 0.0, s);
    EXPECT_NEAR(near.dq, st.dq, 1e-10 * (1 + s * s));
    const auto near9 = Flow({w * (1 + 1e-9), 0.0, F}, w, phase, 0.0, 0.0, s);
    LD q, v;
    Textbook(w * (1 + 1e-9L), w, F, phase, 0, 0, s, q, v);
    EXPECT_NEAR(near9.dq, static_cast<double>(q), 1e-6 * (1 + s * s));  // long double cancels too
  }
}

TEST(Oscillator, DampedMatchesTextbookFormula) {
  const double nu = 1.3, z = 0.05, w = 0.8, F = 0.7, phase = 1.1, q0 = 0.4, v0 = -0.2;
  const LD den = (nu * nu - w * w) * (nu * nu - w * w) + 4.0L * z * z * nu * nu * w * w;
  const LD P = F * (nu * nu - w * w) / den, Q = -F * 2.0L * z * nu * w / den;
  const LD A = q0 - (P * std::sin(phase) + Q * std::cos(phase));
  const LD B = v0 - w * (P * std::cos(phase) - Q * std::sin(phase));
  const LD a = z * nu, nd = nu * std::sqrt(1.0L - z * z);
  for (double s : {1e-4, 0.3, 2.0, 25.0}) {
    const LD q = P * std::sin(phase + w * s) + Q * std::cos(phase + w * s) +
                 std::exp(-a * s) * (A * std::cos(nd * s) + (B + a * A) / nd * std::sin(nd * s));
    const auto st = Flow({nu, z, F}, w, phase, q0, v0, s);
    EXPECT_NEAR(st.dq, static_cast<double>(q - q0), 1e-14);
    // Velocity by a centred difference of the long double solution.
    const LD h = 1e-6L;
    const auto qa = [&](LD t) {
      return P * std::sin(phase + w * t) + Q * std::cos(phase + w * t) +
             std::exp(-a * t) * (A * std::cos(nd * t) + (B + a * A) / nd * std::sin(nd * t));
    };
    EXPECT_NEAR(st.v, static_cast<double>((qa(s + h) - qa(s - h)) / (2 * h)), 1e-8);
  }
}

// Unforced 1-DOF near a clearance stop x0 < 0: x(t) = X0 cos t + v0 sin t = A cos(t − θ) reaches
// its minimum −A just after the start; with A = |x0| / cos(w/2) it stays below x0 for a time w.
// The gap is tiny (X0 − x0 = 2⁻⁴¹) so that the dip, 1e-23 deep, is far above the rounding of the
// increments from the start.
struct Grazing {
  double x0 = -std::ldexp(1.0, -20);  // ≈ −9.5e−7
  double X0, v0;
  // depth_factor = 1/cos(w/2) − 1 > 0 penetrates, < 0 stays above the stop.
  explicit Grazing(LD depth_factor) {
    X0 = x0 + std::ldexp(1.0, -41);
    const LD A = -static_cast<LD>(x0) * (1 + depth_factor), aX = -static_cast<LD>(X0);
    v0 = static_cast<double>(-std::sqrt((A - aX) * (A + aX)));
  }
  static LD Penetrating(LD window) { return 1 / std::cos(window / 2) - 1; }
  // Roots of x(t) = x0 in long double.
  bool Roots(LD& t_in, LD& t_out) const {
    // As increments from the start (x(t) − x0 = (X0 − x0) + X0 (cos t − 1) + v0 sin t): the
    // absolute form loses the 1e-23 dip in the rounding of X0 cos t even in long double.
    const auto g = [&](LD t) {
      const LD h = std::sin(t / 2);
      return static_cast<LD>(X0 - x0) - 2 * X0 * h * h + v0 * std::sin(t);
    };
    const LD tmin = std::atan2(static_cast<LD>(v0), static_cast<LD>(X0)) + M_PIl;  // x' = 0
    const LD t_star = std::fmod(tmin, 2 * M_PIl);
    if (g(t_star) > 0) return false;
    const auto bisect = [&](LD lo, LD hi) {
      const bool lo_pos = g(lo) > 0;
      for (int i = 0; i < 300; ++i) {
        const LD mid = 0.5L * (lo + hi);
        ((g(mid) > 0) == lo_pos ? lo : hi) = mid;
      }
      return 0.5L * (lo + hi);
    };
    t_in = bisect(0, t_star);
    t_out = bisect(t_star, 2 * t_star);
    return true;
  }
};

Scene GrazingScene(const Grazing& g) {
  Scene s = OneDof(0.5, 1.0, 0.0, g.x0, 1);
  s.initial_displacement = Eigen::VectorXd::Constant(1, g.X0);
  s.initial_velocity = Eigen::VectorXd::Constant(1, g.v0);
  return s;
}

TEST(ExactEngine, NearGrazingPenetrationWindowOf1e8IsFound) {
  const Grazing g(Grazing::Penetrating(1e-8L));
  LD t_in, t_out;
  ASSERT_TRUE(g.Roots(t_in, t_out));
  EXPECT_NEAR(static_cast<double>(t_out - t_in), 1e-8, 1e-10);
  const Outcome run = Simulate(GrazingScene(g));
  ASSERT_EQ(run.result.status, RunStatus::kOk);
  const auto impacts = run.log.Of(EventKind::kImpact);
  ASSERT_FALSE(impacts.empty()) << "the near-grazing impact was missed";
  EXPECT_NEAR(impacts.front().t, static_cast<double>(t_in), 1e-5 * static_cast<double>(t_out - t_in));
  EXPECT_LT(impacts.front().v_before, 0.0);
}

TEST(ExactEngine, NearGrazingWithoutPenetrationIsNoImpact) {
  // Same flight, with its minimum 1e-14·|x0| ≈ 1e-20 above the stop.
  const Grazing g(-1e-14L);
  LD t_in, t_out;
  ASSERT_FALSE(g.Roots(t_in, t_out));
  const Outcome run = Simulate(GrazingScene(g));
  ASSERT_EQ(run.result.status, RunStatus::kOk);
  const double t_min = static_cast<double>(std::atan2(static_cast<LD>(g.v0), static_cast<LD>(g.X0)) + M_PIl);
  for (const auto& e : run.log.Of(EventKind::kImpact)) EXPECT_GT(e.t, t_min + 1.0);
}

double Energy(const System& sys, const Eigen::VectorXd& X, const Eigen::VectorXd& V) {
  // Modal masses 1/T_B,i (docs/model.md §3): E = ½ Σ (V_i² + ω_i² X_i²)/T_B,i.
  double e = 0;
  for (int i = 0; i < sys.dof(); ++i)
    e += 0.5 * (V[i] * V[i] + sys.omega()[i] * sys.omega()[i] * X[i] * X[i]) / sys.contact()[i];
  return e;
}

TEST(ExactEngine, EnergyNeverRisesUnforced) {
  for (double r : {0.0, 0.5, 0.9}) {
    for (int n : {2, 3}) {
      SCOPED_TRACE(testing::Message() << "r = " << r << ", n = " << n);
      Scene s = Chain(n, 0.2, r, 1.0, 0.0);
      s.initial_displacement = Eigen::VectorXd::LinSpaced(n, 1.5, 2.5);
      s.initial_velocity = Eigen::VectorXd::Zero(n);
      s.run.periods = 30;
      s.run.samples_per_period = 50;
      const System sys(s);
      const Outcome run = Simulate(s);
      ASSERT_EQ(run.result.status, RunStatus::kOk);
      ASSERT_GT(run.result.counts.impacts, 3);
      double prev = Energy(sys, run.log.samples.front().X, run.log.samples.front().V);
      for (const auto& row : run.log.samples) {
        const double e = Energy(sys, row.X, row.V);
        EXPECT_LE(e, prev * (1 + 1e-12));
        prev = e;
      }
      EXPECT_LT(prev, Energy(sys, run.log.samples.front().X, run.log.samples.front().V));
    }
  }
}

TEST(ExactEngine, StickingInvariantsHold) {
  // On the stop: x_B = x0, ẋ_B = 0 and R ≥ 0 at every dense sample (2-DOF with chattering and
  // 3-DOF plastic).
  for (const auto& [n, r, w, f] : {std::tuple{2, 0.5, 0.8, 0.8}, std::tuple{3, 0.0, 0.8, 1.0}}) {
    Scene s = Chain(n, 1.0, r, w, f);
    s.run.periods = 200;
    s.run.samples_per_period = 200;
    const System sys(s);
    const Outcome run = Simulate(s);
    ASSERT_EQ(run.attractor.kind, "sticking-periodic");
    int stuck = 0;
    for (const auto& row : run.log.samples) {
      EXPECT_GE(row.x_B, sys.stop() - 1e-12);  // never inside the stop
      if (row.mode != Mode::kSticking) continue;
      ++stuck;
      const double phase = sys.frequency() * row.t;
      EXPECT_NEAR(row.x_B, sys.stop(), 1e-13);
      EXPECT_NEAR(sys.ContactVelocity(row.V), 0.0, 1e-13);
      EXPECT_GE(sys.Reaction(row.X, row.V, phase), -1e-12);
    }
    EXPECT_GT(stuck, 100);
  }
}

TEST(ExactEngine, ExactResonanceRuns) {
  // ω = ω_1 (clearance, r = 0.5): the secular free flight is handled; the motion is bounded by
  // the stop and settles.
  Scene s = OneDof(0.5, 1.0, 0.5, -1.0, 200);
  const Outcome run = Simulate(s);
  ASSERT_EQ(run.result.status, RunStatus::kOk);
  EXPECT_GT(run.result.counts.impacts, 10);
  for (const auto& e : run.log.events) EXPECT_TRUE(std::isfinite(e.t));
}

// The state at a point the last probe visited reuses that probe's flows (docs/performance.md, "The
// state at the root"); it must be the closed form evaluated afresh, bit for bit, at that point and
// nowhere else: after a probe of another contact (whose gap is not the start contact's), at the
// next double, at −0 against +0, and after a new segment begins.
TEST(ExactEngine, StateAtAProbedPointIsTheFreshClosedForm) {
  const auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  for (const char* file : {"contacts_chain2.toml", "fig08_preload.toml", "chain3.toml"}) {
    SCOPED_TRACE(file);
    const auto loaded = LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, {});
    const System sys(loaded.scene);
    const detail::ModelT<double> model(sys);
    const int n = model.dof(), m = sys.contact_count();
    Eigen::VectorXd X(n), V(n), X2(n), V2(n);
    for (int i = 0; i < n; ++i) {
      X[i] = 0.3 - 0.17 * i;
      V[i] = -0.4 + 0.11 * i;
      X2[i] = -0.2 + 0.05 * i;
      V2[i] = 0.7 - 0.3 * i;
    }
    std::vector<double> gaps(static_cast<size_t>(m)), gaps2(static_cast<size_t>(m));
    for (int j = 0; j < m; ++j) {
      gaps[static_cast<size_t>(j)] = 0.25 + 0.1 * j;
      gaps2[static_cast<size_t>(j)] = 0.5 + 0.2 * j;
    }
    const auto begin = [&](detail::ExactEngine& e, const Eigen::VectorXd& x, const Eigen::VectorXd& v,
                           const std::vector<double>& g, double phase) {
      detail::SegmentStartT<double> st{Mode::kFree, phase, 0.0, x, v, g[0], detail::FlightStart::kGeneric,
                                       detail::StickStart::kGeneric};
      if (m > 1) st.gaps = &g;
      e.Begin(st);
    };
    const double cap = detail::StepCap<double>(model);
    for (const double sigma : {0.0, -0.0, 1e-9, 0.3141, 1.7}) {
      detail::ExactEngine fresh(sys, model);
      begin(fresh, X, V, gaps, 0.9);
      Eigen::VectorXd Xf, Vf;
      const double gf = fresh.EvaluateWithGap(sigma, Xf, Vf);
      for (int j = 0; j < m; ++j) {
        SCOPED_TRACE(j);
        detail::ExactEngine e(sys, model);
        begin(e, X, V, gaps, 0.9);
        (void)e.GapProbe(j, sigma, cap, 10.0);
        Eigen::VectorXd Xe, Ve;
        EXPECT_EQ(bits(e.EvaluateWithGap(sigma, Xe, Ve)), bits(gf));
        for (int i = 0; i < n; ++i) {
          EXPECT_EQ(bits(Xe[i]), bits(Xf[i]));
          EXPECT_EQ(bits(Ve[i]), bits(Vf[i]));
        }
        (void)e.GapProbe(j, sigma, cap, 10.0);
        e.Evaluate(sigma, Xe, Ve);
        for (int i = 0; i < n; ++i) {
          EXPECT_EQ(bits(Xe[i]), bits(Xf[i]));
          EXPECT_EQ(bits(Ve[i]), bits(Vf[i]));
        }
        // The next double, and the other signed zero: the fresh closed form there.
        const double other = sigma == 0.0 ? -sigma : std::nextafter(sigma, 10.0);
        (void)e.GapProbe(j, sigma, cap, 10.0);
        Eigen::VectorXd Xo, Vo;
        const double go = fresh.EvaluateWithGap(other, Xo, Vo);
        EXPECT_EQ(bits(e.EvaluateWithGap(other, Xe, Ve)), bits(go));
        for (int i = 0; i < n; ++i) EXPECT_EQ(bits(Ve[i]), bits(Vo[i]));
        // A new segment: its own start, not the probe's.
        (void)e.GapProbe(j, sigma, cap, 10.0);
        begin(e, X2, V2, gaps2, 2.1);
        detail::ExactEngine fresh2(sys, model);
        begin(fresh2, X2, V2, gaps2, 2.1);
        Eigen::VectorXd Xn, Vn;
        EXPECT_EQ(bits(e.EvaluateWithGap(sigma, Xe, Ve)), bits(fresh2.EvaluateWithGap(sigma, Xn, Vn)));
        for (int i = 0; i < n; ++i) {
          EXPECT_EQ(bits(Xe[i]), bits(Xn[i]));
          EXPECT_EQ(bits(Ve[i]), bits(Vn[i]));
        }
      }
    }
  }
}

}  // namespace
}  // namespace vibro::test
