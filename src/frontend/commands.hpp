// The commands `validate`, `score` and `partition` as the command line (src/cli/cmd_*.cpp) and the
// Python module (python/src/bindings.cpp) both run them: the checks of their options (every
// problem in one InputError, the option named as the caller's users write it), the computation
// with a stop flag, and what is written to an HDF5 output. Printing stays with the callers.
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "frontend/frontend.hpp"
#include "frontend/limits.hpp"
#include "vibro/branch_check.hpp"
#include "vibro/continuation.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/score.hpp"
#include "vibro/simulator.hpp"

namespace vibro::frontend {

// The message for a KEY the scene has no number at, with the nearest known key.
std::string NotANumericKey(const std::string& option, const std::string& key);

// ---- validate: a branch of orbits from another tool, point by point (docs/validation.md) ----
struct ValidationSpec {
  std::string csv, param;  // the branch CSV and the scene key its value column sets
  OrbitKind kind = OrbitKind::kAuto;
  int period = 0;  // where a row claims none (0: the first return)
  double tolerance = 1e-6, sticking_tolerance = 1e-6;
};
// The claimed points with the scene at each point's value, all checked before anything is
// computed or written (InputError naming each bad row). `interrupted`: a stop request ended the
// preparation; `claims` and `scenes` hold the rows prepared until then.
struct ValidationJob {
  std::vector<ClaimedPoint> claims;
  std::vector<Scene> scenes;
  bool interrupted = false;
};
// The number of entries of a claimed state (displacement_1..n): the scene's DOFs (physical form)
// or listed modes (modal form).
int ClaimedStateSize(const LoadedScene& loaded);
// An in-memory branch table (a CSV read by ReadBranchCsv, or arrays from Python): the options,
// then every row (its value a valid scene, its state one vibro can start from: ClaimedStart);
// where(point) names a row in messages. `stop` is polled between rows.
ValidationJob PrepareValidationTable(const SceneOrigin& origin, const LoadedScene& loaded, const ValidationSpec& spec,
                                     std::vector<ClaimedPoint> claims,
                                     const std::function<std::string(const ClaimedPoint&)>& where, Naming naming,
                                     const std::atomic<bool>* stop = nullptr);
// The same from spec.csv (rows named FILE:LINE); a stop request while it is read gives an
// interrupted job with no claims.
ValidationJob PrepareValidation(const SceneOrigin& origin, const LoadedScene& loaded, const ValidationSpec& spec,
                                Naming naming, const std::atomic<bool>* stop = nullptr);
struct Validation {
  std::vector<PointCheck> checks;  // the points checked, in order (fewer when interrupted)
  int disagreements = 0;  // verdicts other than confirmed and undetermined
  int undetermined = 0;   // verdicts undetermined (the check could not be made)
  bool interrupted = false;
};
// Checks the points in order; `stop` is polled between points; progress(done, total) after each.
Validation RunValidation(const ValidationJob& job, const ValidationSpec& spec, const std::atomic<bool>* stop,
                         const std::function<void(size_t, size_t)>& progress = {});
// Writes /validation (verdicts, vibro's orbits, the claims) and closes the run.
void FinishValidation(Hdf5Store& store, const ValidationJob& job, const Validation& validation);

// ---- score: another simulator's events against vibro's run of the same scene ----
struct Scoring {
  Scene scene;  // as run: the whole scene (run.periods as given), no dense samples
  ScoreReport report;
  RunResult run;  // vibro's own run (status kInterrupted when stopped)
};
// An in-memory event table (a CSV read by ReadEventsCsv, or arrays from Python): checks window
// and tolerance (finite, > 0) and the table (EventTableProblems: finite, in time order, within the
// scene's run; where(e) names a row in messages), all before anything runs (InputError); then
// runs the whole scene and scores.
Scoring ScoreEventTable(const LoadedScene& loaded, const std::vector<TheirEvent>& theirs,
                        const std::function<std::string(const TheirEvent&)>& where, double window, double tolerance,
                        const std::atomic<bool>* stop, Naming naming);
// The same from an events CSV (rows named FILE:LINE).
Scoring ScoreEventsCsv(const LoadedScene& loaded, const std::string& csv, double window, double tolerance,
                       const std::atomic<bool>* stop, Naming naming);

// ---- partition: curves of constant sticking fraction in a parameter plane ----
struct PartitionSpec {
  std::vector<std::string> params;             // KEY1, KEY2
  std::vector<double> range1, range2, levels;  // A,B of KEY1; C,D of KEY2; sticking fractions
  long long steps1 = 20, period = 0, threads = 0;  // checked against limits.hpp's limits
  std::optional<double> from2;  // where each column starts (default: the scene's KEY2)
};
// Checks `spec` against the scene and builds the request: columns at KEY1 = A + (B − A)·i/steps1,
// each continued in KEY2 over [C, D]. on_scene(value1) is called (from any thread) whenever a
// column asks for a scene. The corners of range1 at the start value must be valid scenes.
PartitionRequest PartitionRequestFor(const SceneOrigin& origin, const LoadedScene& loaded,
                                     const PartitionSpec& spec, Naming naming,
                                     std::function<void(double)> on_scene = {});
// Writes /partition and closes the run (status interrupted or ok).
void FinishPartition(Hdf5Store& store, const PartitionSpec& spec, const std::vector<PartitionColumn>& columns,
                     bool interrupted);

}  // namespace vibro::frontend
