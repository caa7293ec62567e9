// JSON summaries printed by `--json` (docs/cli.md, docs/output.md). nlohmann/json stays inside src/io.
#pragma once

#include <string>

#include "vibro/attractor.hpp"
#include "vibro/branch_check.hpp"
#include "vibro/check.hpp"
#include "vibro/continuation.hpp"
#include "vibro/diagram.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/loads.hpp"
#include "vibro/lyapunov.hpp"
#include "vibro/poincare.hpp"
#include "vibro/studies.hpp"
#include "vibro/scene.hpp"
#include "vibro/score.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace vibro {

// `vibro model --json`: frequencies, forcing, contact, constrained_frequencies, static_reaction,
// modes_kept (+ mode_shapes, modal_masses and contact_modes for the physical form).
std::string ModelJson(const System& system);

// `vibro simulate --json`: status (+ message), engine, t_end, counts, attractor.
// `lyapunov`: the run's Lyapunov exponents ("lyapunov_exponents", "lyapunov_ci", "chaotic"), when
// measured (run.lyapunov); −∞ is written as null.
// `loads`: per contact (docs/loads.md), "loads": [{"contact", "impacts_per_period",
// "impulse_per_period", "reaction_integral_per_period", "mean_force", "dissipated_power",
// "work_rate", "contact_fraction", each with "…_ci": [lo, hi] (null when the run is too short)}],
// and "loads_window": {"first_period", "periods", "blocks", "block_periods", "note", "whole_run",
// "known_from" and "coverage" when not whole_run}.
std::string SimulationJson(const Scene& scene, const RunResult& result, const Attractor& attractor,
                           const LyapunovSpectrum* lyapunov = nullptr, const LoadsSummary* loads = nullptr);

// `vibro orbit --json` (docs/cli.md, docs/output.md).
// `loads`: the orbit's exact per-period contact loads (docs/loads.md), "loads" as simulate's
// without intervals ("loads_note" when they could not be computed).
std::string OrbitJson(const OrbitResult& orbit, OrbitKind kind, const LoadsSummary* loads = nullptr);

// `vibro validate --json`: {"points": [{"value", "verdict", "detail", "distance", "period",
// "stable", "floquet_multipliers", "sticking_fraction", "simulated_distance"}...],
// "disagreements": N}; vibro's own values (null where no orbit converged).
std::string ValidationJson(const std::vector<PointCheck>& checks);

// `vibro score --json`: {"period", "engine", "chatter", "max_time_error", "max_velocity_error",
// "kinds": [{"kind", "theirs", "ours", "matched", "max_time_error", "mean_time_error",
// "max_velocity_error"}], "first_divergence": {"t", "kind", "why", "ours_t"} or null}; errors
// relative to T (times) and to the largest impact speed (velocities).
// complete = false: vibro's run was cut short (interrupted, time limit): "agrees" is null, no
// verdict is drawn from a partial run.
std::string ScoreJson(const ScoreReport& report, const Scene& scene, bool complete = true);

// `vibro continue --json` (docs/cli.md, docs/output.md); every point holds its orbit's exact
// per-period "loads" per contact (docs/loads.md: contact, impacts_per_period, impulse_per_period,
// reaction_integral_per_period, mean_force, dissipated_power, work_rate, contact_fraction; null
// when unknown), and "loads_note" when there is one.
std::string BranchJson(const Branch& branch);
// A branch started by switching at a bifurcation of a stored branch (`vibro continue --switch`):
// BranchJson plus "switch": {"kind", "at" (the bifurcation's λ as located), "start" (λ of the new
// branch's first orbit), "period", "direction" (±1: the side of λ it leaves towards), "half" (in
// words), "x_B_offset", "distance" (from the old orbit at the same λ)}.
struct SwitchRecord {
  std::string kind;
  double at = 0, start = 0;
  int period = 0, direction = 0;
  std::string half;
  double x_B_offset = 0, distance = 0;
};
std::string BranchJson(const Branch& branch, const SwitchRecord& switched);
// `vibro partition --json`: {"params", "levels", "columns": [{"value1", "status", "crossings":
// [{"level", "value"}], "bifurcations": [{"kind", "value"}], "end_down", "end_up", "points":
// [{"value2", "sticking_fraction", "stable", "loads": [...], "loads_note"?}]}]} (the cells, with
// their loads as in BranchJson).
std::string PartitionJson(const std::string& param1, const std::string& param2,
                          const std::vector<double>& levels, const std::vector<PartitionColumn>& columns);

// `vibro attractors --json` and `vibro basin --json`.
std::string StudyJson(const StudyResult& study, const Coordinate& x, const Coordinate& y);

// `vibro sweep --json`.
std::string SweepJson(const std::vector<SweepPoint>& sweep);

// `vibro diagram --json` (docs/diagram.md): {"param", "from", "to", "status", "duplicates",
// "seeds_tried", "seconds": {"sweep", "search", "continuation", "switching", "coverage"},
// "branches": [BranchJson's object plus "index", "origin", "parent", "born_at", "end_first",
// "end_last"], "coverage": [{"value", "direction", "kind", "period", "branch" (null: uncovered),
// "distance", "reason"}], "uncovered" (count), "notes", "sweep": SweepJson's points}.
std::string DiagramJson(const DiagramResult& diagram);

// `vibro check --json`.
std::string CheckJson(const CheckReport& report);

// `vibro info --json`: what a stored run holds.
std::string StoredRunJson(const StoredRun& run);

}  // namespace vibro
