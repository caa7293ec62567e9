// `vibro diagram` (docs/diagram.md): the whole diagram of the tube in its loose support over
// ω ∈ [0.4, 1.6] (issue 41's scene) as docs/diagram.md runs it for issue 41's "Done when": a sweep
// of 30 steps (the argument), every other option at its default (`vibro diagram
// data/scenes/tube_loose_support.toml --param excitation.frequency --from 0.4 --to 1.6 --steps 30`).
// Counters: the stages' wall time (`seconds`) and the share of it spent in
// the sweep, the attractor searches, continuation, switching and the coverage check; what the
// diagram found (branches, points, uncovered attractors, of which periodic: 0 when every periodic
// attractor lies on a stable branch). One iteration (a diagram takes minutes on a loaded
// machine): `--benchmark_filter=Diagram`.
#include <benchmark/benchmark.h>

#include <string>

#include "vibro/diagram.hpp"
#include "vibro/scene_file.hpp"

namespace {

void BM_DiagramTube(benchmark::State& state) {
  const std::string path = std::string(VIBRO_SCENES_DIR) + "/tube_loose_support.toml";
  const auto base = vibro::LoadScene(path, {"run.samples_per_period=0"}).scene;
  vibro::DiagramRequest req;  // every other option at its default (vibro::DiagramDefaults)
  req.scene_at = [&](double w) {
    vibro::Scene s = base;
    s.frequency = w;
    return s;
  };
  req.param = "excitation.frequency";
  req.from = 0.4;
  req.to = 1.6;
  req.sweep_steps = static_cast<int>(state.range(0));
  vibro::DiagramResult d;
  for (auto _ : state) d = vibro::Diagram(req);
  const double total =
      d.sweep_seconds + d.search_seconds + d.continuation_seconds + d.switching_seconds + d.coverage_seconds;
  state.counters["seconds"] = total;
  state.counters["branches"] = static_cast<double>(d.branches.size());
  double points = 0;
  for (const auto& b : d.branches) points += static_cast<double>(b.branch.points.size());
  state.counters["points"] = points;
  state.counters["duplicates"] = d.duplicates;
  long long uncovered = 0, periodic = 0;
  for (const auto& c : d.coverage)
    if (c.branch < 0) {
      ++uncovered;
      periodic += c.period > 0 ? 1 : 0;
    }
  state.counters["uncovered"] = static_cast<double>(uncovered);
  state.counters["uncovered_periodic"] = static_cast<double>(periodic);
  state.counters["cap_reached"] = d.cap_reached ? 1 : 0;
  state.counters["sweep_share"] = d.sweep_seconds / total;
  state.counters["search_share"] = d.search_seconds / total;
  state.counters["continuation_share"] = d.continuation_seconds / total;
  state.counters["switching_share"] = d.switching_seconds / total;
  state.counters["coverage_share"] = d.coverage_seconds / total;
}
BENCHMARK(BM_DiagramTube)->Arg(30)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
