// The extremes (ctest label `extremes`): where numerics are hardest, every run gives a result checked
// against an independent truth (closed form, scaling law, the other engine) or a clear status —
// never a silent wrong answer, a hang or a crash.
#include <cmath>

#include <gtest/gtest.h>

#include "support.hpp"

namespace vibro::test {
namespace {

Scene Cvode(Scene s, double rtol = 1e-11) {
  s.run.engine = Engine::kCvode;
  s.run.rtol = rtol;
  s.run.atol = rtol * 1e-2;
  return s;
}

// Stick and release times agree between two runs (the flights' ends), up to `tol`.
void ExpectSameMilestones(const Outcome& a, const Outcome& b, double tol, size_t at_most = 40) {
  const auto ms = [](const Outcome& o) {
    std::vector<double> t;
    for (const auto& e : o.log.events)
      if (e.kind == EventKind::kStick || e.kind == EventKind::kRelease) t.push_back(e.t);
    return t;
  };
  const auto x = ms(a), y = ms(b);
  const size_t n = std::min({x.size(), y.size(), at_most});
  ASSERT_GE(n, std::min<size_t>(at_most, 3));
  for (size_t i = 0; i < n; ++i) EXPECT_NEAR(x[i], y[i], tol) << i;
}

TEST(Extremes, RestitutionTinyIsContinuousWithPlastic) {
  const Outcome r0 = Simulate(OneDof(0.0, 2.8, 1.2, 1.0, 30));
  const Outcome r9 = Simulate(OneDof(1e-9, 2.8, 1.2, 1.0, 30));
  ASSERT_EQ(r9.result.status, RunStatus::kOk);
  EXPECT_EQ(r9.result.counts.accumulations, 30);  // one rebound of 1e-9, then accumulation
  EXPECT_NEAR(*r9.attractor.sticking_fraction, *r0.attractor.sticking_fraction, 1e-8);
}

TEST(Extremes, RestitutionNearOne) {
  // r = 0.99: hundreds of impacts a sequence before the prediction is within its target (the
  // tail shrinks by 1 % an impact); CVODE agrees.
  const Scene s = OneDof(0.99, 2.8, 1.001, 1.0, 10);
  const Outcome ex = Simulate(s);
  ASSERT_EQ(ex.result.status, RunStatus::kOk);
  EXPECT_EQ(ex.result.counts.accumulations, 10);
  EXPECT_GT(ex.result.counts.impacts, 10 * 300);
  const Outcome cv = Simulate(Cvode(s));
  ASSERT_EQ(cv.result.status, RunStatus::kOk) << cv.result.message;
  EXPECT_NEAR(*ex.attractor.sticking_fraction, *cv.attractor.sticking_fraction, 1e-4);
  // r = 0.99 and 0.999 on the exactly summable sequence of tests/reference/chatter_test.cpp
  // (unforced, leaving x0 = 1 at unit speed): t∞ = Σ 2 atan(rʲ).
  for (double r : {0.99, 0.999}) {
    Scene b = OneDof(r, 1.0, 0.0, 1.0, 1000);
    b.initial_displacement = Eigen::VectorXd::Constant(1, 1.0);
    b.initial_velocity = Eigen::VectorXd::Constant(1, 1.0);
    const Outcome o = Simulate(b);
    ASSERT_EQ(o.result.status, RunStatus::kOk);
    LD t = 0, v = 1;
    for (int j = 0; j < 10000000 && v > 1e-30L; ++j, v *= r) t += 2 * std::atan(v);
    const auto sticks = o.log.Of(EventKind::kStick);
    ASSERT_EQ(sticks.size(), 1u) << r;
    EXPECT_NEAR(sticks[0].t, static_cast<double>(t), 1e-9 * static_cast<double>(t)) << r;
  }
}

TEST(Extremes, ElasticImpactsAgreeWithCvodeAndNeverAccumulate) {
  const Scene s = OneDof(1.0, 2.8, 1.2, 1.0, 10);
  const Outcome ex = Simulate(s), cv = Simulate(Cvode(s, 1e-12));
  EXPECT_EQ(ex.result.counts.accumulations, 0);
  EXPECT_EQ(cv.result.counts.accumulations, 0);
  const auto a = ex.log.Of(EventKind::kImpact), b = cv.log.Of(EventKind::kImpact);
  ASSERT_GT(a.size(), 10u);
  for (size_t i = 0; i < 10; ++i) EXPECT_NEAR(a[i].t, b[i].t, 1e-6) << i;
}

TEST(Extremes, ForcingJustAbovePreload) {
  // f = 1 + 1e-9 (r = 0): a flight of 6e-5 that starts with a triple zero and lands almost
  // tangentially. The paper's (34): t'_0 − t'_1 = 4√(f² − 1)/ω (1 + O(√(f² − 1))), so
  // 1 − SP = 4√(f² − 1)/2π to a relative 1e-4.
  const double w = 2.8, f = 1.0 + 1e-9;
  const Outcome o = Simulate(OneDof(0.0, w, f, 1.0, 10));
  ASSERT_EQ(o.result.status, RunStatus::kOk);
  ASSERT_TRUE(o.attractor.sticking_fraction.has_value());
  const double flight = 1.0 - *o.attractor.sticking_fraction;
  EXPECT_NEAR(flight, 4 * std::sqrt(f * f - 1) / (2 * M_PI), 1e-4 * flight);
  EXPECT_EQ(o.attractor.period, 1);
}

TEST(Extremes, ForcingOneBillionthAroundTheFreeFlightLimit) {
  // r = 0, ω = 2.8: f_ff(ω, 1) = √(1 + ω² tan²(π/ω)) (docs/model.md §6.3). 1e-9 below it the period-1
  // sticking orbit sticks for a fraction 3e-11 of the period, as the closed form of §6.2 says;
  // 1e-9 above it the landing comes after the release phase, R < 0 there, and the motion is the
  // one-impact orbit without sticking.
  const double w = 2.8, fff = std::sqrt(1.0 + w * w * std::pow(std::tan(M_PI / w), 2));
  {
    const double f = fff - 1e-9;
    const Outcome o = Simulate(OneDof(0.0, w, f, 1.0, 300));
    ASSERT_EQ(o.result.status, RunStatus::kOk);
    ASSERT_EQ(o.attractor.kind, "sticking-periodic");
    const LD t1 = ReleaseTime(w, f);
    const LD t0 = Flight1{w, f, t1, 1, 0}.Landing(1);
    const double sp = static_cast<double>(1 - w * (t0 - t1) / (2 * M_PIl));
    ASSERT_GT(sp, 0);
    EXPECT_NEAR(*o.attractor.sticking_fraction, sp, 1e-13) << "closed form " << sp;
  }
  {
    const Outcome o = Simulate(OneDof(0.0, w, fff + 1e-9, 1.0, 300));
    ASSERT_EQ(o.result.status, RunStatus::kOk);
    EXPECT_EQ(o.attractor.kind, "impact-periodic");
    EXPECT_EQ(o.attractor.period, 1);
    EXPECT_EQ(o.attractor.impacts_per_period, 1);
  }
}

TEST(Extremes, ImpactAtTenToTheMinusTenIsAnImpact) {
  // Unforced 1-DOF oscillator, stop at x0 = 0: from X0 = 6e-11, v0 = −8e-11 it reaches the stop
  // with speed √(X0² + v0²) = 1e-10 (exact energy: the data are exact to 1e-16 relative).
  Scene s = OneDof(0.5, 1.0, 0.0, 0.0, 1);
  s.initial_displacement = Eigen::VectorXd::Constant(1, 6e-11);
  s.initial_velocity = Eigen::VectorXd::Constant(1, -8e-11);
  const Outcome o = Simulate(s);
  ASSERT_EQ(o.result.status, RunStatus::kOk);
  const auto impacts = o.log.Of(EventKind::kImpact);
  ASSERT_FALSE(impacts.empty());
  EXPECT_EQ(o.log.Of(EventKind::kGrazing).size(), 0u);
  EXPECT_NEAR(impacts.front().v_before, -1e-10, 1e-22);
  EXPECT_NEAR(impacts.front().v_after, 0.5e-10, 1e-22);
  EXPECT_NEAR(impacts.front().t, std::atan2(6.0, 8.0), 1e-12);  // X0 cos t + v0 sin t = 0
}

TEST(Extremes, ForcingAtAndNearAModalPulsation) {
  // ω = ω_1 exactly (secular free flight), and 1e-12 away: continuous, and CVODE agrees.
  const Outcome at = Simulate(OneDof(0.5, 1.0, 0.5, -1.0, 40));
  const Outcome near = Simulate(OneDof(0.5, 1.0 + 1e-12, 0.5, -1.0, 40));
  const Outcome cv = Simulate(Cvode(OneDof(0.5, 1.0, 0.5, -1.0, 40)));
  ASSERT_EQ(at.result.status, RunStatus::kOk);
  const auto a = at.log.Of(EventKind::kImpact), b = near.log.Of(EventKind::kImpact),
             c = cv.log.Of(EventKind::kImpact);
  ASSERT_GT(a.size(), 5u);
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_NEAR(a[i].t, b[i].t, 1e-9) << i;
    EXPECT_NEAR(a[i].t, c[i].t, 1e-7) << i;
  }
}

TEST(Extremes, ForcingAtAndNearTheConstrainedPulsation) {
  // 2-DOF chain, ω = ω'_1 = √2 (resonance of the stuck structure) and 1e-12 away.
  for (double dw : {0.0, 1e-12}) {
    SCOPED_TRACE(dw);
    // The first sticking phase, from the static equilibrium, is driven at the resonance of the
    // stuck structure (secular growth of the constrained mode until the release).
    Scene s = Chain(2, 1.0, 0.5, std::sqrt(2.0) * (1 + dw), 0.6);
    s.run.periods = 3;
    const Outcome ex = Simulate(s), cv = Simulate(Cvode(s, 1e-12));
    ASSERT_EQ(ex.result.status, RunStatus::kOk);
    ASSERT_EQ(cv.result.status, RunStatus::kOk);
    ExpectSameMilestones(ex, cv, 1e-7, 2);
  }
}

TEST(Extremes, StiffModalSetOfRatioTenThousand) {
  // Two masses joined by a spring 1e8 times stiffer than the ground spring: ω_2/ω_1 ≈ 2e4.
  Scene s = Chain(2, 1.0, 0.5, 0.5, 1.5);
  s.physical->stiffness << 1.0 + 1e8, -1e8, -1e8, 1e8;
  s.run.periods = 1;
  const System sys(s);
  EXPECT_GT(sys.omega()[1] / sys.omega()[0], 1e4);
  const Outcome ex = Simulate(s);
  ASSERT_EQ(ex.result.status, RunStatus::kOk);
  // The first release (from the static equilibrium) against CVODE (Adams, rtol 1e-12, whose own
  // scatter on this set is ~1e-6); the later chattering motion is sensitive.
  Scene c = Cvode(s, 1e-12);
  c.run.atol = 1e-14;
  const Outcome cv = Simulate(c);
  ASSERT_EQ(cv.result.status, RunStatus::kOk) << cv.result.message;
  ExpectSameMilestones(ex, cv, 1e-5, 2);
  EXPECT_GT(ex.result.counts.impacts, 3);
}

TEST(Extremes, PaperFig6MagnitudesOnTheTwoDofChain) {
  // (r, ω, f, x0) = (0.75, 148, 28.5, 3.2e-4) of the paper's rising-bifurcation figure.
  Scene s = Chain(2, 3.2e-4, 0.75, 148.0, 28.5);
  s.run.periods = 30;
  const Outcome ex = Simulate(s), cv = Simulate(Cvode(s));
  ASSERT_EQ(ex.result.status, RunStatus::kOk);
  ASSERT_EQ(cv.result.status, RunStatus::kOk) << cv.result.message;
  EXPECT_EQ(ex.attractor.kind, cv.attractor.kind);
  if (ex.attractor.sticking_fraction && cv.attractor.sticking_fraction) {
    EXPECT_NEAR(*ex.attractor.sticking_fraction, *cv.attractor.sticking_fraction, 1e-4);
  }
}

TEST(Extremes, MillionPeriodsStayExactlyPeriodic) {
  // 10⁶ forcing periods of the q = 2 orbit of Fig. 4: the last release has the same phase, to the
  // bit, as the first (the clock keeps whole periods apart from the offset).
  const Outcome o = Simulate(OneDof(0.0, 10.0, 6.0, 1.0, 1000000));
  ASSERT_EQ(o.result.status, RunStatus::kOk);
  EXPECT_EQ(o.result.end.period, 1000000);
  const auto rel = o.log.Of(EventKind::kRelease);
  ASSERT_GT(rel.size(), 400000u);
  EXPECT_EQ(rel.back().clock.offset, rel[1].clock.offset);
  EXPECT_EQ(*o.attractor.period, 2);
}

TEST(Extremes, HugeAndTinyStopPositionsFollowTheScalingLaw) {
  // docs/model.md §1.4: X → X/|x0|, f → f/|x0| maps any x0 to ±1; the phases are unchanged.
  for (double sign : {1.0, -1.0}) {
    // Preload: Fig. 8 (r = 0.75, chattering); clearance: Fig. 11 (r = 0).
    const double f = sign > 0 ? 1.2 : 10.0, w = sign > 0 ? 2.8 : 1.4, r = sign > 0 ? 0.75 : 0.0;
    const Outcome unit = Simulate(OneDof(r, w, f, sign, 30));
    ASSERT_EQ(unit.attractor.kind, "sticking-periodic");
    for (double scale : {1e8, 1e-8}) {
      SCOPED_TRACE(testing::Message() << "x0 = " << sign * scale);
      const Outcome o = Simulate(OneDof(r, w, f * scale, sign * scale, 30));
      ASSERT_EQ(o.result.status, RunStatus::kOk);
      EXPECT_EQ(o.attractor.kind, unit.attractor.kind);
      ASSERT_EQ(o.attractor.stick_phases.size(), unit.attractor.stick_phases.size());
      for (size_t i = 0; i < o.attractor.stick_phases.size(); ++i) {
        EXPECT_NEAR(o.attractor.stick_phases[i].first, unit.attractor.stick_phases[i].first, 1e-9);
        EXPECT_NEAR(o.attractor.stick_phases[i].second, unit.attractor.stick_phases[i].second, 1e-9);
      }
    }
  }
}

}  // namespace
}  // namespace vibro::test
