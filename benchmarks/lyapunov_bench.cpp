// The cost of the Lyapunov exponents (run.lyapunov, on by default): the same run with and without
// the LyapunovObserver, which carries an orthonormal frame through every flight, impact, sticking
// phase and accumulation point and re-orthonormalises it once per period. Goal (issue 30): ≤ 1.3×
// for n ≤ 3.
//
// BM_LyapunovCost_* give the ratio itself ("with/without"): the two runs alternate, and their
// order too, in one process, each timed by the thread's CPU clock, so that both see the same
// machine (docs/performance.md, "Lyapunov exponents"). BM_Lyapunov_*/0 and /1 time each kind
// of run on its own.
#include <ctime>
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

// One run as `vibro simulate` makes it (an AttractorRecorder; the LyapunovObserver when asked).
long long OneRun(const vibro::System& sys, const vibro::Scene& scene, bool lyapunov) {
  vibro::AttractorRecorder rec(sys, scene);
  std::optional<vibro::LyapunovObserver> ly;
  vibro::SimulationOptions opt;
  opt.observers = {&rec};
  if (lyapunov) opt.observers.push_back(&ly.emplace(sys, scene));
  const auto r = vibro::Simulate(sys, scene, opt);
  benchmark::DoNotOptimize(rec.Classify());
  if (ly) benchmark::DoNotOptimize(ly->Spectrum());
  return r.counts.impacts + r.counts.accumulations + r.counts.sticks + r.counts.releases;
}

vibro::LoadedScene Load(const char* file, std::vector<std::string> sets) {
  sets.push_back("run.samples_per_period=0");
  return vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, sets);
}

void RunWithLyapunov(benchmark::State& state, const char* file, std::vector<std::string> sets) {
  const auto loaded = Load(file, std::move(sets));
  const vibro::System sys(loaded.scene);
  const bool lyapunov = state.range(0) != 0;
  long long events = 0;
  for (auto _ : state) events += OneRun(sys, loaded.scene, lyapunov);
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(events), benchmark::Counter::kIsRate);
}

double ThreadSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// with/without: CPU time of the runs with the exponents over that of the runs without them.
void CompareLyapunov(benchmark::State& state, const char* file, std::vector<std::string> sets) {
  const auto loaded = Load(file, std::move(sets));
  const vibro::System sys(loaded.scene);
  double with_s = 0, without_s = 0;
  long long events = 0;
  const auto run = [&](bool lyapunov, double& seconds) {
    const double a = ThreadSeconds();
    events += OneRun(sys, loaded.scene, lyapunov);
    seconds += ThreadSeconds() - a;
  };
  bool without_first = true;
  for (auto _ : state) {
    if (without_first) run(false, without_s);
    run(true, with_s);
    if (!without_first) run(false, without_s);
    without_first = !without_first;
  }
  const auto iterations = static_cast<double>(state.iterations());
  state.counters["with/without"] = with_s / without_s;
  state.counters["ms_without"] = 1e3 * without_s / iterations;
  state.counters["ms_with"] = 1e3 * with_s / iterations;
  state.counters["events_per_run"] = static_cast<double>(events) / (2 * iterations);
}

// The scenes of issue 30 (n ≤ 3): Fig. 8 (1 DOF, chattering and sticking), the 2-DOF chain, the
// 3-DOF chain as BM_Events3Dof (r = 0.5, ω = 1.5, f = 0.5: impacts) and as shipped (r = 0: a
// held flow of two modes every period), and the chaotic 2-DOF scene (sticking).
const std::vector<std::string> kChain3Impacts = {"stop.restitution=0.5", "excitation.frequency=1.5",
                                                 "excitation.amplitude=0.5"};

void BM_Lyapunov_Fig8(benchmark::State& state) { RunWithLyapunov(state, "fig08_preload.toml", {}); }
void BM_Lyapunov_Chain2(benchmark::State& state) { RunWithLyapunov(state, "chain2.toml", {}); }
void BM_Lyapunov_Chain3(benchmark::State& state) { RunWithLyapunov(state, "chain3.toml", kChain3Impacts); }
void BM_Lyapunov_Chain2Chaotic(benchmark::State& state) {
  RunWithLyapunov(state, "chaotic/chain2_sticking.toml", {});
}
BENCHMARK(BM_Lyapunov_Fig8)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lyapunov_Chain2)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lyapunov_Chain3)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lyapunov_Chain2Chaotic)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_LyapunovCost_Fig8(benchmark::State& state) { CompareLyapunov(state, "fig08_preload.toml", {}); }
void BM_LyapunovCost_Chain2(benchmark::State& state) { CompareLyapunov(state, "chain2.toml", {}); }
void BM_LyapunovCost_Chain3(benchmark::State& state) { CompareLyapunov(state, "chain3.toml", kChain3Impacts); }
void BM_LyapunovCost_Chain3Sticking(benchmark::State& state) { CompareLyapunov(state, "chain3.toml", {}); }
void BM_LyapunovCost_Chain2Chaotic(benchmark::State& state) {
  CompareLyapunov(state, "chaotic/chain2_sticking.toml", {});
}
BENCHMARK(BM_LyapunovCost_Fig8)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_LyapunovCost_Chain2)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_LyapunovCost_Chain3)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_LyapunovCost_Chain3Sticking)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_LyapunovCost_Chain2Chaotic)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
