// HDF5 trajectory store (docs/output.md): an Observer that streams events, dense samples and the
// stroboscopic section to a file as a run goes, crash-safe and resumable. The HDF5 C API
// is included by src/io/h5_file.cpp alone (a small RAII wrapper); each record kind has its own
// src/io/hdf5_*.cpp.
//
// Crash safety: rows are buffered in memory and written, with the latest checkpoint, at flushes
// (every `flush_interval` seconds of wall time, when the rows held reach 8 MiB, and at the end).
// Between flushes nothing touches
// the file's metadata (metadata-cache evictions are off) and freed file space is never reused
// (file-space strategy NONE), so the file on disk is always the consistent state of the last
// flush: after a kill -9 it opens as it is and holds everything up to the last flush.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "vibro/attractor.hpp"
#include "vibro/loads.hpp"
#include "vibro/continuation.hpp"
#include "vibro/diagram.hpp"
#include "vibro/observer.hpp"
#include "vibro/poincare.hpp"
#include "vibro/simulator.hpp"
#include "vibro/studies.hpp"

namespace vibro {

// A write to an output file failed (no space left on device, an I/O error): what() is one line,
// "<the system's reason> writing FILE; ...". The file keeps what its last flush wrote (readable,
// resumable) and is not written again by this process. The CLI exits 3.
class WriteError : public std::runtime_error {
 public:
  // from_system: the system said why (ENOSPC, EIO, ...); false when HDF5 failed without a system
  // error, which on a file being resumed means the file itself is damaged (bad input, exit 2).
  explicit WriteError(const std::string& what, bool from_system = true)
      : std::runtime_error(what), from_system_(from_system) {}
  bool from_system() const { return from_system_; }

 private:
  bool from_system_;
};

struct StoreHeader {
  std::string scene_text;  // the scene as run (TOML)
  std::string engine, chatter, method;
  double rtol = 0, atol = 0;
  int dof = 0;
  int samples_per_period = 0;
  long long periods = 0;
  double period = 0;        // T
  double initial_time = 0;  // t0
  int max_period = 32;      // run.max_period: how much history a resume reloads
  // The model in the paper's scaling, written to /model for readers (plots, scripts).
  Eigen::VectorXd frequencies, forcing, contact, contact_shape, damping_ratios,
      constrained_frequencies;
  double s_A = 0, s_B = 0, stop = 0, restitution = 0, amplitude = 0, frequency = 0;
  // A sum of harmonics (docs/harmonics.md; empty for one harmonic): f_h, ω_h, ψ_h, and the modal
  // forcing T_A^(h) of each harmonic per unit amplitude as the rows of an (H, n) matrix.
  Eigen::VectorXd harmonic_amplitudes, harmonic_frequencies, harmonic_phases;
  Eigen::MatrixXd harmonic_forcing;
  // Physical form: mode shapes ψ_i as columns (N, n), x = Σ ψ_i X_i, and a label per physical DOF;
  // empty for the modal form.
  Eigen::MatrixXd mode_shapes;
  std::vector<std::string> dof_labels;
  // Provenance: the command that writes the file ("simulate", "basin", ...; root attribute
  // `command`) and further root string attributes (command_line, options, scene_resolved).
  std::string command;
  std::vector<std::pair<std::string, std::string>> provenance;
  // Create() refuses to replace a vibro file of another scene or command unless `force`.
  bool force = false;
};

// What a stored run holds, read back (for `vibro info`, resume and tests).
struct StoredRun {
  std::string scene_text, engine, chatter, status, message, created, version;
  long long events = 0, samples = 0, sections = 0;
  std::optional<Checkpoint> checkpoint;
  // The per-period loads the file holds (/loads, docs/loads.md §5): those of the periods
  // [loads_known_from, checkpoint period), given back by Hdf5Store::ReplayLoads (set by Resume and
  // Extend; a file written before /loads, or whose /loads does not reach its checkpoint, has
  // loads_known_from = the checkpoint's period).
  long long loads_known_from = 0;
  std::vector<Event> tail_events;  // events of the last periods before the checkpoint
  std::vector<Clock> tail_section_clocks;
  std::vector<Eigen::VectorXd> tail_section_X, tail_section_V;
  std::vector<Mode> tail_section_modes;
  Attractor attractor;  // as written at the end (kind "" when the run did not finish)
  std::string command, git_commit;  // "" in files written before they were stored
  std::vector<std::string> groups;  // the root's groups, e.g. "events", "orbit", "basin"
  // One line per group: its rows and main attributes (e.g. "27 rows, param = excitation.amplitude").
  std::vector<std::string> group_notes;
};

// A group of small datasets written or read at once (/branch, /validation: hdf5_branch.hpp).
struct H5Table {
  struct Array {
    std::string name;
    std::vector<size_t> dims;  // shape (row-major); dims[0] may be 0
    std::vector<double> data;  // stored as float64, or uint8 / int64 when `type` says so
    char type = 'f';           // 'f' float64, 'u' uint8, 'i' int64
  };
  std::vector<Array> arrays;
  std::vector<std::pair<std::string, std::vector<std::string>>> strings;  // 1-D string datasets
  std::vector<std::pair<std::string, std::string>> text;                   // string attributes
  std::vector<std::pair<std::string, long long>> integers;                 // integer attributes
  const Array* Find(const std::string& name) const;
};

class Hdf5Store final : public Observer, public LoadsSink {
 public:
  // Creates (truncates) `path` and writes the header. Throws InputError when the destination
  // cannot be written (read-only, missing directory, full disk): nothing is computed then.
  static std::unique_ptr<Hdf5Store> Create(const std::string& path, const StoreHeader& header,
                                           double flush_interval = 1.0);
  // Opens `path` to continue the run it holds from its last checkpoint (later rows are dropped).
  // Throws InputError when the file holds another scene or no checkpoint.
  static std::unique_ptr<Hdf5Store> Resume(const std::string& path, const StoreHeader& header,
                                           StoredRun& stored, double flush_interval = 1.0);
  // Opens `path` to extend the run it holds, finished or not, to header.periods periods in all
  // (vibro simulate --extend): as Resume, but the file's scene may differ from header.scene_text
  // in run.periods alone, which must grow; a finished run is taken up at its final checkpoint.
  // The file's scene, periods and provenance become the header's. Throws InputError when the
  // scenes differ otherwise, or the run ended in a numerical failure or undetermined.
  static std::unique_ptr<Hdf5Store> Extend(const std::string& path, const StoreHeader& header,
                                           StoredRun& stored, double flush_interval = 1.0);
  ~Hdf5Store() override;

  void OnEvent(const Event& e) override;
  void OnSample(const Sample& s) override;
  void OnSection(const Sample& s) override;
  void OnCheckpoint(const Checkpoint& c) override;
  // The store records events, samples, sections and checkpoints, never resets: a run whose other
  // observers do not read them either builds none (Observer::WantsResets).
  bool WantsResets() const override { return false; }
  // The loads of each period as it ends (LoadsRecorder::SetSink): /loads, one row per period,
  // from the run's first period (or, resumed from a file without them, from its checkpoint's).
  // A period out of sequence ends the table's rows (a resume then finds it short: unknown).
  void OnPeriodLoads(long long period, const std::vector<LoadsRow>& rows) override;
  // A resumed or extended run: the stored rows of /loads, periods [StoredRun::loads_known_from,
  // checkpoint period), one call per period in order (read in blocks).
  void ReplayLoads(const std::function<void(const std::vector<LoadsRow>&)>& each) const;

  // Writes /orbit: scalars period, newton_iterations (int64), stable (bool), residual,
  // section_time (float64) as scalar attributes, the section point X, V and the multipliers
  // (m, 2) as [re, im]. Call before Finish.
  void WriteOrbit(const OrbitResult& orbit);

  // Writes numeric attributes into group `group` (created if needed). Call before Finish.
  void WriteGroup(const std::string& group,
                  const std::vector<std::pair<std::string, std::vector<double>>>& values);

  // Basin studies. The grid of a study (what a resume must match).
  struct StudyGrid {
    Coordinate x, y;
    int nx = 0, ny = 0;
    bool early_stop = true;  // cells stop once settled (vibro basin without --full-periods)
  };
  // Creates /basin (axes and grid as attributes) and the cell table /basin/cells, to which
  // WriteCells appends the finished cells (flushed with the store's flush interval, so that an
  // interrupted or killed study keeps them).
  void BeginStudy(const StudyGrid& grid);
  void WriteCells(const std::vector<size_t>& indices, const std::vector<CellResult>& cells);
  // Opens an interrupted study to continue it: checks the scene and the grid (InputError naming
  // the option that differs), loads the finished cells into `cells` (sized nx·ny by the caller)
  // and drops an earlier label map and table.
  static std::unique_ptr<Hdf5Store> ResumeStudy(const std::string& path, const StoreHeader& header,
                                                const StudyGrid& grid, std::vector<CellResult>& cells,
                                                double flush_interval = 1.0);
  // Writes the labels /basin/labels (ny, nx) int32 (−1 unresolved, −2 inadmissible, −3 not
  // computed) and the attractor table /attractors/* (one row per label). Call before Finish.
  void WriteStudy(const StudyResult& study, const StudyGrid& grid);

  // A sweep (vibro sweep --out): /sweep with one row per run, in the order run (up, then down).
  struct SweepSpec {
    std::string param;
    double from = 0, to = 0;
    int steps = 0, record = 0;
    bool both_ways = true;
  };
  void WriteSweep(const std::vector<SweepPoint>& sweep, const SweepSpec& spec);

  // Writes a continuation branch: /branch (one row per point: value, sticking_fraction (NaN for
  // none), stable (uint8), x_B, section_phase, max_multiplier, stick_phases count, events
  // (strings), multipliers (N, m, 2) as [re, im] padded with NaN; attributes param, period, end,
  // status) and /bifurcations (value, kind, detail, bracket). Call before Finish.
  // `group` (absolute, existing): the three groups go under it (a diagram's branches,
  // /diagram/branches/NNN/branch ...); empty: at the root.
  void WriteBranch(const Branch& branch, const std::string& group = "");  // hdf5_branch.cpp

  // Writes a diagram (hdf5_diagram.cpp, docs/diagram.md): /sweep as WriteSweep, /diagram
  // (attributes param, from, to, status, duplicates, seeds_tried, stage times; notes), every
  // branch under /diagram/branches/NNN as WriteBranch writes /branch (with attributes origin,
  // parent, born_at, end_first, end_last) and the coverage table /diagram/coverage. Call before
  // Finish.
  void WriteDiagram(const DiagramResult& diagram, const SweepSpec& spec);

  // Writes `table` into the new group `group` (absolute path). Call before Finish.
  void WriteTable(const std::string& group, const H5Table& table);

  // Writes a partition: /partition with attributes param1, param2, levels and the tables
  // columns (value1, status), crossings (value1, level, value2) and boundaries (value1, value2,
  // kind) as datasets. Call before Finish.
  void WritePartition(const std::string& param1, const std::string& param2,
                      const std::vector<double>& levels, const std::vector<PartitionColumn>& columns);

  // Writes the final status, message, counts and attractor (/attractor; removed when
  // `attractor.kind` is empty: studies and branches have no single attractor), and closes the
  // file.
  void Finish(const RunResult& result, const Attractor& attractor);

  struct Stats {
    long long flushes = 0;
    double flush_seconds = 0;  // wall time spent writing
  };
  Stats stats() const;

 private:
  struct Impl;
  explicit Hdf5Store(std::unique_ptr<Impl> impl);
  static std::unique_ptr<Hdf5Store> Continue(const std::string& path, const StoreHeader& header,
                                             StoredRun& stored, double flush_interval, bool extend);
  std::unique_ptr<Impl> impl_;
};

// Reads a stored run; `tail_periods` > 0 also loads the events and section rows of the last
// tail_periods periods before the checkpoint. Throws InputError when the file is not a vibro run.
StoredRun ReadStoredRun(const std::string& path, int tail_periods = 0);

// Reads every dataset (numeric ones as float64) and attribute (strings and integers) of `group`.
// Throws InputError naming the file and group when either is missing.
H5Table ReadTable(const std::string& path, const std::string& group);

// The section point (time, modal X and Ẋ) of the orbit that `vibro orbit --out` stored in /orbit.
// Throws InputError naming the file when it holds none.
InitialOverride ReadOrbitSection(const std::string& path);

}  // namespace vibro
