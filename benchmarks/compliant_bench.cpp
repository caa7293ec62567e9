// The cost of a compliant contact phase against a rigid impact (docs/compliant.md, "Cost"): the
// tube of data/scenes/tube_compliant_support.toml run by the exact engine, its two-sided support
// compliant (k = 1000, c = 2, rule "force"), against the same scene with rigid stops of the
// equivalent restitution e(ζ) (docs/compliant.md, "The rigid model beside it"). Each run records
// its events (an observer, as `vibro simulate` does, so that the contact phases' loads are
// computed). Counter s/contact: the run's time per contact, a contact phase (its entry, its exit,
// its loads and the flight after) or an impact (and the flight after). The bound: a contact
// phase costs at most 2× a rigid impact, i.e. s/contact(compliant) / s/contact(rigid) ≤ 2 in one
// run. Arg 0: rigid, 1: compliant, 2: compliant without an observer (the phases' loads, the peak
// force and penetration searches, not computed: what the search for them costs).
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

#include <fmt/format.h>

#include "vibro/rigid_model.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace {

struct Counter final : vibro::Observer {
  long long events = 0;
  void OnEvent(const vibro::Event&) override { ++events; }
};

std::string Scene(bool compliant) {
  const double k = 1000.0, c = 2.0;
  // ζ = c/(2√(k m)) with m = 1, the effective mass at the tube's DOF (docs/compliant.md).
  const double e = vibro::EquivalentRestitution(c / (2 * std::sqrt(k)), vibro::Separation::kForce);
  const std::string law = compliant ? fmt::format("stiffness = {}\ndamping = {}\nseparation = \"force\"\n", k, c)
                                    : fmt::format("restitution = {}\n", e);
  return "[structure]\nmass = [[2.0, 0.0], [0.0, 1.0]]\nstiffness = [[4.0, -1.0], [-1.0, 1.0]]\nforcing_dof = 0\n"
         "damping_ratios = [0.02, 0.02]\n"
         "[[contact]]\ndof = 1\nside = \"below\"\nposition = -0.1\n" + law +
         "[[contact]]\ndof = 1\nside = \"above\"\nposition = 0.1\n" + law +
         "[excitation]\namplitude = 0.3\nfrequency = 0.9\n"
         "[initial]\ndisplacement = [0.0, 0.0]\nvelocity = [0.0, 0.0]\n"
         "[run]\nperiods = 200\nsamples_per_period = 0\nlyapunov = false\n";
}

void BM_CompliantContactVsRigidImpact(benchmark::State& state) {
  const bool compliant = state.range(0) >= 1, observed = state.range(0) <= 1;
  const auto loaded = vibro::ParseScene(Scene(compliant), "compliant_bench");
  const vibro::System sys(loaded.scene);
  long long contacts = 0;
  for (auto _ : state) {
    Counter count;
    vibro::SimulationOptions opt;
    if (observed) opt.observers = {&count};
    const vibro::RunResult r = vibro::Simulate(sys, loaded.scene, opt);
    if (r.status != vibro::RunStatus::kOk) state.SkipWithError(r.message.c_str());
    contacts += compliant ? r.counts.releases : r.counts.impacts + r.counts.accumulations;
    benchmark::DoNotOptimize(count.events);
  }
  state.counters["s/contact"] =
      benchmark::Counter(static_cast<double>(contacts), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["contacts/run"] = static_cast<double>(contacts) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_CompliantContactVsRigidImpact)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace
