// `vibro score SCENE EVENTS.csv`: another simulator's events against vibro's own run of the same
// scene (docs/validation.md). The run and the scoring are frontend/commands.hpp's, shared with
// Python's vibro.score.
#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/stop_signals.hpp"
#include "frontend/commands.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/summary_json.hpp"

int RunScore(const ScoreArgs& a) {
  const auto loaded = vibro::LoadScene(a.scene, a.sets);
  const auto s = vibro::frontend::ScoreEventsCsv(loaded, a.csv, a.window, a.tolerance, &vibro::cli::StopFlag(),
                                                 vibro::frontend::Naming::kCli);
  const auto& rep = s.report;
  if (a.json) {
    fmt::print("{}\n", vibro::ScoreJson(rep, s.scene));
  } else {
    fmt::print("scene        {} (engine {}, chatter {}), T = {:.10g}, {} periods\n", a.scene,
               vibro::ToString(s.scene.run.engine), vibro::ToString(s.scene.run.chatter), rep.period,
               s.scene.run.periods);
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
  if (s.run.status == vibro::RunStatus::kInterrupted) return kExitInterrupted;
  if (s.run.status != vibro::RunStatus::kOk) {
    fmt::print(stderr, "vibro: vibro's own run stopped early: {}\n", s.run.message);
    return kExitNumerical;
  }
  return 0;
}
