// The cost of recording what the contacts endure (docs/loads.md): events/s of a run whose events
// carry their loads (impulses, energies, the sticking phases' ∫R dt and max R) and are summed by a
// LoadsRecorder, against the same run without them, in one process, alternating the two runs so
// that both see the same machine. Target (issue 29): the ratio "loads/plain" ≥ 0.9 on Fig. 8 and on
// the 3-DOF chain (sticking with a held flow of two modes, and chattering).
#include <ctime>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "vibro/attractor.hpp"
#include "vibro/loads.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace {

void Compare(benchmark::State& state, const char* file, std::vector<std::string> sets) {
  sets.push_back("run.samples_per_period=0");
  const auto loaded = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, sets);
  const vibro::System sys(loaded.scene);
  double plain_s = 0, loads_s = 0;
  long long plain_events = 0, loads_events = 0;
  const auto run = [&](bool loads, double& seconds, long long& events) {
    vibro::AttractorRecorder rec(sys, loaded.scene);
    vibro::LoadsRecorder recorder(sys, loaded.scene.run.periods / 10);
    vibro::SimulationOptions opt;
    opt.observers = {&rec};
    if (loads) opt.observers.push_back(&recorder);
    opt.loads = loads;
    timespec a{}, b{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &a);
    const auto r = vibro::Simulate(sys, loaded.scene, opt);
    if (loads) benchmark::DoNotOptimize(recorder.Summary(10));
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &b);
    seconds += static_cast<double>(b.tv_sec - a.tv_sec) + 1e-9 * static_cast<double>(b.tv_nsec - a.tv_nsec);
    events += r.counts.impacts + r.counts.accumulations + r.counts.sticks + r.counts.releases;
  };
  bool plain_first = true;
  for (auto _ : state) {
    if (plain_first) run(false, plain_s, plain_events);
    run(true, loads_s, loads_events);
    if (!plain_first) run(false, plain_s, plain_events);
    plain_first = !plain_first;
  }
  const double plain = static_cast<double>(plain_events) / plain_s;
  const double with = static_cast<double>(loads_events) / loads_s;
  state.counters["plain_events/s"] = plain;
  state.counters["loads_events/s"] = with;
  state.counters["loads/plain"] = with / plain;
  state.counters["s_per_run_plain"] = plain_s / static_cast<double>(state.iterations());
  state.counters["s_per_run_loads"] = loads_s / static_cast<double>(state.iterations());
  state.counters["events_per_run_plain"] = static_cast<double>(plain_events) / static_cast<double>(state.iterations());
  state.counters["events_per_run_loads"] = static_cast<double>(loads_events) / static_cast<double>(state.iterations());
}

void BM_LoadsFig8(benchmark::State& state) { Compare(state, "fig08_preload.toml", {"run.periods=400"}); }
BENCHMARK(BM_LoadsFig8)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The 3-DOF chain as BM_Events3Dof of simulate_bench.cpp measures it (r = 0.5, ω = 1.5, f = 0.5).
void BM_LoadsChain3(benchmark::State& state) {
  Compare(state, "chain3.toml",
          {"run.periods=400", "stop.restitution=0.5", "excitation.frequency=1.5", "excitation.amplitude=0.5"});
}
BENCHMARK(BM_LoadsChain3)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_LoadsChain3Sticking(benchmark::State& state) { Compare(state, "chain3.toml", {"run.periods=400"}); }
BENCHMARK(BM_LoadsChain3Sticking)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_LoadsChain3Chattering(benchmark::State& state) {
  Compare(state, "chain3.toml", {"run.periods=400", "stop.restitution=0.5"});
}
BENCHMARK(BM_LoadsChain3Chattering)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
