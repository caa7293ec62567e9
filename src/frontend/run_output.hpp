// The output file of `vibro simulate --out FILE [--resume | --extend N]` and of
// `vibro basin --out FILE [--resume]`, as the command line (src/cli/cmd_simulate.cpp,
// cmd_study.cpp) and the Python module (python/src/bindings.cpp) both open it: the checks of
// resume and extend (named as the caller's users write them), the scene of an extension, and the
// history a resumed run gives its classification, so that a resumed or extended run writes the
// same bits as an uninterrupted run of its total length (docs/cli.md "Resuming and extending").
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "frontend/limits.hpp"
#include "vibro/attractor.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/studies.hpp"
#include "vibro/system.hpp"

namespace vibro::frontend {

// How a run's output is opened: a new file, the interrupted run it holds taken up at its last
// checkpoint (--resume), or its run (finished or interrupted) continued for `extend` more periods.
struct RunContinuation {
  bool resume = false;
  std::optional<long long> extend;  // --extend N (any value given, checked against the file)
};

// The scene a run of `given` with output `out` runs: `given` itself, or (extend) `given` with
// run.periods = the stored run's periods + N (ExtendedScene). InputError, with the option named,
// when resume or extend comes without an output, or both are given.
LoadedScene SceneToRun(const LoadedScene& given, const std::string& out, const RunContinuation& how, Naming naming);

// The output of one run, opened in place (it holds the checkpoint the run starts from).
class RunOutput {
 public:
  // Creates `out` (nothing when empty), or opens it to resume or extend: the stored run's
  // checkpoint becomes options.resume_from, and the stored tail of sections and events is
  // given to `recorder` (the classification sees the history it would have had), and the stored
  // per-period loads to `loads` (its loads are those of the whole run, docs/loads.md §5). The
  // store keeps the periods' loads of `loads` as they end (LoadsRecorder::SetSink). Appends the
  // store to options.observers (after `loads`, which must be there already: a period's loads
  // reach the store before the checkpoint that ends it). Throws InputError as
  // Hdf5Store::Create, Resume and Extend do, their options named as `naming` writes them.
  RunOutput(const std::string& out, const LoadedScene& loaded, const System& system, const RunContinuation& how,
            AttractorRecorder& recorder, LoadsRecorder* loads, SimulationOptions& options, Naming naming);
  RunOutput(const RunOutput&) = delete;
  RunOutput& operator=(const RunOutput&) = delete;

  Hdf5Store* store() { return store_.get(); }
  // An interrupted run's message ends with where what it computed is kept: "everything so far is
  // kept, continue with --resume" with an output file, "nothing to resume" without one.
  void NoteInterruption(RunResult& result, Naming naming) const;
  // Writes the run's end (Hdf5Store::Finish) and closes the file; returns its write statistics.
  Hdf5Store::Stats Finish(const RunResult& result, const Attractor& attractor);

 private:
  std::unique_ptr<Hdf5Store> store_;
  StoredRun stored_;
};

// InputError naming the option when a study's resume comes without an output.
void CheckStudyResume(const std::string& out, bool resume, Naming naming);

// The output of a study over `grid`: created (and begun), or (resume) the interrupted study it
// holds, whose computed cells are read into `cells` (CheckStudyResume first); nullptr when `out` is
// empty.
std::unique_ptr<Hdf5Store> OpenStudyOutput(const std::string& out, const StoreHeader& header,
                                           const Hdf5Store::StudyGrid& grid, bool resume,
                                           std::vector<CellResult>& cells, Naming naming);

}  // namespace vibro::frontend
