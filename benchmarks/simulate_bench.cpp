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
#include "dynamics/scalar.hpp"
#include "vibro/attractor.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace {

// Counters (rates per CPU second, Google Benchmark's default): events/s, periods/s; probes/event,
// the certified probes of the exact engine's root searches per event (dynamics/exact_engine.hpp,
// ThreadProbeCount); s/probe, the run's CPU time per probe (everything an event costs, shared
// among its probes; BM_Fig8GapProbe times one probe alone).
void RunScene(benchmark::State& state, const char* file, std::vector<std::string> sets) {
  const auto loaded = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, sets);
  const vibro::System sys(loaded.scene);
  long long events = 0, periods = 0;
  const long long probes0 = vibro::detail::ThreadProbeCount();
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
  const auto probes = static_cast<double>(vibro::detail::ThreadProbeCount() - probes0);
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(events), benchmark::Counter::kIsRate);
  state.counters["periods/s"] =
      benchmark::Counter(static_cast<double>(periods), benchmark::Counter::kIsRate);
  if (probes > 0) {
    state.counters["probes/event"] = probes / static_cast<double>(events > 0 ? events : 1);
    state.counters["s/probe"] =
        benchmark::Counter(probes, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  }
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

// A compliant stop (docs/compliant.md): the tube in its two-sided spring–dashpot support, 200
// periods; its events are the contact phases' entries and exits (counted as sticks and releases).
void BM_EventsCompliantTube(benchmark::State& state) {
  RunScene(state, "tube_compliant_support.toml", {"run.samples_per_period=0"});
}
BENCHMARK(BM_EventsCompliantTube)->Unit(benchmark::kMillisecond);

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

namespace {

// The limit of the exact engine on one DOF (docs/performance.md, "The sincos limit"): a certified
// root takes about three probes, and a probe of one mode needs one sincos for the mode's angle and
// one for the forcing's, so an event needs at least six. BM_Limit_Sincos does just that per
// iteration: three probes of two sincos each, the two of a probe independent (they may overlap in
// the processor, as in a probe), each probe's point depending on the last probe's result (as a
// search's next point does), the half angles in [0.5, 1.5] like the engine's. Its events/s is
// the limit, measured in the same run as BM_Events1Dof (benchmarks/engine_limit.py prints the
// ratio); s/sincos is the time of one sincos so counted.
void BM_Limit_Sincos(benchmark::State& state) {
  double u = 0.5;
  for (auto _ : state) {
    for (int k = 0; k < 3; ++k) {
      double sn = 0, cn = 0, sw = 0, cw = 0;
      vibro::detail::Real<double>::sincos(u, sn, cn);          // the mode's angle νσ/2
      vibro::detail::Real<double>::sincos(1.4 * u, sw, cw);    // the forcing's ωσ/2
      u = 1.0 + 0.25 * (sn * cw + cn * sw);                    // the next point waits for both
    }
    benchmark::DoNotOptimize(u);
  }
  state.counters["events/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["s/sincos"] = benchmark::Counter(static_cast<double>(6 * state.iterations()),
                                                  benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Limit_Sincos);

// One certified probe of Fig. 8's gap (one undamped mode: the closed form, the jet, the bound),
// at local times spread over a flight, from a state just after an impact: the cost per probe.
void BM_Fig8GapProbe(benchmark::State& state) {
  const auto loaded = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/fig08_preload.toml", {});
  const vibro::System sys(loaded.scene);
  const vibro::detail::ModelT<double> model(sys);
  vibro::detail::ExactEngine engine(sys, model);
  const Eigen::VectorXd X = Eigen::VectorXd::Constant(1, 1.0), V = Eigen::VectorXd::Constant(1, 0.05);
  engine.Begin({vibro::Mode::kFree, 0.3, 0.0, X, V, 0.0, vibro::detail::FlightStart::kAfterImpact,
                vibro::detail::StickStart::kGeneric});
  const double cap = vibro::detail::StepCap<double>(model);
  double u = 1e-3;
  for (auto _ : state) {
    const auto p = engine.GapProbe(u, cap, 10.0);
    benchmark::DoNotOptimize(p);
    u = u < 0.1 ? u * 1.01 : 1e-3;
  }
  state.counters["s/probe"] = benchmark::Counter(static_cast<double>(state.iterations()),
                                                 benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Fig8GapProbe);

}  // namespace
