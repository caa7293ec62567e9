// Certified event location on a stiff chain: the 1-DOF near-grazing test of
// tests/unit/exact_engine_test.cpp (a penetration window of 1e-8 with a dip of 1e-23 must be
// found) on the ten frequencies of data/scenes/chain10_stiff.toml (ω_10/ω_1 = 625), with every
// mode ringing. The long approach is stepped with the far bound (fast modes bounded by their
// amplitude, docs/performance.md); the grazing itself with the full Taylor bound.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "dynamics/exact_engine.hpp"
#include "dynamics/model_t.hpp"
#include "support.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

// Unforced flight of modal coordinates with T_B,i = 1 (x_B = Σ X_i) from (X, V) at t = 0, and
// the stop x0. All of X and x0 lie on the grid 2⁻⁷⁸ with |·| < 2⁻²⁷, so that the starting gap
// Σ X_i − x0 is exact in double whatever the order of the sum.
struct StiffGrazing {
  Eigen::VectorXd nu, X, V;
  double x0 = 0;
  LD t_min = 0;  // the designed minimum of the gap

  static double OnGrid(LD x) { return static_cast<double>(std::ldexp(std::nearbyint(std::ldexp(x, 78)), -78)); }

  // The gap as increments from the start, long double (the absolute form loses the dip).
  LD Gap(LD t) const {
    LD g = 0;
    for (Eigen::Index i = 0; i < X.size(); ++i) g += static_cast<LD>(X[i]);
    g -= static_cast<LD>(x0);  // exact
    for (Eigen::Index i = 0; i < X.size(); ++i) {
      const LD h = std::sin(static_cast<LD>(nu[i]) * t / 2);
      g += -2 * static_cast<LD>(X[i]) * h * h + static_cast<LD>(V[i]) * std::sin(static_cast<LD>(nu[i]) * t) / static_cast<LD>(nu[i]);
    }
    return g;
  }
  LD Slope(LD t) const {
    LD d = 0;
    for (Eigen::Index i = 0; i < X.size(); ++i)
      d += -static_cast<LD>(X[i]) * static_cast<LD>(nu[i]) * std::sin(static_cast<LD>(nu[i]) * t) +
           static_cast<LD>(V[i]) * std::cos(static_cast<LD>(nu[i]) * t);
    return d;
  }

  // Every mode at a minimum at t* = 3: X_i(t) = −a_i cos ν_i(t − t*), the slow mode with 2e-9, the
  // nine others sharing the curvature κ = 8e-7 that makes a dip δ a window of √(8δ/κ) (1e-8 for
  // δ = 1e-23). x0 is set from the rounded start so that the minimum lies `depth` below the stop
  // (negative: above it).
  StiffGrazing(const Eigen::VectorXd& frequencies, LD depth) : nu(frequencies) {
    const LD t_star = 3;
    const auto n = nu.size();
    X.resize(n);
    V.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const LD w = static_cast<LD>(nu[i]);
      const LD a = i == 0 ? 2e-9L : 8e-7L / 9 / (w * w);
      X[i] = OnGrid(-a * std::cos(w * t_star));
      V[i] = static_cast<double>(-a * w * std::sin(w * t_star));
    }
    // The minimum of the rounded flight near t*, by bisection on the slope.
    LD lo = t_star - 1e-3L, hi = t_star + 1e-3L;
    for (int it = 0; it < 200; ++it) {
      const LD mid = (lo + hi) / 2;
      (Slope(mid) < 0 ? lo : hi) = mid;
    }
    t_min = (lo + hi) / 2;
    x0 = 0;
    x0 = OnGrid(Gap(t_min) + depth);  // Gap with x0 = 0 is Σ X_i(t_min)
  }

  // Roots of the gap around the minimum, long double.
  bool Roots(LD& t_in, LD& t_out) const {
    if (Gap(t_min) > 0) return false;
    const auto bisect = [&](LD a, LD b) {
      const bool a_pos = Gap(a) > 0;
      for (int i = 0; i < 300; ++i) {
        const LD mid = (a + b) / 2;
        ((Gap(mid) > 0) == a_pos ? a : b) = mid;
      }
      return (a + b) / 2;
    };
    t_in = bisect(t_min - 1e-6L, t_min);
    t_out = bisect(t_min, t_min + 1e-6L);
    return true;
  }

  Scene MakeScene() const {
    Scene s;
    const auto n = nu.size();
    s.modal = ModalStructureSpec{nu, Eigen::VectorXd::Ones(n), Eigen::VectorXd::Ones(n)};
    s.restitution = 0.5;
    s.frequency = 0.2;
    s.amplitude = 0.0;
    s.stop_position = x0;
    s.run.periods = 1;
    s.run.samples_per_period = 0;
    s.initial_displacement = X;
    s.initial_velocity = V;
    return s;
  }
};

Eigen::VectorXd StiffFrequencies() {
  const auto loaded = LoadScene(std::string(VIBRO_SCENES_DIR) + "/chain10_stiff.toml", {});
  return System(loaded.scene).omega();
}

TEST(StiffChain, TheFlightIsStiffAndTheFarBoundSteersTheApproach) {
  const StiffGrazing g(StiffFrequencies(), 1e-23L);
  ASSERT_EQ(g.nu.size(), 10);
  EXPECT_GT(g.nu.maxCoeff() / g.nu.minCoeff(), 600.0);
  // At the start the gap (≈ 8e-10) is far above what the fast modes can take off (≈ 2e-10):
  // the probe offers the far bound, over a window longer than the Taylor bound's cap.
  const Scene s = g.MakeScene();
  const System sys(s);
  const detail::ModelT<double> model(sys);
  detail::ExactEngine engine(sys, model);
  const double gap0 = model.ContactDisplacement(g.X) - model.x0;
  EXPECT_EQ(gap0, static_cast<double>(g.Gap(0)));
  engine.Begin({Mode::kFree, 0.0, 0.0, g.X, g.V, gap0, detail::FlightStart::kGeneric,
                detail::StickStart::kGeneric});
  const double cap = detail::StepCap<double>(model);
  const auto p = engine.GapProbe(0.0, cap, 10.0);
  EXPECT_GT(p.far_H, 10 * cap);
  EXPECT_GT(p.far.g, 0.5 * p.jet.g);
  EXPECT_LT(p.far_M, 1e-3 * p.M);
}

TEST(StiffChain, NearGrazingPenetrationWindowOf1e8IsFound) {
  const StiffGrazing g(StiffFrequencies(), 1e-23L);
  LD t_in, t_out;
  ASSERT_TRUE(g.Roots(t_in, t_out));
  // The rounding of the start to the grid moves the dip by < 2e-24 and the window by < 10 %.
  EXPECT_NEAR(static_cast<double>(-g.Gap(g.t_min)), 1e-23, 2e-24);
  EXPECT_NEAR(static_cast<double>(t_out - t_in), 1e-8, 1e-9);
  const Outcome run = Simulate(g.MakeScene());
  ASSERT_EQ(run.result.status, RunStatus::kOk) << run.result.message;
  const auto impacts = run.log.Of(EventKind::kImpact);
  ASSERT_FALSE(impacts.empty()) << "the near-grazing impact was missed";
  // The time is as good as the gap's rounding allows: each mode's increment is evaluated to a few
  // ulps of its amplitude (measured: under one; the closed form's own accuracy, ≈ 1e-25 here over t = 3), which moves
  // the root by e_g / |g'(t_in)| (≈ 5 % of the window; the 1-DOF test starts next to its
  // minimum, where the increments are small, and reaches 1e-5 of it).
  LD e_g = 0;
  for (Eigen::Index i = 0; i < g.X.size(); ++i)
    e_g += 4 * std::numeric_limits<double>::epsilon() *
           (std::abs(static_cast<LD>(g.X[i])) + std::abs(static_cast<LD>(g.V[i]) / static_cast<LD>(g.nu[i])));
  const double tol = static_cast<double>(e_g / std::abs(g.Slope(t_in)));
  EXPECT_LT(tol, 0.1 * static_cast<double>(t_out - t_in));
  EXPECT_NEAR(impacts.front().t, static_cast<double>(t_in), tol);
  EXPECT_LT(impacts.front().v_before, 0.0);
}

TEST(StiffChain, NearGrazingWithoutPenetrationIsNoImpact) {
  // The same flight with its minimum 1e-23 above the stop.
  const StiffGrazing g(StiffFrequencies(), -1e-23L);
  LD t_in, t_out;
  ASSERT_FALSE(g.Roots(t_in, t_out));
  const Outcome run = Simulate(g.MakeScene());
  ASSERT_EQ(run.result.status, RunStatus::kOk) << run.result.message;
  for (const auto& e : run.log.Of(EventKind::kImpact))
    EXPECT_GT(e.t, static_cast<double>(g.t_min) + 0.01);
}

}  // namespace
}  // namespace vibro::test
