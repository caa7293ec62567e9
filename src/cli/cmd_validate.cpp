// `vibro validate SCENE BRANCH.csv --param KEY`: confirm or refute, point by point, a branch of
// periodic orbits computed by another tool (docs/validation.md). The checks, the computation and
// /validation are frontend/commands.hpp's, shared with Python's vibro.validate.
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signals.hpp"
#include "frontend/commands.hpp"
#include "vibro/summary_json.hpp"

int RunValidate(const ValidateArgs& a) {
  const vibro::frontend::SceneOrigin origin{a.scene, std::nullopt, a.scene, a.sets};
  const auto loaded = origin.Load();
  const vibro::frontend::ValidationSpec spec{a.csv, a.param, a.kind, a.period, a.tolerance, a.sticking_tolerance};
  const auto job = vibro::frontend::PrepareValidation(origin, loaded, spec, vibro::frontend::Naming::kCli,
                                                      &vibro::cli::StopFlag());
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!a.out.empty())
    store = vibro::Hdf5Store::Create(a.out, vibro::frontend::HeaderOf(loaded, vibro::System(loaded.scene)));

  std::optional<vibro::cli::Progress> progress(std::in_place, "points", a.json);
  const auto result = vibro::frontend::RunValidation(job, spec, &vibro::cli::StopFlag(), [&](size_t done, size_t total) {
    progress->Update(static_cast<long long>(done), static_cast<long long>(total));
  });
  progress.reset();
  if (store) {
    const vibro::cli::FinalWrite writing;
    vibro::frontend::FinishValidation(*store, job, result);
    store.reset();
  }
  const auto& checks = result.checks;
  if (a.json) {
    fmt::print("{}\n", vibro::ValidationJson(checks));
  } else {
    // Several contacts: vibro's contact sequence of each orbit, in a column before the detail.
    size_t width = 0;
    for (const auto& c : checks) width = std::max(width, c.orbit.sequence.size());
    const auto sequence = [&](const std::string& text) {
      return width == 0 ? std::string() : fmt::format("  {:<{}}", text, std::max<size_t>(width, 8));
    };
    fmt::print("{:>16} {:>26} {:>10} {:>6} {:>8} {:>12} {:>12}{}  {}\n", a.param, "verdict", "distance", "period",
               "stable", "max|mu|", "SP", sequence("sequence"), "detail");
    for (const auto& c : checks) {
      const auto& o = c.orbit;
      const bool ok = o.status == "converged";
      double lead = 0;
      for (const auto& m : o.multipliers) lead = std::max(lead, std::abs(m));
      fmt::print("{:>16.10g} {:>26} {:>10} {:>6} {:>8} {:>12} {:>12}{}  {}\n", c.value, c.verdict,
                 c.distance ? fmt::format("{:.2e}", *c.distance) : "-",
                 ok ? std::to_string(o.summary.period.value_or(o.period)) : "-",
                 ok ? (o.stable ? "yes" : "no") : "-", ok ? fmt::format("{:.6g}", lead) : "-",
                 ok && o.summary.sticking_fraction ? fmt::format("{:.8f}", *o.summary.sticking_fraction) : "-",
                 sequence(ok ? o.sequence : "-"), c.detail);
    }
    fmt::print("{} of {} points confirmed{}{}\n",
               checks.size() - static_cast<size_t>(result.disagreements + result.undetermined), checks.size(),
               result.disagreements ? fmt::format(", {} disagree", result.disagreements) : "",
               result.undetermined ? fmt::format(", {} undetermined", result.undetermined) : "");
  }
  if (result.interrupted) {
    if (job.interrupted)
      fmt::print(stderr, "vibro: interrupted while the points were read and checked (after {} rows); none was "
                 "computed\n", job.claims.size());
    else
      fmt::print(stderr, "vibro: interrupted after {} of {} points\n", checks.size(), job.claims.size());
    return kExitInterrupted;
  }
  return result.disagreements + result.undetermined > 0 ? kExitDisagree : 0;
}
