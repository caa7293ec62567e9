// Exact engine throughput: events and forcing periods per second (1-DOF to 10-DOF) and the Fig. 5
// sticking case end to end (200 periods, attractor classification included). Target: Fig. 5 well
// under 20 ms. The certified chattering rule (docs/model.md §5.4) is measured on Fig. 8 far from and
// 1e-7 below the end of sticking, and the quad-precision reference against double on Fig. 8.
// Periods per second is the fair measure across chattering rules: a rule that predicts earlier
// follows fewer impacts per period.
#include <string>

#include <benchmark/benchmark.h>

#include "dynamics/exact_engine.hpp"
#include "dynamics/flight_window.hpp"
#include "dynamics/model_t.hpp"
#include "vibro/attractor.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace {

void RunScene(benchmark::State& state, const char* file, std::vector<std::string> sets) {
  const auto loaded = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, sets);
  const vibro::System sys(loaded.scene);
  long long events = 0, periods = 0;
  for (auto _ : state) {
    vibro::AttractorRecorder rec(sys, loaded.scene);
    vibro::SimulationOptions opt;
    opt.observers = {&rec};
    const auto r = vibro::Simulate(sys, loaded.scene, opt);
    const auto a = rec.Classify();
    benchmark::DoNotOptimize(a);
    events += r.counts.impacts + r.counts.accumulations + r.counts.sticks + r.counts.releases;
    periods += r.end.period;
  }
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(events), benchmark::Counter::kIsRate);
  state.counters["periods/s"] =
      benchmark::Counter(static_cast<double>(periods), benchmark::Counter::kIsRate);
}

void BM_Fig5StickingEndToEnd(benchmark::State& state) {
  RunScene(state, "fig05_coexistence.toml", {"run.samples_per_period=0"});
}
BENCHMARK(BM_Fig5StickingEndToEnd)->Unit(benchmark::kMillisecond);

void BM_Events1Dof(benchmark::State& state) {
  RunScene(state, "fig08_preload.toml", {"run.samples_per_period=0"});
}
BENCHMARK(BM_Events1Dof)->Unit(benchmark::kMillisecond);

// f_max of Fig. 8 (r = 0.75, ω = 2.8) is 1.28923923…; 1e-7 below it the reaction at the
// accumulation point is ~1e-4 and every sequence is followed until |ε| ≤ 0.1.
void BM_Fig8NearEndOfSticking(benchmark::State& state) {
  RunScene(state, "fig08_preload.toml",
           {"run.samples_per_period=0", "excitation.amplitude=1.2892391"});
}
BENCHMARK(BM_Fig8NearEndOfSticking)->Unit(benchmark::kMillisecond);

void BM_Fig8Quad(benchmark::State& state) {
  RunScene(state, "fig08_preload.toml",
           {"run.samples_per_period=0", "run.periods=20", "run.precision=\"quad\""});
}
BENCHMARK(BM_Fig8Quad)->Unit(benchmark::kMillisecond);

void BM_Fig8DoubleSamePeriods(benchmark::State& state) {
  RunScene(state, "fig08_preload.toml", {"run.samples_per_period=0", "run.periods=20"});
}
BENCHMARK(BM_Fig8DoubleSamePeriods)->Unit(benchmark::kMillisecond);

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

namespace {

// Cost per event against the number of modes: the 50-node beam (data/scenes/large/beam50.toml) truncated
// to its lowest n modes (structure.modes), 50 periods each. benchmarks/mode_sweep.py turns the
// counters into docs/mode_sweep.{csv,png}.
void BM_BeamModes(benchmark::State& state) {
  RunScene(state, "large/beam50.toml",
           {"run.samples_per_period=0", "structure.modes=" + std::to_string(state.range(0))});
}
BENCHMARK(BM_BeamModes)
    ->Arg(1)->Arg(2)->Arg(3)->Arg(5)->Arg(8)->Arg(12)->Arg(16)->Arg(20)->Arg(25)->Arg(30)->Arg(40)
    ->Arg(50)
    ->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

// One certified probe of the free-flight gap (closed-form state of every mode, jet, bounds and the
// far bound) on the beam truncated to n modes: the cost per probe, linear in n by construction.
// µs per event / µs per probe = probes per event (docs/performance.md).
void BM_BeamGapProbe(benchmark::State& state) {
  const auto loaded = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/large/beam50.toml",
                                       {"structure.modes=" + std::to_string(state.range(0))});
  const vibro::System sys(loaded.scene);
  const vibro::detail::ModelT<double> model(sys);
  vibro::detail::ExactEngine engine(sys, model);
  const auto n = sys.dof();
  const Eigen::VectorXd X = Eigen::VectorXd::Constant(n, 1e-3), V = Eigen::VectorXd::Constant(n, 1e-2);
  engine.Begin({vibro::Mode::kFree, 0.3, 0.0, X, V, 0.05, vibro::detail::FlightStart::kGeneric,
                vibro::detail::StickStart::kGeneric});
  const double cap = vibro::detail::StepCap<double>(model);
  double u = 0;
  long long probes = 0;
  for (auto _ : state) {
    const auto p = engine.GapProbe(u, cap, 10.0);
    benchmark::DoNotOptimize(p);
    u = u < 5.0 ? u + 1e-3 : 0.0;
    ++probes;
  }
  state.counters["probes/s"] = benchmark::Counter(static_cast<double>(probes), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BeamGapProbe)->Arg(1)->Arg(2)->Arg(3)->Arg(5)->Arg(8)->Arg(12)->Arg(16)->Arg(20)->Arg(25)
    ->Arg(30)->Arg(40)->Arg(50);

}  // namespace
