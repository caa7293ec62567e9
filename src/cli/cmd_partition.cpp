// `vibro partition SCENE --params KEY1,KEY2`: curves of constant sticking fraction in a
// parameter plane (docs/orbits.md). The checks and the request are frontend/commands.hpp's,
// shared with Python's vibro.partition.
#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signals.hpp"
#include "frontend/commands.hpp"
#include "vibro/continuation.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

namespace {

// The range of the mean contact force and of the normal work rate over a column's cells, per
// contact (docs/loads.md); the cells themselves are in --json and --out.
void PrintCellLoads(const vibro::PartitionColumn& c, const std::string& key2) {
  if (c.points.empty()) return;
  size_t contacts = 0;
  for (const auto& p : c.points) contacts = std::max(contacts, p.loads.size());
  fmt::print("  {:<17} {} points, {} = {:.10g} to {:.10g}\n", "cells", c.points.size(), key2,
             c.points.front().value2, c.points.back().value2);
  for (size_t j = 0; j < contacts; ++j) {
    double f_lo = INFINITY, f_hi = -INFINITY, w_lo = INFINITY, w_hi = -INFINITY;
    for (const auto& p : c.points) {
      if (j >= p.loads.size()) continue;
      if (std::isfinite(p.loads[j].mean_force)) {
        f_lo = std::min(f_lo, p.loads[j].mean_force);
        f_hi = std::max(f_hi, p.loads[j].mean_force);
      }
      w_lo = std::min(w_lo, p.loads[j].work_rate);
      w_hi = std::max(w_hi, p.loads[j].work_rate);
    }
    const auto range = [](double lo, double hi) {
      return lo <= hi ? fmt::format("{:.6g} to {:.6g}", lo, hi) : std::string("unknown");
    };
    fmt::print("  {:<17} mean force {}, work rate {}\n", fmt::format("loads, contact {}", j), range(f_lo, f_hi),
               range(w_lo, w_hi));
  }
}

}  // namespace

int RunPartition(const std::string& path, const std::vector<std::string>& sets, bool json,
                 const PartitionArgs& a) {
  const vibro::frontend::SceneOrigin origin{path, std::nullopt, path, sets};
  const auto loaded = origin.Load();
  // Progress: columns started (each column asks for scenes at its own value of KEY1).
  vibro::cli::Progress progress("columns", json);
  std::mutex seen_mutex;
  std::vector<double> seen;
  auto req = vibro::frontend::PartitionRequestFor(origin, loaded, a.spec, vibro::frontend::Naming::kCli,
                                                  [&](double v1) {
                                                    if (!progress.active()) return;
                                                    std::lock_guard<std::mutex> lock(seen_mutex);
                                                    if (std::find(seen.begin(), seen.end(), v1) == seen.end())
                                                      seen.push_back(v1);
                                                    progress.Update(static_cast<long long>(seen.size()) - 1,
                                                                    a.spec.steps1 + 1LL);
                                                  });
  req.stop_requested = &vibro::cli::StopFlag();
  const vibro::System sys(loaded.scene);
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!a.out.empty()) store = vibro::Hdf5Store::Create(a.out, vibro::frontend::HeaderOf(loaded, sys));  // fails early
  const auto columns = vibro::Partition(req);
  const bool interrupted = vibro::cli::StopRequested();
  if (store) {
    const vibro::cli::FinalWrite writing;
    vibro::frontend::FinishPartition(*store, a.spec, columns, interrupted);
    store.reset();
  }
  const auto& keys = a.spec.params;
  if (json) {
    fmt::print("{}\n", vibro::PartitionJson(keys[0], keys[1], a.spec.levels, columns));
  } else {
    for (const auto& c : columns) {
      fmt::print("{} = {:.10g}: {}\n", keys[0], c.value1, c.status);
      for (const auto& x : c.crossings)
        fmt::print("  sticking fraction {:<6g} at {} = {:.12g}\n", x.level, keys[1], x.value);
      for (const auto& b : c.bifurcations)
        fmt::print("  {:<17} at {} = {:#.17g} (bracket {:.1e})\n", b.kind, keys[1], b.value, b.bracket);
      PrintCellLoads(c, keys[1]);
      for (const auto& sp : c.sequences)
        fmt::print("  sequence {} for {} in [{:.12g}, {:.12g}]\n", sp.sequence, keys[1], sp.from, sp.to);
    }
  }
  return interrupted ? kExitInterrupted : 0;
}
