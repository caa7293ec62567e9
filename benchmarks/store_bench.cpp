// Cost of the HDF5 store: the same run with and without the store (events/s), and with dense
// samples (samples/s). The store must never double the run time of a long simulation.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>

#include "vibro/attractor.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace {

void Run(benchmark::State& state, bool with_store, int samples_per_period) {
  const auto loaded = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/fig08_preload.toml",
                                       {"run.periods=2000", "run.samples_per_period=" +
                                                                std::to_string(samples_per_period)});
  const vibro::System sys(loaded.scene);
  const std::string path = "/tmp/vibro_store_bench.h5";
  long long events = 0, samples = 0;
  for (auto _ : state) {
    vibro::AttractorRecorder rec(sys, loaded.scene);
    vibro::SimulationOptions opt;
    opt.observers = {&rec};
    std::unique_ptr<vibro::Hdf5Store> store;
    if (with_store) {
      vibro::StoreHeader h;
      h.scene_text = loaded.text_as_run;
      h.dof = sys.dof();
      h.frequencies = sys.omega();
      store = vibro::Hdf5Store::Create(path, h);
      opt.observers.push_back(store.get());
    }
    const auto r = vibro::Simulate(sys, loaded.scene, opt);
    if (store) store->Finish(r, rec.Classify());
    events += r.counts.impacts + r.counts.accumulations + r.counts.sticks + r.counts.releases;
    samples += samples_per_period * loaded.scene.run.periods;
  }
  std::remove(path.c_str());
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(events), benchmark::Counter::kIsRate);
  if (samples_per_period > 0)
    state.counters["samples/s"] = benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
}

void BM_Fig8NoStore(benchmark::State& s) { Run(s, false, 0); }
void BM_Fig8Store(benchmark::State& s) { Run(s, true, 0); }
void BM_Fig8NoStoreSamples64(benchmark::State& s) { Run(s, false, 64); }
void BM_Fig8StoreSamples64(benchmark::State& s) { Run(s, true, 64); }
BENCHMARK(BM_Fig8NoStore)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Fig8Store)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Fig8NoStoreSamples64)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Fig8StoreSamples64)->Unit(benchmark::kMillisecond);

}  // namespace
