// `vibro prove` (docs/prove.md): time to prove a periodic orbit, from the orbit search (a 200-period
// transient and Newton) to the certificate. The targets: a 1-DOF impacting orbit in under
// 1 s, a chattering sticking orbit in under 10 s; the 2-DOF chain's impacting orbits are measured beside them. Counters: the box width and the
// number of impacts per period.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "vibro/prove.hpp"
#include "vibro/scene_file.hpp"

namespace {

void Prove(benchmark::State& state, const char* file, std::vector<std::string> sets, vibro::OrbitKind kind) {
  sets.push_back("run.samples_per_period=0");
  const auto loaded = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, sets);
  const vibro::System sys(loaded.scene);
  vibro::ProofRequest req;
  req.kind = kind;
  // The default transient of 200 periods (as `vibro prove`): 20 do not settle Fig. 5's orbit.
  double width = 0;
  std::size_t events = 0;
  for (auto _ : state) {
    const auto r = vibro::ProveOrbit(sys, loaded.scene, req);
    if (!r.proven) state.SkipWithError(("not proven: " + r.reason).c_str());
    width = r.box_width;
    events = r.events.size();
  }
  state.counters["box_width"] = width;
  state.counters["events"] = static_cast<double>(events);
}

// Fig. 5's stable single-impact orbit (r = 0.75, ω = 10, f = 1.1).
void BM_Prove1DofImpact(benchmark::State& s) { Prove(s, "fig05_coexistence.toml", {}, vibro::OrbitKind::kImpact); }
// Fig. 4's period-2 sticking orbit (r = 0): no orbit search, the release is fixed by the model.
void BM_Prove1DofSticking(benchmark::State& s) { Prove(s, "fig04_subharmonic.toml", {}, vibro::OrbitKind::kSticking); }
// Fig. 8's sticking orbit with chattering (r = 0.75): some 50 impacts followed, then the tail bounded.
void BM_Prove1DofChattering(benchmark::State& s) { Prove(s, "fig08_preload.toml", {}, vibro::OrbitKind::kSticking); }
// The 2-DOF chain at f = 5: six impacts over two periods, a 4 x 4 monodromy (Rump's method).
void BM_Prove2DofImpact(benchmark::State& s) {
  Prove(s, "chain2.toml", {"excitation.amplitude=5"}, vibro::OrbitKind::kImpact);
}
BENCHMARK(BM_Prove1DofImpact)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove1DofSticking)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove1DofChattering)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove2DofImpact)->Unit(benchmark::kMillisecond);

}  // namespace
