// `vibro partition SCENE --params KEY1,KEY2`: curves of constant sticking fraction in a
// parameter plane (docs/orbits.md).
#include <algorithm>
#include <memory>
#include <mutex>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signals.hpp"
#include "vibro/continuation.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

int RunPartition(const std::string& path, const std::vector<std::string>& sets, bool json,
                 const PartitionArgs& a) {
  const auto loaded = vibro::LoadScene(path, sets);
  std::vector<std::string> problems;
  if (a.params.size() != 2) problems.push_back("--params: expected KEY1,KEY2");
  if (a.range1.size() != 2 || !(a.range1[0] < a.range1[1]))
    problems.push_back("--range1: expected A,B with A < B");
  if (a.range2.size() != 2 || !(a.range2[0] < a.range2[1]))
    problems.push_back("--range2: expected C,D with C < D");
  if (a.steps1 < 1) problems.push_back("--steps1: expected N ≥ 1");
  if (a.levels.empty()) problems.push_back("--sticking-fraction: expected S1,S2,... in (0, 1)");
  for (double s : a.levels)
    if (!(s > 0 && s < 1)) problems.push_back(fmt::format("--sticking-fraction {}: not in (0, 1)", s));
  std::optional<double> start2 = a.from2;
  if (a.params.size() == 2) {
    for (const auto& k : a.params)
      if (!vibro::SceneNumber(loaded.text_as_run, k))
        problems.push_back(NotANumericKey("--params", k));
    if (!start2) start2 = vibro::SceneNumber(loaded.text_as_run, a.params[1]);
  }
  if (start2 && a.range2.size() == 2 && !(*start2 >= a.range2[0] && *start2 <= a.range2[1]))
    problems.push_back(fmt::format("--from2 {}: outside --range2", *start2));
  if (!problems.empty()) throw vibro::InputError(problems);
  vibro::PartitionRequest req;
  // Progress: columns started (each column asks for scenes at its own value of KEY1).
  vibro::cli::Progress progress("columns", json);
  std::mutex seen_mutex;
  std::vector<double> seen;
  req.scene_at = [&](double v1, double v2) {
    if (progress.active()) {
      std::lock_guard<std::mutex> lock(seen_mutex);
      if (std::find(seen.begin(), seen.end(), v1) == seen.end()) seen.push_back(v1);
      progress.Update(static_cast<long long>(seen.size()) - 1, a.steps1 + 1LL);
    }
    std::vector<std::string> s = sets;
    s.push_back(fmt::format("{}={:.17g}", a.params[0], v1));
    return vibro::frontend::SceneWith(path, s, a.params[1], v2);
  };
  for (int i = 0; i <= a.steps1; ++i)
    req.values1.push_back(a.range1[0] + (a.range1[1] - a.range1[0]) * i / a.steps1);
  // The corners of --range1 at the start value must be valid scenes (bad input, exit 2, before
  // anything is written); values of KEY2 outside its valid range just end a column's branch.
  for (double v1 : {a.range1[0], a.range1[1]}) req.scene_at(v1, *start2);
  req.start2 = *start2;
  req.lo2 = a.range2[0];
  req.hi2 = a.range2[1];
  req.levels = a.levels;
  req.orbit.period = a.period;
  req.threads = a.threads;
  req.stop_requested = &vibro::cli::StopFlag();
  const vibro::System sys(loaded.scene);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!a.out.empty()) store = vibro::Hdf5Store::Create(a.out, vibro::frontend::HeaderOf(loaded, sys));  // fails early
  const auto columns = vibro::Partition(req);
  const bool interrupted = vibro::cli::StopRequested();
  if (store) {
    const vibro::cli::FinalWrite writing;
    store->WritePartition(a.params[0], a.params[1], a.levels, columns);
    vibro::RunResult r;
    r.status = interrupted ? vibro::RunStatus::kInterrupted : vibro::RunStatus::kOk;
    store->Finish(r, vibro::frontend::NoAttractor());
    store.reset();
  }
  if (json) {
    fmt::print("{}\n", vibro::PartitionJson(a.params[0], a.params[1], a.levels, columns));
  } else {
    for (const auto& c : columns) {
      fmt::print("{} = {:.10g}: {}\n", a.params[0], c.value1, c.status);
      for (const auto& x : c.crossings)
        fmt::print("  sticking fraction {:<6g} at {} = {:.12g}\n", x.level, a.params[1], x.value);
      for (const auto& b : c.bifurcations)
        fmt::print("  {:<17} at {} = {:.12g}\n", b.kind, a.params[1], b.value);
    }
  }
  return interrupted ? kExitInterrupted : 0;
}
