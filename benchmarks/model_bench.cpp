// Model construction cost: scene parsing and the modal/constrained eigenproblems.
#include <benchmark/benchmark.h>

#include "vibro/scene_file.hpp"
#include "vibro/system.hpp"

namespace {

void BM_LoadScene(benchmark::State& state) {
  for (auto _ : state) {
    auto loaded = vibro::LoadScene(VIBRO_SCENES_DIR "/chain10_stiff.toml");
    benchmark::DoNotOptimize(loaded);
  }
}
BENCHMARK(BM_LoadScene);

void BM_BuildSystem10(benchmark::State& state) {
  const auto loaded = vibro::LoadScene(VIBRO_SCENES_DIR "/chain10_stiff.toml");
  for (auto _ : state) {
    vibro::System sys(loaded.scene);
    benchmark::DoNotOptimize(sys);
  }
}
BENCHMARK(BM_BuildSystem10);

}  // namespace

BENCHMARK_MAIN();


