// Continuation: points per second along a branch for 1-, 2- and 3-DOF sticking orbits, and the
// cost of the CLI's way of building each scene (re-reading the TOML file) against building it
// once and setting the parameter in the struct. Issue target: a 1000-point 3-DOF branch in well
// under a second.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

#include <fmt/format.h>

#include "vibro/continuation.hpp"
#include "vibro/scene_file.hpp"

namespace {

enum class Param { kAmplitude, kFrequency };

void Branch(benchmark::State& state, const char* file, std::vector<std::string> sets, Param param,
            double to, bool reparse) {
  sets.push_back("run.samples_per_period=0");
  const std::string path = std::string(VIBRO_SCENES_DIR) + "/" + file;
  const auto base = vibro::LoadScene(path, sets).scene;
  vibro::ContinuationRequest req;
  req.scene_at = [&](double v) {
    if (reparse) {
      auto s = sets;
      s.push_back((param == Param::kAmplitude ? "excitation.amplitude=" : "excitation.frequency=") +
                  fmt::format("{:.17g}", v));
      return vibro::LoadScene(path, s).scene;
    }
    vibro::Scene s = base;
    (param == Param::kAmplitude ? s.amplitude : s.frequency) = v;
    return s;
  };
  req.from = param == Param::kAmplitude ? base.amplitude : base.frequency;
  req.to = to;
  req.max_step = std::abs(to - req.from) / 200;  // dense branches: ~ hundreds of points
  req.max_points = static_cast<int>(state.range(0));
  size_t points = 0;
  for (auto _ : state) {
    const auto b = vibro::Continue(req);
    if (b.status != "ok") state.SkipWithError(("continue: " + b.end).c_str());
    points += b.points.size();
  }
  state.counters["points"] = benchmark::Counter(static_cast<double>(points) / static_cast<double>(state.iterations()));
  state.counters["points_per_s"] = benchmark::Counter(static_cast<double>(points), benchmark::Counter::kIsRate);
}

void BM_Continue1Dof(benchmark::State& s) {
  Branch(s, "fig08_preload.toml", {"stop.restitution=0.0", "excitation.amplitude=1.5"}, Param::kAmplitude, 20, false);
}
void BM_Continue2Dof(benchmark::State& s) {
  Branch(s, "chain2.toml", {"stop.restitution=0.0"}, Param::kFrequency, 1.35, false);
}
void BM_Continue3Dof(benchmark::State& s) {
  Branch(s, "chain3.toml", {}, Param::kFrequency, 1.5, false);
}
void BM_Continue3DofReparse(benchmark::State& s) {
  Branch(s, "chain3.toml", {}, Param::kFrequency, 1.5, true);
}
BENCHMARK(BM_Continue1Dof)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Continue2Dof)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Continue3Dof)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Continue3DofReparse)->Arg(1000)->Unit(benchmark::kMillisecond);

}  // namespace
