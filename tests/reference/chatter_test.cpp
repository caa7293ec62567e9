// Chattering treatments (MODEL §5.4) against an exactly summable impact sequence.
//
// Oracle: the unforced 1-DOF oscillator (ω_1 = 1, f = 0) leaving the stop x0 = 1 with speed v
// returns after Δ(v) = 2 atan(v/x0) with speed v (x = x0 cos s + v sin s), then rebounds with r v.
// Starting with speed v_0 = 1 on the stop, the impacts accumulate at
//     t_∞ = Σ_{j≥0} 2 atan(r^j v_0 / x0)
// and the body then rests on the stop for ever (R = x0 > 0).
#include <cmath>

#include <gtest/gtest.h>

#include "support.hpp"

namespace vibro::test {
namespace {

Scene Bouncing(double r, ChatterTreatment treatment, double chatter_switch) {
  Scene s = OneDof(r, 1.0, 0.0, 1.0, 20);
  s.initial_displacement = Eigen::VectorXd::Constant(1, 1.0);
  s.initial_velocity = Eigen::VectorXd::Constant(1, 1.0);
  s.run.chatter = treatment;
  s.run.chatter_switch = chatter_switch;
  return s;
}

LD AccumulationTime(LD r) {
  LD t = 0, v = 1;
  for (int j = 0; j < 100000 && v > 1e-30L; ++j, v *= r) t += 2 * std::atan(v);
  return t;
}

double StickTime(const Outcome& run) {
  const auto sticks = run.log.Of(EventKind::kStick);
  EXPECT_EQ(sticks.size(), 1u);
  return sticks.empty() ? std::nan("") : sticks.front().t;
}

TEST(Chatter, AccumulationPointIsExact) {
  for (double r : {0.3, 0.75, 0.95}) {
    SCOPED_TRACE(r);
    const Outcome run = Simulate(Bouncing(r, ChatterTreatment::kAccumulation, 1e-6));
    ASSERT_EQ(run.result.status, RunStatus::kOk);
    EXPECT_EQ(run.log.Of(EventKind::kAccumulation).size(), 1u);
    EXPECT_NEAR(StickTime(run), static_cast<double>(AccumulationTime(r)), 1e-13);
    EXPECT_EQ(run.attractor.kind, "permanent-contact");
    // The number of impacts followed: ln(switch)/ln(r) (+ the first).
    const double expected = std::log(1e-6) / std::log(r);
    EXPECT_NEAR(static_cast<double>(run.result.counts.impacts), expected, 2.0);
  }
}

TEST(Chatter, AccumulationErrorIsSecondOrderThresholdFirstOrder) {
  // Halving the switch velocity divides the error of "accumulation" by ≥ 4 (O(v²); here the
  // sequence is symmetric and the error is even O(v³)) and that of "threshold" by 2 (O(v)).
  const double r = 0.5;
  const double exact = static_cast<double>(AccumulationTime(r));
  for (double eps : {2e-3, 1e-3}) {
    const double acc1 = std::abs(StickTime(Simulate(Bouncing(r, ChatterTreatment::kAccumulation, eps))) - exact);
    const double acc2 = std::abs(StickTime(Simulate(Bouncing(r, ChatterTreatment::kAccumulation, eps / 2))) - exact);
    const double thr1 = std::abs(StickTime(Simulate(Bouncing(r, ChatterTreatment::kThreshold, eps))) - exact);
    const double thr2 = std::abs(StickTime(Simulate(Bouncing(r, ChatterTreatment::kThreshold, eps / 2))) - exact);
    SCOPED_TRACE(testing::Message() << "eps " << eps << ": accumulation " << acc1 << " → " << acc2
                                    << ", threshold " << thr1 << " → " << thr2);
    EXPECT_GT(acc1, 0.0);
    EXPECT_GE(acc1 / acc2, 3.9);
    EXPECT_GT(thr1 / thr2, 1.4);  // impacts are discrete: v at the switch jumps by factors of r
    EXPECT_LT(thr1 / thr2, 2.9);
    EXPECT_LT(acc1, 1e-3 * thr1);
  }
}

TEST(Chatter, NoneStopsWithAClearStatusInsteadOfStalling) {
  const Outcome run = Simulate(Bouncing(0.75, ChatterTreatment::kNone, 1e-6));
  EXPECT_EQ(run.result.status, RunStatus::kNumericalFailure);
  EXPECT_NE(run.result.message.find("accumulation"), std::string::npos) << run.result.message;
  // Everything followed so far is kept: the impacts converge on t_∞ from below.
  const auto impacts = run.log.Of(EventKind::kImpact);
  ASSERT_GT(impacts.size(), 50u);
  const double exact = static_cast<double>(AccumulationTime(0.75));
  EXPECT_LT(impacts.back().t, exact + 1e-12);
  EXPECT_NEAR(impacts.back().t, exact, 1e-9);
}

TEST(Chatter, ElasticImpactsNeverAccumulate) {
  // r = 1: energy is conserved, the flights all last π/2; no accumulation is ever predicted.
  const Outcome run = Simulate(Bouncing(1.0, ChatterTreatment::kAccumulation, 1e-6));
  ASSERT_EQ(run.result.status, RunStatus::kOk);
  EXPECT_EQ(run.result.counts.accumulations, 0);
  const auto impacts = run.log.Of(EventKind::kImpact);
  ASSERT_GT(impacts.size(), 10u);
  for (size_t i = 0; i < impacts.size(); ++i) {
    EXPECT_NEAR(impacts[i].t, static_cast<double>(i + 1) * M_PI / 2.0, 1e-12 * (1.0 + impacts[i].t));
    EXPECT_NEAR(impacts[i].v_before, -1.0, 1e-12);
  }
}

}  // namespace
}  // namespace vibro::test
