// The cost of the Lyapunov exponents (run.lyapunov, on by default): the same run with and without
// the LyapunovObserver, which carries an orthonormal frame through every flight, impact, sticking
// phase and accumulation point and re-orthonormalises it once per period. Goal: ≤ 1.3× for n ≤ 3
// (compare BM_Lyapunov/…/1 with …/0 of the same scene, from one run).
#include <optional>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "vibro/attractor.hpp"
#include "vibro/lyapunov.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace {

void RunWithLyapunov(benchmark::State& state, const char* file, std::vector<std::string> sets) {
  sets.push_back("run.samples_per_period=0");
  const auto loaded = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, sets);
  const vibro::System sys(loaded.scene);
  const bool lyapunov = state.range(0) != 0;
  long long events = 0;
  for (auto _ : state) {
    vibro::AttractorRecorder rec(sys, loaded.scene);
    std::optional<vibro::LyapunovObserver> ly;
    vibro::SimulationOptions opt;
    opt.observers = {&rec};
    if (lyapunov) opt.observers.push_back(&ly.emplace(sys, loaded.scene));
    const auto r = vibro::Simulate(sys, loaded.scene, opt);
    benchmark::DoNotOptimize(rec.Classify());
    if (ly) benchmark::DoNotOptimize(ly->Spectrum());
    events += r.counts.impacts + r.counts.accumulations + r.counts.sticks + r.counts.releases;
  }
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(events), benchmark::Counter::kIsRate);
}

void BM_Lyapunov_Fig8(benchmark::State& state) { RunWithLyapunov(state, "fig08_preload.toml", {}); }
void BM_Lyapunov_Chain2(benchmark::State& state) { RunWithLyapunov(state, "chain2.toml", {}); }
void BM_Lyapunov_Chain3(benchmark::State& state) {
  RunWithLyapunov(state, "chain3.toml",
                  {"stop.restitution=0.5", "excitation.frequency=1.5", "excitation.amplitude=0.5"});
}
void BM_Lyapunov_Chain2Chaotic(benchmark::State& state) {
  RunWithLyapunov(state, "chaotic/chain2_sticking.toml", {});
}
BENCHMARK(BM_Lyapunov_Fig8)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lyapunov_Chain2)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lyapunov_Chain3)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lyapunov_Chain2Chaotic)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
