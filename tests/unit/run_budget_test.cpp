// A run always ends (docs/orbits.md, "Every map evaluation ends"): a scene built in code with a
// forcing frequency that is not finite and positive is refused, not run (its clock never reaches a
// period boundary: before the fix, Simulate of the tube at ω = −0.863 — a Newton iterate of the
// tube's continuation — looped inside Automaton::Run and never returned), and a run given a segment
// budget stops with a numerical failure once it is spent. Each run is watched: one that has not
// returned after 60 s fails the test and ends the process (a hung run cannot be stopped from
// outside: the old loop polled nothing).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <limits>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"

namespace vibro::test {
namespace {

// Simulate with a watchdog: a run that does not return within 60 s ends the test binary (exit 1).
RunResult Watched(const System& sys, const Scene& scene, const SimulationOptions& opt) {
  std::packaged_task<RunResult()> task([&] { return Simulate(sys, scene, opt); });
  auto result = task.get_future();
  std::thread worker(std::move(task));
  if (result.wait_for(std::chrono::seconds(60)) != std::future_status::ready) {
    std::fprintf(stderr, "FAILED: Simulate did not return within 60 s (an endless run)\n");
    std::fflush(stderr);
    std::_Exit(1);
  }
  worker.join();
  return result.get();
}

Scene Tube(double w) {
  Scene s = LoadScene(std::string(VIBRO_SCENES_DIR) + "/tube_loose_support.toml", {"run.samples_per_period=0"}).scene;
  s.frequency = w;  // set in code, as a continuation's scene_at does: not validated
  return s;
}

TEST(RunBudget, ANonPositiveOrNonFiniteFrequencyIsRefusedNotRun) {
  // The state and section of the trial point at which the tube's continuation from 0.9 to 1.5 hung.
  Eigen::VectorXd X(2), V(2);
  X << -0.040854052884282344, -0.1127274414217975;
  V << -0.6528416687920043, 0.3373589902182059;
  for (const double w : {-0.86301109781178376, 0.0, std::numeric_limits<double>::quiet_NaN()}) {
    SCOPED_TRACE(w);
    Scene s = Tube(w);
    s.run.periods = 1;
    const System sys(s);
    const InitialOverride init{0.11658253987931921 / w, X, V};
    SimulationOptions opt;
    opt.initial = &init;
    const RunResult r = Watched(sys, s, opt);
    EXPECT_EQ(r.status, RunStatus::kNumericalFailure);
    EXPECT_NE(r.message.find("excitation.frequency"), std::string::npos) << r.message;
  }
}

TEST(RunBudget, ASpentSegmentBudgetIsANumericalFailureAndNoBudgetChangesNothing) {
  // The tube's period-1 orbit hits each side once a period: each of its 200 periods is at least
  // three segments (two flights between impacts, cut at the period boundary), far above 50.
  Scene s = Tube(0.9);
  s.run.periods = 200;
  const System sys(s);
  SimulationOptions free_run;
  const RunResult full = Watched(sys, s, free_run);
  ASSERT_EQ(full.status, RunStatus::kOk);
  const long long impacts = full.counts.impacts;
  ASSERT_GT(impacts, 200);
  SimulationOptions budget;
  budget.max_segments = 50;
  const RunResult cut = Watched(sys, s, budget);
  EXPECT_EQ(cut.status, RunStatus::kNumericalFailure);
  EXPECT_NE(cut.message.find("segment budget"), std::string::npos) << cut.message;
  EXPECT_LT(cut.end.period, 50);
  // A budget the run does not reach: the same run to the bit.
  SimulationOptions ample;
  ample.max_segments = 1000000;
  const RunResult same = Watched(sys, s, ample);
  ASSERT_EQ(same.status, RunStatus::kOk);
  EXPECT_EQ(same.counts.impacts, impacts);
  for (long k = 0; k < full.X.size(); ++k) {
    EXPECT_EQ(same.X[k], full.X[k]);
    EXPECT_EQ(same.V[k], full.V[k]);
  }
}

}  // namespace
}  // namespace vibro::test
