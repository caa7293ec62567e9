// Exact engine throughput: events per second (1-DOF and 3-DOF) and the Fig. 5 sticking case end
// to end (200 periods, attractor classification included). Target: Fig. 5 well under 20 ms.
#include <benchmark/benchmark.h>

#include "vibro/attractor.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace {

void RunScene(benchmark::State& state, const char* file, std::vector<std::string> sets) {
  const auto loaded = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, sets);
  const vibro::System sys(loaded.scene);
  long long events = 0;
  for (auto _ : state) {
    vibro::AttractorRecorder rec(sys, loaded.scene);
    vibro::SimulationOptions opt;
    opt.observers = {&rec};
    const auto r = vibro::Simulate(sys, loaded.scene, opt);
    const auto a = rec.Classify();
    benchmark::DoNotOptimize(a);
    events += r.counts.impacts + r.counts.accumulations + r.counts.sticks + r.counts.releases;
  }
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(events), benchmark::Counter::kIsRate);
}

void BM_Fig5StickingEndToEnd(benchmark::State& state) {
  RunScene(state, "fig05_coexistence.toml", {"run.samples_per_period=0"});
}
BENCHMARK(BM_Fig5StickingEndToEnd)->Unit(benchmark::kMillisecond);

void BM_Events1Dof(benchmark::State& state) {
  RunScene(state, "fig08_preload.toml", {"run.samples_per_period=0"});
}
BENCHMARK(BM_Events1Dof)->Unit(benchmark::kMillisecond);

void BM_Events2Dof(benchmark::State& state) {
  RunScene(state, "chain2.toml", {"run.samples_per_period=0"});
}
BENCHMARK(BM_Events2Dof)->Unit(benchmark::kMillisecond);

void BM_Events3Dof(benchmark::State& state) {
  RunScene(state, "chain3.toml", {"run.samples_per_period=0", "stop.restitution=0.5",
                                   "excitation.frequency=1.5", "excitation.amplitude=0.5"});
}
BENCHMARK(BM_Events3Dof)->Unit(benchmark::kMillisecond);

void BM_Events10DofStiff(benchmark::State& state) {
  RunScene(state, "chain10_stiff.toml", {"run.samples_per_period=0"});
}
BENCHMARK(BM_Events10DofStiff)->Unit(benchmark::kMillisecond);

}  // namespace
