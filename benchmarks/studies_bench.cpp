// Studies: cells per second of a Fig. 5 basin (1-DOF, 100 periods per cell, exact engine) with one
// and two threads (parallel efficiency = ratio of the two rates / 2), with the early stops (cells
// stop once settled or on a known orbit; the pilot study that finds the known orbits is included
// in the time) and without them (every cell runs its 100 periods).
#include <benchmark/benchmark.h>

#include <string>

#include "vibro/scene_file.hpp"
#include "vibro/studies.hpp"

namespace {

void Basin(benchmark::State& state) {
  const auto loaded = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/fig05_coexistence.toml",
                                       {"run.periods=100", "run.samples_per_period=0"});
  const vibro::System sys(loaded.scene);
  const vibro::Coordinate x{"x_B", 1.0, 3.0}, v{"v_B", -2.0, 2.0};
  const auto pts = vibro::GridPoints(x, v, 48, 48);
  vibro::StudyOptions opt;
  opt.threads = static_cast<int>(state.range(0));
  if (state.range(1) == 0) opt.settle_remainder = 0;  // every cell runs all its periods
  long long cells = 0;
  for (auto _ : state) {
    const auto r = vibro::RunStudy(sys, loaded.scene, x, v, pts, opt);
    benchmark::DoNotOptimize(r);
    cells += r.cells;
  }
  state.counters["cells/s"] = benchmark::Counter(static_cast<double>(cells), benchmark::Counter::kIsRate);
}
BENCHMARK(Basin)
    ->ArgNames({"threads", "early_stop"})
    ->Args({1, 1})
    ->Args({2, 1})
    ->Args({1, 0})
    ->Args({2, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
