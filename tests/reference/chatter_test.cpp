// Chattering treatments (docs/model.md §5.4, §5.4) against an exactly summable impact sequence.
//
// Oracle: the unforced 1-DOF oscillator (ω_1 = 1, f = 0) leaving the stop x0 = 1 with speed v
// returns after Δ(v) = 2 atan(v/x0) with speed v (x = x0 cos s + v sin s), then rebounds with r v.
// Starting with speed v_0 = 1 on the stop, the impacts accumulate at
//     t_∞ = Σ_{j≥0} 2 atan(r^j v_0 / x0)
// and the body then rests on the stop for ever (R = x0 > 0).
#include <cmath>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

// `knob`: run.chatter_switch for "threshold", run.chatter_tolerance for "accumulation".
Scene Bouncing(double r, ChatterTreatment treatment, double knob) {
  Scene s = OneDof(r, 1.0, 0.0, 1.0, 100);
  s.initial_displacement = Eigen::VectorXd::Constant(1, 1.0);
  s.initial_velocity = Eigen::VectorXd::Constant(1, 1.0);
  s.run.chatter = treatment;
  if (treatment == ChatterTreatment::kAccumulation)
    s.run.chatter_tolerance = knob;
  else
    s.run.chatter_switch = knob;
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
  // The run's accuracy target holds, and so does the estimate it reports: the true error of the
  // accumulation time is below the largest estimated error of the predictions taken, plus the
  // rounding of the impacts followed before it (a few ε t each; this is what limits double
  // precision to targets of about 1e-14 T on long sequences).
  const double T = 2.0 * M_PI;
  for (double r : {0.3, 0.75, 0.95, 0.99}) {
    for (double tol : {1e-10, 1e-12}) {
      SCOPED_TRACE(testing::Message() << "r = " << r << ", tolerance " << tol);
      const Outcome run = Simulate(Bouncing(r, ChatterTreatment::kAccumulation, tol));
      ASSERT_EQ(run.result.status, RunStatus::kOk);
      EXPECT_EQ(run.log.Of(EventKind::kAccumulation).size(), 1u);
      EXPECT_EQ(run.result.chatter.accumulations_predicted, 1);
      const double err = std::abs(StickTime(run) - static_cast<double>(AccumulationTime(r)));
      const double est = run.result.chatter.max_estimated_error * T;
      const double rounding =
          4.0 * 2.2e-16 * StickTime(run) * static_cast<double>(run.result.counts.impacts);
      EXPECT_LE(err, tol * T + rounding);
      EXPECT_LE(err, est + rounding);
      EXPECT_LE(run.result.chatter.max_estimated_error, tol);
      EXPECT_EQ(run.attractor.kind, "permanent-contact");
      // Every impact but the last was followed because its prediction was not yet good enough.
      EXPECT_EQ(run.result.chatter.impacts_followed, run.result.counts.impacts - 1);
    }
  }
}

TEST(Chatter, AccumulationErrorFollowsTheTargetThresholdIsFirstOrder) {
  // "accumulation": the error stays below the target and falls with it. "threshold": halving the
  // switch velocity halves the error (O(v), the paper's plastic alternative).
  const double r = 0.5, T = 2.0 * M_PI;
  const double exact = static_cast<double>(AccumulationTime(r));
  double previous = 1.0;
  for (double tol : {1e-4, 1e-6, 1e-8, 1e-10, 1e-12}) {
    const Outcome run = Simulate(Bouncing(r, ChatterTreatment::kAccumulation, tol));
    const double err = std::abs(StickTime(run) - exact);
    SCOPED_TRACE(testing::Message() << "tolerance " << tol << ": error " << err);
    EXPECT_LE(err, tol * T);
    EXPECT_LE(err, run.result.chatter.max_estimated_error * T + 1e-15);
    EXPECT_LT(err, previous);
    previous = err;
  }
  for (double eps : {2e-3, 1e-3}) {
    const double thr1 = std::abs(StickTime(Simulate(Bouncing(r, ChatterTreatment::kThreshold, eps))) - exact);
    const double thr2 = std::abs(StickTime(Simulate(Bouncing(r, ChatterTreatment::kThreshold, eps / 2))) - exact);
    SCOPED_TRACE(testing::Message() << "eps " << eps << ": threshold " << thr1 << " → " << thr2);
    EXPECT_GT(thr1 / thr2, 1.4);  // impacts are discrete: v at the switch jumps by factors of r
    EXPECT_LT(thr1 / thr2, 2.9);
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
  const Outcome run = Simulate(Bouncing(1.0, ChatterTreatment::kAccumulation, 0.0));
  ASSERT_EQ(run.result.status, RunStatus::kOk);
  EXPECT_EQ(run.result.counts.accumulations, 0);
  const auto impacts = run.log.Of(EventKind::kImpact);
  ASSERT_GT(impacts.size(), 10u);
  for (size_t i = 0; i < impacts.size(); ++i) {
    EXPECT_NEAR(impacts[i].t, static_cast<double>(i + 1) * M_PI / 2.0, 1e-12 * (1.0 + impacts[i].t));
    EXPECT_NEAR(impacts[i].v_before, -1.0, 1e-12);
  }
}


// Resets are built only when some observer reads them (Observer::WantsResets, docs/performance.md):
// Fig. 8 (a chattering sequence and a predicted accumulation every period) with an event log that
// reads no resets, alone and beside an observer that reads them. The events are the same to the
// bit; alone, no reset reaches the log; beside the reader, every impact and every accumulation
// gives one, the accumulation's with its jump-time gradient (2n) and the free state at t∞.
struct EventsOnly final : Observer {
  std::vector<Event> events;
  int resets = 0;
  void OnEvent(const Event& e) override { events.push_back(e); }
  void OnReset(const Reset&) override { ++resets; }
  bool WantsResets() const override { return false; }
};
struct ResetReader final : Observer {
  int impacts = 0, accumulations = 0, with_gradient = 0;
  void OnReset(const Reset& r) override {
    if (r.kind == ResetKind::kImpact) ++impacts;
    if (r.kind != ResetKind::kAccumulation) return;
    ++accumulations;
    if (r.delta_gradient && r.delta_gradient->size() == 2 && r.X_end && r.X_end->size() == 1 &&
        std::isfinite((*r.delta_gradient)[0]) && r.delta > 0)
      ++with_gradient;
  }
};

TEST(Chatter, ResetsOnlyForObserversThatReadThem) {
  const auto loaded = LoadScene(std::string(VIBRO_SCENES_DIR) + "/fig08_preload.toml",
                                {"run.periods=20", "run.samples_per_period=0"});
  const System sys(loaded.scene);
  EventsOnly alone, beside;
  ResetReader reader;
  SimulationOptions a, b;
  a.observers = {&alone};
  b.observers = {&beside, &reader};
  const RunResult ra = Simulate(sys, loaded.scene, a), rb = Simulate(sys, loaded.scene, b);
  ASSERT_EQ(ra.status, RunStatus::kOk);
  ASSERT_EQ(rb.status, RunStatus::kOk);
  ASSERT_GT(ra.counts.accumulations, 10);
  ASSERT_EQ(alone.events.size(), beside.events.size());
  for (size_t i = 0; i < alone.events.size(); ++i) {
    const Event &x = alone.events[i], &y = beside.events[i];
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ(x.clock.period, y.clock.period);
    for (const auto& [u, v] : {std::pair{x.clock.offset, y.clock.offset}, {x.t, y.t}, {x.x_B, y.x_B},
                               {x.v_before, y.v_before}, {x.v_after, y.v_after}, {x.impulse, y.impulse},
                               {x.energy_dissipated, y.energy_dissipated}})
      EXPECT_TRUE(u == v || (std::isnan(u) && std::isnan(v))) << "event " << i << ": " << u << " vs " << v;
  }
  EXPECT_EQ(alone.resets, 0);
  EXPECT_GT(beside.resets, 0);
  EXPECT_EQ(reader.impacts, rb.counts.impacts);
  EXPECT_EQ(reader.accumulations, rb.counts.accumulations);
  EXPECT_EQ(reader.with_gradient, reader.accumulations);
}

}  // namespace
}  // namespace vibro::test
