// `vibro attractors SCENE` and `vibro basin SCENE`: studies over initial states, on threads and
// MPI ranks (docs/studies.md).
#include <memory>
#include <new>
#include <optional>

#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signals.hpp"
#include "cli/text_format.hpp"
#include "frontend/run_output.hpp"
#include "vibro/child_process.hpp"
#include "vibro/distribute.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/studies.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

int RunStudyCommand(const std::string& path, const std::vector<std::string>& sets, bool json,
                    const StudyArgs& args, bool basin) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  vibro::frontend::CheckStudyResume(args.out, args.resume, vibro::frontend::Naming::kCli);
  vibro::frontend::StudySpec spec;
  spec.x = args.x;
  spec.y = args.y;
  spec.x_range = args.x_range;
  spec.y_range = args.y_range;
  spec.grid.assign(args.grid.begin(), args.grid.end());
  spec.samples = args.samples;
  spec.threads = args.threads;
  const auto axes = vibro::frontend::CheckStudyOptions(sys, spec, basin, vibro::frontend::Naming::kCli);
  const vibro::Coordinate& cx = axes.x;
  const vibro::Coordinate& cy = axes.y;
  const auto points = basin ? vibro::GridPoints(cx, cy, args.grid[0], args.grid[1])
                            : vibro::RandomPoints(cx, cy, args.samples, args.seed);
  const vibro::Hdf5Store::StudyGrid grid{cx, cy, basin ? args.grid[0] : static_cast<int>(points.size()),
                                         basin ? args.grid[1] : 1, !args.full_periods};

  // Every process of an MPI job gets here; rank 0 alone reads and writes the file and prints.
  const vibro::Distribution dist;
  std::vector<vibro::CellResult> cells(points.size());
  std::unique_ptr<vibro::Hdf5Store> store;
  std::optional<vibro::InputError> file_problem;
  bool out_of_memory = false, stopped = false;
  std::optional<vibro::Interrupted> stopped_reading;  // said by main ("...; nothing was written")
  if (dist.root() && !args.out.empty()) {
    try {
      store = vibro::frontend::OpenStudyOutput(args.out, vibro::frontend::HeaderOf(loaded, sys), grid, args.resume,
                                               cells, vibro::frontend::Naming::kCli);
    } catch (const vibro::InputError& e) {
      file_problem = e;
    } catch (const std::bad_alloc&) {  // a limit (exit 3), not bad input
      out_of_memory = true;
    } catch (const vibro::Interrupted& e) {  // a stop request during the file's test read (exit 130)
      stopped = true;
      stopped_reading = e;
    } catch (const std::exception& e) {  // every rank must hear of it (no rank left waiting)
      file_problem = vibro::InputError({fmt::format("{}: cannot write the study: {}", args.out, e.what())});
    }
  }
  if (dist.Any(file_problem.has_value() || out_of_memory || stopped)) {
    if (out_of_memory) throw std::bad_alloc();
    // Rank 0 says so, as a stop during any other test read (it ended silently, exit 130).
    if (stopped_reading) throw *stopped_reading;
    if (stopped) return kExitInterrupted;
    if (file_problem) throw *file_problem;
    return kExitBadInput;  // reported by rank 0
  }

  vibro::StudyOptions opt;
  opt.threads = args.threads;
  opt.stop_requested = &vibro::cli::StopFlag();
  if (args.full_periods) opt.settle_remainder = 0;
  // Stable orbits known before the cells run (a pilot grid, the same on every rank).
  if (!args.full_periods) opt.known = vibro::KnownOrbits(sys, loaded.scene, cx, cy, opt);
  // Progress of the cells (not of the pilot) on rank 0's terminal.
  std::optional<vibro::cli::Progress> progress(std::in_place, "cells", json || !dist.root());
  if (progress->active())
    opt.progress = [&](long long done, long long total) { progress->Update(done, total); };
  vibro::RunPendingCells(sys, loaded.scene, cx, cy, points, cells, opt, dist,
                         [&](const std::vector<size_t>& batch) {
                           if (store) store->WriteCells(batch, cells);
                         });
  opt.progress = nullptr;
  progress.reset();
  const bool interrupted = dist.Any(vibro::cli::StopRequested());
  if (!dist.root()) return interrupted ? kExitInterrupted : 0;
  const auto study = vibro::LabelCells(sys, loaded.scene, points, cells, opt);
  if (store) try {
    const vibro::cli::FinalWrite writing;
    vibro::frontend::FinishStudy(*store, study, grid, interrupted);
    store.reset();
  } catch (const vibro::WriteError&) {  // full disk: exit 3 (main)
    throw;
  } catch (const std::runtime_error& e) {  // a resumed file whose damage shows only when written
    fmt::print(stderr, "vibro: cannot write the study to {}: {}; the cells computed are in its /basin/cells\n",
               args.out, e.what());
    return kExitInternal;
  }
  if (json) {
    fmt::print("{}\n", vibro::StudyJson(study, cx, cy));
  } else {
    fmt::print("{} cells over {} ∈ [{}, {}] × {} ∈ [{}, {}]{}\n", study.cells, cx.name, cx.from, cx.to,
               cy.name, cy.from, cy.to, dist.size() > 1 ? fmt::format(" ({} MPI ranks)", dist.size()) : "");
    for (size_t k = 0; k < study.attractors.size(); ++k) {
      const auto& a = study.attractors[k];
      fmt::print("attractor {}: basin fraction {:.4f} ± {:.4f}, example ({}, {}) = ({:.6g}, {:.6g})\n",
                 k, a.basin_fraction, a.basin_fraction_error, cx.name, cy.name, a.example[0], a.example[1]);
      fmt::print("{}", vibro::cli::AttractorText(a.attractor,
                                                 loaded.scene.contacts.size() > 1 ? std::nan("") : loaded.scene.restitution,
                                                 "  ", !loaded.scene.contacts.empty()));
      const std::string mu = vibro::cli::FormatMultipliers(a.orbit.multipliers, 4);
      fmt::print("  orbit        {}{}{}{}\n", a.orbit.status,
                 a.orbit.stable ? (*a.orbit.stable ? ", stable" : ", unstable") : "",
                 mu.empty() ? "" : ", multipliers " + mu,
                 a.orbit.merged > 1 ? fmt::format(" ({} cell classes merged)", a.orbit.merged) : "");
      if (a.lyapunov) fmt::print("{}", vibro::cli::LyapunovText(*a.lyapunov, "  "));
    }
    fmt::print("unresolved fraction {:.4f}, inadmissible fraction {:.4f}{}\n", study.unresolved_fraction,
               study.inadmissible_fraction,
               study.pending_fraction > 0 ? fmt::format(", not computed {:.4f}", study.pending_fraction) : "");
    if (study.unresolved_lyapunov)
      fmt::print("unresolved: the first not-periodic cell, from ({}, {}) = ({:.6g}, {:.6g}):\n{}", cx.name, cy.name,
                 study.unresolved_example[0], study.unresolved_example[1],
                 vibro::cli::LyapunovText(*study.unresolved_lyapunov, "  "));
  }
  if (interrupted) fmt::print(stderr, "vibro: interrupted; {}\n", args.out.empty() ? "results so far printed" : "continue with --resume");
  return interrupted ? kExitInterrupted : 0;
}
