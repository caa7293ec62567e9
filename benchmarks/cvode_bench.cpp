// CVODE engine work: time per forcing period and events per second at rtol 1e-6, 1e-9, 1e-12
// (atol = rtol·1e-2), Adams and BDF, on the 1-DOF Fig. 5 sticking case and the 10-DOF stiff chain,
// with the exact engine on the same runs for the ratio.
#include <benchmark/benchmark.h>

#include <string>

#include <fmt/format.h>

#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace {

void Run(benchmark::State& state, const char* file, long long periods, const char* engine,
         const char* method, double rtol) {
  const auto loaded = vibro::LoadScene(
      std::string(VIBRO_SCENES_DIR) + "/" + file,
      {"run.samples_per_period=0", "run.periods=" + std::to_string(periods),
       std::string("run.engine=\"") + engine + "\"", std::string("run.method=\"") + method + "\"",
       fmt::format("run.rtol={:g}", rtol), fmt::format("run.atol={:g}", rtol * 1e-2)});
  const vibro::System sys(loaded.scene);
  long long events = 0, steps = 0, done = 0;
  for (auto _ : state) {
    const auto r = vibro::Simulate(sys, loaded.scene, {});
    events += r.counts.impacts + r.counts.accumulations + r.counts.sticks + r.counts.releases;
    steps += r.solver.steps;
    done += r.end.period;
  }
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(events), benchmark::Counter::kIsRate);
  state.counters["periods/s"] = benchmark::Counter(static_cast<double>(done), benchmark::Counter::kIsRate);
  state.counters["steps/period"] = static_cast<double>(steps) / static_cast<double>(std::max(done, 1LL));
}

#define VIBRO_CVODE_CASE(name, file, periods, method, rtol)                                     \
  void name(benchmark::State& s) { Run(s, file, periods, "cvode", method, rtol); }         \
  BENCHMARK(name)->Unit(benchmark::kMillisecond)

VIBRO_CVODE_CASE(BM_Fig5_Adams_1e6, "fig05_coexistence.toml", 50, "adams", 1e-6);
VIBRO_CVODE_CASE(BM_Fig5_Adams_1e9, "fig05_coexistence.toml", 50, "adams", 1e-9);
VIBRO_CVODE_CASE(BM_Fig5_Adams_1e12, "fig05_coexistence.toml", 50, "adams", 1e-12);
VIBRO_CVODE_CASE(BM_Fig5_Bdf_1e6, "fig05_coexistence.toml", 50, "bdf", 1e-6);
VIBRO_CVODE_CASE(BM_Fig5_Bdf_1e9, "fig05_coexistence.toml", 50, "bdf", 1e-9);
VIBRO_CVODE_CASE(BM_Fig5_Bdf_1e12, "fig05_coexistence.toml", 50, "bdf", 1e-12);
VIBRO_CVODE_CASE(BM_Chain10_Adams_1e6, "chain10_stiff.toml", 5, "adams", 1e-6);
VIBRO_CVODE_CASE(BM_Chain10_Adams_1e9, "chain10_stiff.toml", 5, "adams", 1e-9);
VIBRO_CVODE_CASE(BM_Chain10_Adams_1e12, "chain10_stiff.toml", 5, "adams", 1e-12);
VIBRO_CVODE_CASE(BM_Chain10_Bdf_1e6, "chain10_stiff.toml", 5, "bdf", 1e-6);
VIBRO_CVODE_CASE(BM_Chain10_Bdf_1e9, "chain10_stiff.toml", 5, "bdf", 1e-9);
VIBRO_CVODE_CASE(BM_Chain10_Bdf_1e12, "chain10_stiff.toml", 5, "bdf", 1e-12);

void BM_Fig5_Exact(benchmark::State& s) { Run(s, "fig05_coexistence.toml", 50, "exact", "adams", 1e-10); }
BENCHMARK(BM_Fig5_Exact)->Unit(benchmark::kMillisecond);
void BM_Chain10_Exact(benchmark::State& s) { Run(s, "chain10_stiff.toml", 5, "exact", "adams", 1e-10); }
BENCHMARK(BM_Chain10_Exact)->Unit(benchmark::kMillisecond);

}  // namespace
