// `vibro diagram SCENE --param KEY --from A --to B`: the whole one-parameter bifurcation diagram
// (docs/diagram.md).
#include <algorithm>
#include <memory>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signals.hpp"
#include "frontend/diagram.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

int RunDiagram(const std::string& path, const std::vector<std::string>& sets, bool json,
               const vibro::frontend::DiagramSpec& spec, const std::string& out) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::frontend::SceneOrigin origin{path, std::nullopt, path, sets};
  auto req = vibro::frontend::PrepareDiagram(origin, spec, vibro::frontend::Naming::kCli);
  req.stop_requested = &vibro::cli::StopFlag();
  vibro::cli::Progress progress("diagram", json);
  if (progress.active())
    req.progress = [&](const std::string& stage, long long branches) {
      progress.Update(branches, spec.max_branches, stage);
    };
  std::unique_ptr<vibro::Hdf5Store> store;
  if (!out.empty()) store = vibro::Hdf5Store::Create(out, vibro::frontend::HeaderOf(loaded, vibro::System(loaded.scene)));
  const auto d = vibro::Diagram(req);
  const bool interrupted = d.status == "interrupted" || vibro::cli::StopRequested();
  vibro::RunResult r;
  r.status = interrupted ? vibro::RunStatus::kInterrupted : vibro::RunStatus::kOk;
  r.message = interrupted ? "interrupted: the branches finished so far are kept" : "";
  if (store) {
    const vibro::cli::FinalWrite writing;
    store->WriteDiagram(d, {spec.key, spec.from, spec.to, static_cast<int>(spec.steps), static_cast<int>(spec.record),
                            true});
    store->Finish(r, vibro::frontend::NoAttractor());
    store.reset();
  }
  if (json) {
    fmt::print("{}\n", vibro::DiagramJson(d));
    return ExitCode(r.status);
  }
  const auto stable_share = [](const vibro::Branch& b) {
    size_t s = 0;
    for (const auto& p : b.points) s += p.stable ? 1 : 0;
    return fmt::format("{}/{}", s, b.points.size());
  };
  fmt::print("diagram      {} from {} to {}: {} branches ({} found again and kept once), {} seeds continued\n",
             spec.key, spec.from, spec.to, d.branches.size(), d.duplicates, d.seeds_tried);
  for (size_t k = 0; k < d.branches.size(); ++k) {
    const auto& b = d.branches[k];
    const auto& pts = b.branch.points;
    fmt::print("branch {:>3}   period {}, {} points ({} stable), {} = {:.10g} .. {:.10g}; {}\n", k, b.branch.period,
               pts.size(), stable_share(b.branch), spec.key, pts.front().value, pts.back().value,
               b.origin == "seed" ? fmt::format("seeded at {:.10g}", b.born_at)
                                  : fmt::format("switched from branch {} at its {}", b.parent, b.origin));
    if (!pts.front().sequence.empty()) fmt::print("             sequence {}\n", pts.front().sequence);
    fmt::print("             first end ({:.12g}): {}\n", pts.front().value, b.end_first);
    fmt::print("             last end  ({:.12g}): {}\n", pts.back().value, b.end_last);
    for (const auto& x : b.branch.bifurcations)
      fmt::print("             {} at {} = {:#.17g}{}\n", x.kind, spec.key, x.value,
                 x.detail.empty() ? "" : ": " + x.detail);
  }
  int uncovered = 0;
  for (const auto& c : d.coverage) uncovered += c.branch < 0 ? 1 : 0;
  fmt::print("coverage     {} of {} attractors of the sweep and searches lie on a stable branch (within {:.1e}); {} uncovered\n",
             d.coverage.size() - static_cast<size_t>(uncovered), d.coverage.size(), spec.coverage_tolerance, uncovered);
  // The not-periodic ones as windows [a, b] of consecutive values (the chaotic windows); every
  // other uncovered attractor on its own line.
  for (const auto& w : d.uncovered_windows)
    fmt::print("uncovered    {} in [{:.10g}, {:.10g}] ({}, {} value{}): {}\n", spec.key, std::min(w.from, w.to),
               std::max(w.from, w.to), w.source, w.count,
               w.count == 1 ? "" : "s", w.reason);
  for (const auto& c : d.coverage)
    if (c.branch < 0 && !(c.period == 0 && c.kind == "not-periodic"))
      fmt::print("uncovered    {} = {:.10g} ({}): {}: {}\n", spec.key, c.value, c.source, c.kind, c.reason);
  if (d.cap_reached)
    fmt::print("left out     --max-branches {} reached: {} seed{} not continued, {} switch{} not followed (each named "
               "in the notes)\n",
               spec.max_branches, d.seeds_left_out, d.seeds_left_out == 1 ? "" : "s", d.switches_left_out,
               d.switches_left_out == 1 ? "" : "es");
  for (const auto& n : d.notes) fmt::print("note         {}\n", n);
  fmt::print("time         sweep {:.2f} s, searches {:.2f} s, continuation {:.2f} s, switching {:.2f} s, coverage "
             "{:.2f} s\n",
             d.sweep_seconds, d.search_seconds, d.continuation_seconds, d.switching_seconds, d.coverage_seconds);
  if (interrupted) fmt::print(stderr, "vibro: diagram interrupted; the branches finished so far are kept\n");
  return ExitCode(r.status);
}
