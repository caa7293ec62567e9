// Cost of the HDF5 store: the same run with and without the store (events/s), and with dense
// samples (samples/s). The store must never double the run time of a long simulation; with events
// and sections stored it must keep 0.85 of the speed (BM_Fig8StoreRatio, docs/performance.md).
#include <benchmark/benchmark.h>

#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "io/chunk_deflate.hpp"
#include "vibro/attractor.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace {

// One Fig. 8 run, stored in `path` when it is not empty; returns its events.
long long OneRun(const vibro::System& sys, const vibro::LoadedScene& loaded, const std::string& path) {
  vibro::AttractorRecorder rec(sys, loaded.scene);
  vibro::SimulationOptions opt;
  opt.observers = {&rec};
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!path.empty()) {
    vibro::StoreHeader h;
    h.scene_text = loaded.text_as_run;
    h.dof = sys.dof();
    h.frequencies = sys.omega();
    store = vibro::Hdf5Store::Create(path, h);
    opt.observers.push_back(store.get());
  }
  const auto r = vibro::Simulate(sys, loaded.scene, opt);
  if (store) store->Finish(r, rec.Classify());
  return r.counts.impacts + r.counts.accumulations + r.counts.sticks + r.counts.releases;
}

// A file of this process's own: two benchmark processes at once (the claims check beside another
// build's) must not share one (the store refuses a file another process writes).
std::string TmpPath(const std::string& stem) { return "/tmp/" + stem + "_" + std::to_string(getpid()) + ".h5"; }

vibro::LoadedScene Fig8(int samples_per_period, int periods = 2000) {
  return vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/fig08_preload.toml",
                          {"run.periods=" + std::to_string(periods),
                           "run.samples_per_period=" + std::to_string(samples_per_period)});
}

void Run(benchmark::State& state, bool with_store, int samples_per_period) {
  const auto loaded = Fig8(samples_per_period);
  const vibro::System sys(loaded.scene);
  const std::string path = TmpPath("vibro_store_bench");
  long long events = 0, samples = 0;
  for (auto _ : state) {
    events += OneRun(sys, loaded, with_store ? path : "");
    samples += samples_per_period * loaded.scene.run.periods;
  }
  std::remove(path.c_str());
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(events), benchmark::Counter::kIsRate);
  if (samples_per_period > 0)
    state.counters["samples/s"] = benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
}

double Seconds(clockid_t clock) {
  timespec t{};
  clock_gettime(clock, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The store's speed ratio measured pair by pair: each iteration runs the plain run and the stored
// one (events and sections), in alternating order, and times both three ways: the wall clock, the
// simulation thread's CPU, and the whole process's CPU (the store's writer thread included: the
// write-behind moves the compression and the writes to it, off the simulation's path). Each
// `store_speed_*` counter is (plain time) / (stored time) summed over the pairs. 20 000 periods
// (720 000 events, 0.4 s): the throughput of a long run, not the file's creation.
void BM_Fig8StoreRatio(benchmark::State& state) {
  const auto loaded = Fig8(0, 20000);
  const vibro::System sys(loaded.scene);
  const std::string path = TmpPath("vibro_store_ratio_bench");
  double plain[3] = {0, 0, 0}, stored[3] = {0, 0, 0};
  bool plain_first = true;
  const auto timed = [&](double* sums, const std::string& p) {
    const double w0 = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    const double t0 = Seconds(CLOCK_THREAD_CPUTIME_ID), c0 = Seconds(CLOCK_PROCESS_CPUTIME_ID);
    benchmark::DoNotOptimize(OneRun(sys, loaded, p));
    sums[0] += std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count() - w0;
    sums[1] += Seconds(CLOCK_THREAD_CPUTIME_ID) - t0;
    sums[2] += Seconds(CLOCK_PROCESS_CPUTIME_ID) - c0;
  };
  for (auto _ : state) {
    if (plain_first) timed(plain, "");
    timed(stored, path);
    if (!plain_first) timed(plain, "");
    plain_first = !plain_first;
  }
  std::remove(path.c_str());
  state.counters["store_speed_wall"] = plain[0] / stored[0];
  state.counters["store_speed_thread_cpu"] = plain[1] / stored[1];
  state.counters["store_speed_process_cpu"] = plain[2] / stored[2];
}
BENCHMARK(BM_Fig8StoreRatio)->Unit(benchmark::kMillisecond)->MinTime(3.0);

// The store's chunk encoder alone (src/io/chunk_deflate.cpp: shuffle, LZ77, Adler-32) on two
// columns of Fig. 8's /events over 20 000 periods, chunk by chunk (16 384 rows of float64): `t`,
// whose low byte planes seldom repeat (the costliest column), and `v_after`, which repeats every
// period like most of the others. bytes/s of the rows encoded; ratio: encoded / raw bytes.
struct EventColumns : vibro::Observer {
  std::vector<double> t, v_after;
  void OnEvent(const vibro::Event& e) override {
    t.push_back(e.t);
    v_after.push_back(e.v_after);
  }
  bool WantsResets() const override { return false; }
};

const EventColumns& Fig8Columns() {
  static const EventColumns columns = [] {
    const auto loaded = Fig8(0, 20000);
    const vibro::System sys(loaded.scene);
    EventColumns c;
    vibro::SimulationOptions opt;
    opt.observers = {&c};
    vibro::Simulate(sys, loaded.scene, opt);
    return c;
  }();
  return columns;
}

void EncodeChunks(benchmark::State& state, const std::vector<double>& column) {
  constexpr size_t kChunk = 16384 * sizeof(double);
  const auto* bytes = reinterpret_cast<const unsigned char*>(column.data());
  const size_t whole = column.size() * sizeof(double) / kChunk * kChunk;
  vibro::h5::Bytes scratch;
  std::vector<unsigned char> out(vibro::h5::ZlibFixedBound(kChunk));
  size_t encoded = 0;
  for (auto _ : state) {
    encoded = 0;
    for (size_t at = 0; at < whole; at += kChunk)
      encoded += vibro::h5::ShuffleDeflate(bytes + at, kChunk, sizeof(double), scratch, out.data());
    benchmark::DoNotOptimize(encoded);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * whole));
  state.counters["ratio"] = static_cast<double>(encoded) / static_cast<double>(whole);
}
void BM_ChunkEncodeT(benchmark::State& s) { EncodeChunks(s, Fig8Columns().t); }
void BM_ChunkEncodeVAfter(benchmark::State& s) { EncodeChunks(s, Fig8Columns().v_after); }
BENCHMARK(BM_ChunkEncodeT)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ChunkEncodeVAfter)->Unit(benchmark::kMillisecond);

void BM_Fig8NoStore(benchmark::State& s) { Run(s, false, 0); }
void BM_Fig8Store(benchmark::State& s) { Run(s, true, 0); }
void BM_Fig8NoStoreSamples64(benchmark::State& s) { Run(s, false, 64); }
void BM_Fig8StoreSamples64(benchmark::State& s) { Run(s, true, 64); }
BENCHMARK(BM_Fig8NoStore)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Fig8Store)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Fig8NoStoreSamples64)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Fig8StoreSamples64)->Unit(benchmark::kMillisecond);

}  // namespace
