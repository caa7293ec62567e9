// Poincaré solver: time to find an orbit (transient guess of 20 periods + Newton with the analytic
// Jacobian) for 1-, 2-, 3- and 10-DOF structures, with the Newton iterations as a counter.
#include <benchmark/benchmark.h>

#include <string>

#include "vibro/poincare.hpp"
#include "vibro/scene_file.hpp"

namespace {

void Solve(benchmark::State& state, const char* file, std::vector<std::string> sets) {
  sets.push_back("run.samples_per_period=0");
  const auto loaded = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, sets);
  const vibro::System sys(loaded.scene);
  vibro::OrbitRequest req;
  req.transient_periods = 20;
  req.period = 1;
  int iterations = 0;
  for (auto _ : state) {
    const auto o = vibro::FindOrbit(sys, loaded.scene, req);
    if (o.status != "converged") state.SkipWithError(("orbit: " + o.message).c_str());
    iterations = o.newton_iterations;
  }
  state.counters["newton_iterations"] = iterations;
}

void BM_Orbit1Dof(benchmark::State& s) { Solve(s, "fig08_preload.toml", {}); }
void BM_Orbit2Dof(benchmark::State& s) { Solve(s, "chain2.toml", {}); }
void BM_Orbit3Dof(benchmark::State& s) { Solve(s, "chain3.toml", {}); }
void BM_Orbit10Dof(benchmark::State& s) {
  Solve(s, "chain10_stiff.toml",
        {"structure.damping_ratios=[0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05]"});
}
BENCHMARK(BM_Orbit1Dof)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Orbit2Dof)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Orbit3Dof)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Orbit10Dof)->Unit(benchmark::kMillisecond);

}  // namespace
