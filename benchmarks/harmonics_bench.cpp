// The cost of a sum of harmonics per probe (docs/harmonics.md, docs/performance.md): one certified
// probe of the free-flight gap on an 8-mode structure forced by H = 1…4 harmonics. H harmonics
// should cost at most (1 + H)/2 times one harmonic's probe: each adds one sincos per probe (its
// angle), shared by every mode, and a few products per mode (the half angle of each mode is shared
// by every harmonic). Arg = H; the ratio is s/probe(H) / s/probe(1) of one run.
#include <benchmark/benchmark.h>

#include <string>

#include <fmt/format.h>

#include "dynamics/exact_engine.hpp"
#include "dynamics/flight_window.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/system.hpp"

namespace {

std::string Scene(int H) {
  // Eight undamped modes, a clearance; harmonics at ω, 2ω, 3ω, 5ω (ω = 0.7) with phases.
  const double w[4] = {0.7, 1.4, 2.1, 3.5}, f[4] = {1.0, 0.5, 0.3, 0.2}, psi[4] = {0.0, 0.4, 1.1, 2.0};
  std::string a, fr, ph;
  for (int h = 0; h < H; ++h) {
    a += fmt::format("{}{}", h ? ", " : "", f[h]);
    fr += fmt::format("{}{}", h ? ", " : "", w[h]);
    ph += fmt::format("{}{}", h ? ", " : "", psi[h]);
  }
  const std::string excitation =
      H == 1 ? "amplitude = 1.0\nfrequency = 0.7\n"
             : fmt::format("amplitude = [{}]\nfrequency = [{}]\nphase = [{}]\n", a, fr, ph);
  return "[structure]\n"
         "frequencies = [1.0, 2.3, 3.9, 5.2, 7.1, 8.6, 10.4, 12.9]\n"
         "forcing = [0.3, -0.2, 0.15, 0.1, -0.08, 0.05, 0.04, -0.03]\n"
         "contact = [0.3, 0.2, 0.15, 0.1, 0.08, 0.07, 0.05, 0.05]\n"
         "[stop]\nposition = -1.0\nrestitution = 0.8\n[excitation]\n" +
         excitation;
}

void BM_HarmonicsGapProbe(benchmark::State& state) {
  const int H = static_cast<int>(state.range(0));
  const auto loaded = vibro::ParseScene(Scene(H), "harmonics_bench");
  const vibro::System sys(loaded.scene);
  const vibro::detail::ModelT<double> model(sys);
  vibro::detail::ExactEngine engine(sys, model);
  const auto n = sys.dof();
  const Eigen::VectorXd X = Eigen::VectorXd::Constant(n, 1e-3), V = Eigen::VectorXd::Constant(n, 1e-2);
  engine.Begin({vibro::Mode::kFree, 0.3, 0.0, X, V, 0.05, vibro::detail::FlightStart::kGeneric,
                vibro::detail::StickStart::kGeneric});
  const double cap = vibro::detail::StepCap<double>(model);
  double u = 1e-3;
  for (auto _ : state) {
    const auto p = engine.GapProbe(u, cap);
    benchmark::DoNotOptimize(p);
    u = u < 5.0 ? u + 1e-3 : 1e-3;
  }
  state.counters["s/probe"] = benchmark::Counter(static_cast<double>(state.iterations()),
                                                 benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["(1+H)/2"] = (1.0 + H) / 2;
}
BENCHMARK(BM_HarmonicsGapProbe)->Arg(1)->Arg(2)->Arg(3)->Arg(4);

}  // namespace
