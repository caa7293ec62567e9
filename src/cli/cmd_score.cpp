// `vibro score SCENE EVENTS.csv`: another simulator's events against vibro's own run of the same
// scene (docs/validation.md).
#include <cmath>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "vibro/events_csv.hpp"
#include "vibro/score.hpp"
#include "vibro/simulator.hpp"
#include "vibro/summary_json.hpp"

namespace {


struct EventLog final : vibro::Observer {
  std::vector<vibro::Event> events;
  void OnEvent(const vibro::Event& e) override { events.push_back(e); }
};

}  // namespace

int RunScore(const ScoreArgs& a) {
  std::vector<std::string> problems;
  if (!(a.window > 0)) problems.push_back(fmt::format("--window {}: expected a positive number", a.window));
  if (!(a.tolerance > 0)) problems.push_back(fmt::format("--tolerance {}: expected a positive number", a.tolerance));
  if (!problems.empty()) throw vibro::InputError(problems);
  const auto loaded = vibro::LoadScene(a.scene, a.sets);
  const auto theirs = vibro::ReadEventsCsv(a.csv);
  vibro::Scene scene = loaded.scene;
  const vibro::System sys(scene);
  const double T = sys.period();
  // Long enough to cover their last event.
  const double span = theirs.back().t - scene.initial_time;
  scene.run.periods = std::max<long long>(1, static_cast<long long>(std::ceil(span / T + a.window)) + 1);
  scene.run.samples_per_period = 0;
  EventLog log;
  vibro::SimulationOptions opt;
  opt.observers = {&log};
  const auto run = vibro::Simulate(sys, scene, opt);
  vibro::ScoreOptions so;
  so.window = a.window;
  so.tolerance = a.tolerance;
  const auto rep = vibro::ScoreEvents(log.events, theirs, T, so);
  if (a.json) {
    fmt::print("{}\n", vibro::ScoreJson(rep, scene));
  } else {
    fmt::print("scene        {} (engine {}, chatter {}), T = {:.10g}, {} periods\n", a.scene,
               vibro::ToString(scene.run.engine), vibro::ToString(scene.run.chatter), T, scene.run.periods);
    fmt::print("{:<14} {:>8} {:>8} {:>8} {:>8} {:>14} {:>14} {:>14}\n", "kind", "theirs", "vibro", "matched",
               "in acc.", "max |dt|/T", "mean |dt|/T", "max |dv|/|v|");
    for (const auto& k : rep.kinds)
      fmt::print("{:<14} {:>8} {:>8} {:>8} {:>8} {:>14.3e} {:>14.3e} {:>14}\n", vibro::ToString(k.kind), k.theirs,
                 k.ours, k.matched, k.in_accumulation, k.max_time_error, k.mean_time_error,
                 k.max_velocity_error ? fmt::format("{:.3e}", *k.max_velocity_error) : "-");
    if (rep.divergence)
      fmt::print("first divergence at t = {:.15g} ({}): {}{}\n", rep.divergence->t, vibro::ToString(rep.divergence->kind),
                 rep.divergence->why,
                 rep.divergence->ours_t ? fmt::format(" (vibro: t = {:.15g})", *rep.divergence->ours_t) : "");
    else
      fmt::print("no divergence: every event matched within {:g} T\n", a.tolerance);
  }
  if (run.status != vibro::RunStatus::kOk) {
    fmt::print(stderr, "vibro: vibro's own run stopped early: {}\n", run.message);
    return kExitNumerical;
  }
  return 0;
}
