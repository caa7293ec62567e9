// `vibro prove` (docs/prove.md): time to prove a periodic orbit, from the orbit search (a 200-period
// transient and Newton) to the certificate. Targets (issue 40): a 1-3 DOF impacting orbit, damped or
// with several contacts, in at most 100 ms; a sticking or chattering orbit in at most 1 s. Counters: the box width and the
// number of impacts per period.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "vibro/continuation.hpp"
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
// Damped (ζ = 0.02): the 2-DOF chain's three-impact orbit at f = 3 and the 3-DOF clearance chain.
void BM_Prove2DofDampedImpact(benchmark::State& s) {
  Prove(s, "chain2_damped.toml", {"excitation.amplitude=3"}, vibro::OrbitKind::kImpact);
}
void BM_Prove3DofDampedImpact(benchmark::State& s) {
  Prove(s, "../../tests/scenes/damped3_clearance.toml", {}, vibro::OrbitKind::kImpact);
}
// Two contacts: the damped tube in its two-sided loose support (physical form, 2 DOF).
void BM_Prove2DofTwoSidedTube(benchmark::State& s) {
  Prove(s, "tube_loose_support.toml", {}, vibro::OrbitKind::kImpact);
}
// Sticking orbits of several modes held at a plastic stop (r = 0): the held flow enclosed.
void BM_Prove2DofSticking(benchmark::State& s) {
  Prove(s, "chain2.toml", {"stop.restitution=0"}, vibro::OrbitKind::kSticking);
}
void BM_Prove2DofDampedSticking(benchmark::State& s) {
  Prove(s, "chain2_damped.toml", {"stop.restitution=0"}, vibro::OrbitKind::kSticking);
}
void BM_Prove3DofSticking(benchmark::State& s) { Prove(s, "chain3.toml", {}, vibro::OrbitKind::kSticking); }
// Sticking orbits held on sets of contacts (docs/prove.md "Sticking orbits held on sets of contacts"):
// issue 37's scene A (two masses on their preloaded stops, r = 0: four segments, both held for a third
// of the period) and the damped 3-DOF chain whose first two masses are held together.
void BM_ProveHeldSet2Dof(benchmark::State& s) {
  Prove(s, "../../tests/scenes/contacts_quad_start_two_stops.toml", {}, vibro::OrbitKind::kAuto);
}
void BM_ProveHeldSet3DofDamped(benchmark::State& s) {
  Prove(s, "../../tests/scenes/contacts_two_held_chain.toml", {}, vibro::OrbitKind::kAuto);
}
// A bifurcation point: the tube's grazing near ω = 1.3646 (docs/prove.md "Grazings"), located by a
// continuation in the set-up (not timed), proven from the branch point just before it (Bifurcation::point): the orbit
// search from that state, Newton on the orbit with its tangency, the two Krawczyk tests, the gaps.
void BM_ProveTubeGrazing(benchmark::State& state) {
  const std::string file = std::string(VIBRO_SCENES_DIR) + "/tube_loose_support.toml";
  const auto at = [&](double w) {
    return vibro::LoadScene(file, {"run.samples_per_period=0", "excitation.frequency=" + std::to_string(w)}).scene;
  };
  vibro::ContinuationRequest c;
  c.scene_at = [&](double w) {
    auto scene = vibro::LoadScene(file, {"run.samples_per_period=0"}).scene;
    scene.frequency = w;
    return scene;
  };
  c.orbit.kind = vibro::OrbitKind::kImpact;
  c.from = 0.9;
  c.to = 1.5;
  const auto branch = vibro::Continue(c);
  // The grazing nearest 1.3646 (the branch goes on through grazings and passes others near the
  // pitchfork), proven from its own orbit before it: Bifurcation::point, the branch's point next to
  // it on the side the branch came from.
  const vibro::Bifurcation* graze = nullptr;
  for (const auto& b : branch.bifurcations)
    if (b.kind == "grazing" && (graze == nullptr || std::abs(b.value - 1.3646) < std::abs(graze->value - 1.3646)))
      graze = &b;
  if (graze == nullptr || graze->point < 0 || graze->point >= static_cast<long long>(branch.points.size())) {
    state.SkipWithError("no grazing located");
    return;
  }
  const auto& before = branch.points[static_cast<size_t>(graze->point)];
  vibro::BifurcationRequest req;
  req.kind = "grazing";
  req.parameter = "excitation.frequency";
  req.value = graze->value;
  req.bracket = graze->bracket;
  req.start = vibro::InitialOverride{before.section_time, before.X, before.V};
  req.period = branch.period;
  req.start_value = before.value;
  auto scene = at(0.9);
  scene.frequency = graze->value;
  const vibro::System sys(scene);
  double width = 0;
  for (auto _ : state) {
    const auto r = vibro::ProveBifurcation(sys, scene, req);
    if (!r.proven) state.SkipWithError(("not proven: " + r.reason).c_str());
    width = r.box_width;
  }
  state.counters["interval_width"] = width;
}
// Segments of a branch (docs/prove.md "Along a branch"): the tube over the amplitude, 0.3 to 0.302,
// and over the forcing frequency, 0.9 to 0.901 (in a tube along the family's tangent, Taylor form in
// ω): both ends' orbit searches (200-period transients, Newton) and the proof of every piece.
void Segment(benchmark::State& state, const char* key, double lo, double hi) {
  const std::string file = std::string(VIBRO_SCENES_DIR) + "/tube_loose_support.toml";
  const auto at = [&](double v) {
    return vibro::LoadScene(file, {"run.samples_per_period=0", std::string(key) + "=" + std::to_string(v)}).scene;
  };
  const auto a = at(lo), b = at(hi);
  const vibro::System sa(a), sb(b);
  vibro::ProofRequest req;
  req.kind = vibro::OrbitKind::kImpact;
  std::size_t pieces = 0, stable = 0;
  for (auto _ : state) {
    const auto r = vibro::ProveOrbitOverInterval(sa, a, req, sb, b, req);
    if (!r.front().proven) state.SkipWithError(("not proven: " + r.front().reason).c_str());
    pieces = r.size();
    stable = static_cast<std::size_t>(std::count_if(r.begin(), r.end(), [](const auto& p) { return p.stability == "stable"; }));
  }
  state.counters["pieces"] = static_cast<double>(pieces);
  state.counters["stable_pieces"] = static_cast<double>(stable);
}
// Over the frequency each piece is also proven stable on sub-pieces (docs/prove.md "Stability along a
// segment"); 0.954 to 0.955 lies 4e-4 below the pitchfork, where the spectral radius is 0.995.
void BM_ProveTubeAmplitudeSegment(benchmark::State& s) { Segment(s, "excitation.amplitude", 0.3, 0.302); }
void BM_ProveTubeFrequencySegment(benchmark::State& s) { Segment(s, "excitation.frequency", 0.9, 0.901); }
void BM_ProveTubeFrequencySegmentNearPitchfork(benchmark::State& s) {
  Segment(s, "excitation.frequency", 0.954, 0.955);
}

BENCHMARK(BM_ProveTubeAmplitudeSegment)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProveTubeFrequencySegment)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProveTubeFrequencySegmentNearPitchfork)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProveTubeGrazing)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove1DofImpact)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove2DofSticking)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove2DofDampedSticking)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove3DofSticking)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProveHeldSet2Dof)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProveHeldSet3DofDamped)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove2DofDampedImpact)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove3DofDampedImpact)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove2DofTwoSidedTube)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove1DofSticking)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove1DofChattering)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prove2DofImpact)->Unit(benchmark::kMillisecond);

}  // namespace
