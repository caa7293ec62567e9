// `vibro sweep SCENE --param KEY --from A --to B`: a brute-force bifurcation diagram
// (docs/studies.md).
#include <atomic>
#include <memory>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signals.hpp"
#include "cli/text_format.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/studies.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

int RunSweep(const std::string& path, const std::vector<std::string>& sets, bool json,
             const std::string& key, double from, double to, int steps, int record, bool one_way,
             const std::string& out) {
  const auto loaded = vibro::LoadScene(path, sets);
  vibro::frontend::CheckSweepOptions(vibro::frontend::Naming::kCli, from, to, steps, record);
  // Both ends must be valid values of the key (bad input before any computation).
  const vibro::frontend::SceneOrigin origin{path, std::nullopt, path, sets};
  for (const auto& [v, option] : {std::pair{from, "--from"}, std::pair{to, "--to"}})
    vibro::frontend::SceneAtOption(origin, key, v, option);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!out.empty()) store = vibro::Hdf5Store::Create(out, vibro::frontend::HeaderOf(loaded, vibro::System(loaded.scene)));
  vibro::SweepRequest req;
  // Progress: one scene per run of the sweep, up and (unless --one-way) down.
  vibro::cli::Progress progress("sweep", json);
  const long long runs = steps + 1LL + (one_way ? 0 : steps);  // the way back skips the top
  std::atomic<long long> scenes{0};
  req.scene_at = [&](double v) {
    progress.Update(scenes++, runs, fmt::format("{} = {:.8g}", key, v));
    return vibro::frontend::SceneWith(path, sets, key, v);
  };
  req.from = from;
  req.to = to;
  req.steps = steps;
  req.record = record;
  req.both_ways = !one_way;
  const auto sweep = vibro::Sweep(req, &vibro::cli::StopFlag());
  const bool interrupted = vibro::cli::StopRequested();
  const auto outcome = vibro::frontend::SweepOutcome(sweep, key, interrupted);
  if (store) {
    const vibro::cli::FinalWrite writing;
    store->WriteSweep(sweep, {key, from, to, steps, record, !one_way});
    store->Finish(outcome, sweep.empty() ? vibro::Attractor{} : sweep.back().attractor);
    store.reset();
  }
  if (json) {
    fmt::print("{}\n", vibro::SweepJson(sweep));
  } else {
    // lambda_1: the largest Lyapunov exponent per unit time (run.lyapunov); chaotic: positive
    // beyond its 95 % interval.
    fmt::print("{:>16} {:>5} {:>20} {:>7} {:>12} {:>11} {:>7}\n", key, "dir", "attractor", "period", "SP",
               "lambda_1", "chaotic");
    for (const auto& p : sweep)
      fmt::print("{:>16.10g} {:>5} {:>20} {:>7} {:>12.8f} {:>11} {:>7}\n", p.value, p.upward ? "up" : "down",
                 p.attractor.kind, p.attractor.period ? std::to_string(*p.attractor.period) : "-",
                 p.attractor.sticking_fraction.value_or(0.0), vibro::cli::LargestExponentCell(p.lyapunov),
                 !p.lyapunov || !p.lyapunov->undefined.empty() ? "-" : p.lyapunov->chaotic() ? "yes" : "no");
  }
  if (outcome.status == vibro::RunStatus::kNumericalFailure || outcome.status == vibro::RunStatus::kUndetermined)
    fmt::print(stderr, "vibro: {}\n", outcome.message);
  return ExitCode(outcome.status);
}
