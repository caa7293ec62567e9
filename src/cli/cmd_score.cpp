// `vibro score SCENE EVENTS.csv`: another simulator's events against vibro's own run of the same
// scene (docs/validation.md). The run and the scoring are frontend/commands.hpp's, shared with
// Python's vibro.score. Exit 4 when the two runs diverge beyond --tolerance.
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
  // A run cut short (stop request, --time-limit) draws no verdict: its missing events would count
  // as divergences.
  const bool complete = s.run.status != vibro::RunStatus::kInterrupted;
  if (a.json) {
    fmt::print("{}\n", vibro::ScoreJson(rep, s.scene, complete));
  } else {
    fmt::print("scene        {} (engine {}, chatter {}), T = {:.10g}, {} periods\n", a.scene,
               vibro::ToString(s.scene.run.engine), vibro::ToString(s.scene.run.chatter), rep.period,
               s.scene.run.periods);
    fmt::print("{:<14} {:>8} {:>8} {:>8} {:>8} {:>9} {:>14} {:>14} {:>14}\n", "kind", "theirs", "vibro", "matched",
               "in acc.", "matched%", "max |dt|/T", "mean |dt|/T", "max |dv|/|v|");
    for (const auto& k : rep.kinds) {
      // Errors are over matched events only: none is printed where nothing matched.
      const auto err = [&](double v) { return k.matched > 0 ? fmt::format("{:.3e}", v) : std::string("-"); };
      fmt::print("{:<14} {:>8} {:>8} {:>8} {:>8} {:>9} {:>14} {:>14} {:>14}\n", vibro::ToString(k.kind), k.theirs,
                 k.ours, k.matched, k.in_accumulation + k.ours_in_accumulation,
                 !k.scored            ? std::string("unscored")
                 : k.matched_fraction ? fmt::format("{:.1f}", 100.0 * *k.matched_fraction)
                                      : std::string("-"),
                 err(k.max_time_error), err(k.mean_time_error),
                 k.max_velocity_error ? fmt::format("{:.3e}", *k.max_velocity_error) : "-");
    }
    if (!complete) {
      fmt::print("verdict: none: vibro's run was interrupted at t = {:.10g} (the counts above are of the events "
                 "up to there)\n", s.run.t_end);
    } else if (rep.divergence) {
      const auto& d = *rep.divergence;
      fmt::print("first divergence at t = {:.15g} ({}, {}): {}{}\n", d.t, vibro::ToString(d.kind),
                 d.side == "vibro" ? "vibro's event" : "their event", d.why,
                 d.side == "theirs" && d.ours_t ? fmt::format(" (vibro: t = {:.15g})", *d.ours_t) : "");
      fmt::print("verdict: diverges ({} of {} events matched; tolerance {:g} T)\n", rep.matched,
                 rep.matched + rep.unmatched, a.tolerance);
    } else {
      fmt::print("verdict: agrees: every event of both runs matched within {:g} T ({} matched)\n", a.tolerance,
                 rep.matched);
    }
  }
  if (s.run.status == vibro::RunStatus::kInterrupted) return kExitInterrupted;
  if (s.run.status != vibro::RunStatus::kOk) {
    fmt::print(stderr, "vibro: vibro's own run stopped early: {}\n", s.run.message);
    return kExitNumerical;
  }
  return rep.agrees() ? 0 : kExitDisagree;
}
