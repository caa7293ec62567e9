// Studies: cells per second of a Fig. 5 basin (1-DOF, 100 periods per cell, exact engine) with one
// and two threads (parallel efficiency = ratio of the two rates / 2).
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
  const auto pts = vibro::GridPoints(x, v, 32, 32);
  vibro::StudyOptions opt;
  opt.threads = static_cast<int>(state.range(0));
  long long cells = 0;
  for (auto _ : state) {
    const auto r = vibro::RunStudy(sys, loaded.scene, x, v, pts, opt);
    benchmark::DoNotOptimize(r);
    cells += r.cells;
  }
  state.counters["cells/s"] = benchmark::Counter(static_cast<double>(cells), benchmark::Counter::kIsRate);
}
BENCHMARK(Basin)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
