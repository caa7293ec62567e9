// What the files of the HDF5 store share (private to src/io): the row tables of a run and of a
// study, the store's state (Hdf5Store::Impl), the file header (hdf5_provenance.cpp) and the
// contained first read and write of a given file (hdf5_probe.cpp).
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <new>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "io/file_lock.hpp"
#include "io/h5_file.hpp"
#include "io/memory_reserve.hpp"
#include "io/write_behind.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/lyapunov.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::store {

// The Lyapunov columns of a row of /attractors or /sweep: the largest exponent and its 95 %
// interval (−∞ for a direction collapsed by sticking, NaN when there are no exponents), and
// chaotic: 1 positive beyond its interval, 0 not, −1 no exponents.
struct LyapunovColumns {
  double largest, low, high;
  std::int8_t chaotic;
};
inline LyapunovColumns LyapunovRow(const std::optional<LyapunovSpectrum>& s) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  if (!s || !s->undefined.empty() || s->exponents.empty()) return {nan, nan, nan, -1};
  const auto ci = s->ci.empty() ? std::pair{nan, nan} : s->ci.front();
  return {s->exponents.front(), ci.first, ci.second, static_cast<std::int8_t>(s->chaotic() ? 1 : 0)};
}

// The int8 enum of /events/kind.
h5::Type EventKindType();

// /events: one row per event.
// /events/contact and /events/simultaneous (docs/contacts.md) are absent from files written before
// several contacts: such a file keeps its seven columns when resumed. The loads columns
// (/events/impulse, energy_dissipated, stick_duration, reaction_integral, reaction_max,
// docs/loads.md) are absent from files written before them: such a file keeps its columns. So are
// a compliant contact phase's /events/peak_time and /events/penetration_max (docs/compliant.md).
// A run's events reach the file in two steps (docs/output.md, "Crash safety, flushes and resume";
// docs/performance.md). Push, in the simulation's thread, copies the event into a tile of kTile
// rows (a few KiB, in the cache), and each full tile column by column into a block of rows
// (`filling`, one buffer per column, written with non-temporal stores: the rows do not evict the
// simulation's own data from the cache). Stage, in the writer thread for a flush behind the run
// (Hdf5Store::Impl::FlushBehind) or in the store's thread for a flush it makes itself, encodes the
// block handed to it (Hand) chunk by chunk straight from those buffers (Column::BeginStaged,
// StageChunk). A block begins at a chunk's first row: the rows of a last, part-filled chunk begin
// the next block too, so that the chunk is written whole once it is (and padded by a flush of
// every row before that). A table opened from a file (a resume) appends the rows to its columns
// instead (Drain), which stage them as a column stages its rows.
struct EventTable {
  h5::Column t, period, offset, kind, xB, v_before, v_after, contact, simultaneous;
  h5::Column impulse, energy, stick_duration, reaction_integral, reaction_max;
  h5::Column peak_time, penetration_max;
  bool has_contact = false, has_loads = false, has_compliant = false;
  void Create(h5::Id g);
  void Open(h5::Id g);
  // The bytes of an element of each column, in the order of Columns(), and of a row.
  static constexpr size_t kColumns = 16;
  static constexpr size_t kElem[kColumns] = {8, 8, 8, 1, 8, 8, 8, 4, 1, 8, 8, 8, 8, 8, 8, 8};
  static constexpr size_t kRowBytes = 110;
  // Hdf5Store::Impl::MaybeFlush hands the rows held (HeldBytes) when they reach kHeldBytes, looking
  // every 1024 rows: a block is allocated once with room for kBlockRows rows, never more in a run
  // (docs/output.md, "Crash safety, flushes and resume").
  static constexpr size_t kTile = 64;
  static constexpr size_t kHeldBytes = size_t{4} << 20;
  static constexpr size_t kBlockRows = kHeldBytes / kRowBytes + 1024 + kTile;
  void Push(const Event& e) {
    tile[tile_n++] = e;
    ++count;
    if (tile_n == kTile) PutTile();
  }
  // The table's rows: in the file, staged, in the columns or held (the store's thread only: it
  // reads no column, which the writer thread may be filling).
  h5::Size Rows() const { return count; }
  size_t HeldBytes() const { return (filling.n + tile_n) * kRowBytes; }
  // The rows held after the last whole chunk (a table made here; else 0).
  size_t RowsPastChunk() const {
    return encodes_rows ? (filling.n + tile_n) % static_cast<size_t>(t.chunk_rows()) : 0;
  }
  // Sets the rows pushed aside for Stage (the rows handed before must have been staged): with
  // whole_chunks, those of whole chunks only.
  void Hand(bool whole_chunks);
  // Stages the rows handed (Hand) in every column, as Column::Stage(whole_chunks) stages a
  // column's: in the writer thread while the run pushes the rows that follow, or in the store's
  // thread after Hand.
  void Stage(bool whole_chunks);
  // Keeps the first `n` rows of the file (a resume: those up to its checkpoint); none held.
  void Truncate(h5::Size n);
  std::vector<h5::Column*> All() {
    std::vector<h5::Column*> all{&t, &period, &offset, &kind, &xB, &v_before, &v_after};
    if (has_contact) all.insert(all.end(), {&contact, &simultaneous});
    if (has_loads)
      all.insert(all.end(), {&impulse, &energy, &stick_duration, &reaction_integral, &reaction_max});
    if (has_compliant) all.insert(all.end(), {&peak_time, &penetration_max});
    return all;
  }

 private:
  // Rows column by column: column c's elements at col[c] (kElem[c] bytes each), n of them, the
  // first `written` of which are in the file already (in a part-filled chunk).
  struct Block {
    h5::Bytes col[kColumns];
    size_t n = 0, capacity = 0, written = 0;
    void Reserve(size_t rows);               // room for `rows`, the n kept
    void Append(const Block& b, size_t from, size_t rows);  // rows [from, from + rows) of b
  };
  h5::Size count = 0;
  Event tile[kTile];
  size_t tile_n = 0;
  Block filling, draining;  // the rows pushed; those handed to Stage
  // Created here (Create): every column encodes the rows given (Column::BeginStaged); the block
  // handed begins at row `first` of the table.
  bool encodes_rows = false;
  h5::Size first = 0;
  void PutTile();    // the tile's rows into `filling`
  void Drain();      // the rows handed, appended to the columns (a table opened)
  std::array<h5::Column*, kColumns> Columns() {
    return {&t, &period, &offset, &kind, &xB, &v_before, &v_after, &contact, &simultaneous, &impulse,
            &energy, &stick_duration, &reaction_integral, &reaction_max, &peak_time, &penetration_max};
  }
};

// /samples and /section: one row per state.
struct StateTable {
  h5::Column t, period, X, V, xB, mode;
  void Create(h5::Id g, h5::Size n);
  // dof: width of X and V (h5::Column::kAnyCols: checked later against the checkpoint).
  void Open(h5::Id g, h5::Size dof);
  void Push(const Sample& s);
  std::vector<h5::Column*> All() { return {&t, &period, &X, &V, &xB, &mode}; }
};

// /loads: one row per period of the run (docs/loads.md §5), each column of width `contacts` (column
// j = contact j): the period's sums of a LoadsRecorder, from which a resumed or extended run
// rebuilds the loads of the whole run. Attribute first_period: the period of row 0.
// The compliant stops' columns (contact phases ended, sums of their peak forces and durations, the
// largest peak: docs/loads.md, "Peak force and contact duration over a run") are absent from files
// written before them: such a file keeps its columns, and its replayed periods do not know their phases.
struct LoadsTable {
  h5::Column impacts, impulse, reaction, energy, work, held, partial;
  h5::Column phases, peak_sum, duration_sum, peak_max;
  bool has_phases = false;
  std::vector<h5::Column*> All() {
    std::vector<h5::Column*> all{&impacts, &impulse, &reaction, &energy, &work, &held, &partial};
    if (has_phases) all.insert(all.end(), {&phases, &peak_sum, &duration_sum, &peak_max});
    return all;
  }
  void Create(h5::Id g, h5::Size contacts);
  void CreatePhases(h5::Id g, h5::Size contacts);
  void Open(h5::Id g);
  void Push(const std::vector<LoadsRow>& rows);
};

// /basin/cells: one row per finished cell of a study, appended as batches finish (resume).
struct CellTable {
  h5::Column index, state, kind, period, impacts, sticking_fraction, periods, stop, stick_count,
      impact_count, z, phases;
  std::vector<h5::Column*> All() {
    return {&index, &state, &kind, &period, &impacts, &sticking_fraction, &periods, &stop,
            &stick_count, &impact_count, &z, &phases};
  }
  void Create(h5::Id g, h5::Size zcols);
  void Open(h5::Id g, h5::Size zcols);
  void Push(size_t i, const CellResult& c, h5::Size zcols);
};

// The root attributes and /model of a new file (provenance, the scene, the model).
void WriteHeader(h5::Id file, const StoreHeader& header);
// What an extension (Hdf5Store::Extend) changes in the header: the scene, periods and the
// provenance attributes become those of the run as extended.
void WriteExtension(h5::Id file, const StoreHeader& header);
// Refuses (InputError) to replace at `path` anything but a vibro file of the same scene and
// command (any vibro file with header.force). Nothing is changed.
void CheckReplaceable(const std::string& path, const StoreHeader& header, bool& existed);

// The refusal of a file that HDF5 cannot open, saying why: no such file (an empty name is shown
// as ''), a directory, not readable, or not an HDF5 file (hdf5_probe.cpp).
InputError CannotOpen(const std::string& path);
// A contained first read of a file given to vibro (hdf5_probe.cpp): the whole file (or the
// objects `only`, absolute paths) is read once by a child process; InputError when that child
// crashes.
void ProbeInChild(const std::string& path, const std::vector<std::string>& only = {});
// Before a resume changes a file, `changes` are made to a copy in a child process; InputError
// when the copy cannot take them.
void ProbeWrite(const std::string& path, const std::function<void(const std::string&)>& changes);

}  // namespace vibro::store

namespace vibro {

struct Hdf5Store::Impl {
  store::FileLock lock;  // first member, released last: held until the file is closed
  std::string path;
  StoreHeader header;
  h5::Handle file, events, samples, section, checkpoint, loads;
  store::EventTable ev;
  store::StateTable sa, se;
  std::optional<Checkpoint> last_checkpoint;
  h5::Size cp_events = 0, cp_samples = 0, cp_sections = 0;  // rows at the last checkpoint
  // /loads (absent until the first period ends): its rows from period loads_first, those at the
  // last checkpoint, and whether a period out of sequence has ended it.
  std::optional<store::LoadsTable> ld;
  long long loads_first = 0;
  h5::Size cp_loads = 0;
  bool loads_ended = false;
  bool checkpoint_on_disk = false;  // a checkpoint has been flushed
  double flush_interval = 1.0;
  std::chrono::steady_clock::time_point last_flush;
  unsigned calls = 0;
  Stats stats;
  h5::Handle basin, cells_group;
  std::optional<store::CellTable> cells;
  h5::Size zcols = 0;

  // A flush whose rows the writer thread encodes (write-behind): written, with the checkpoint
  // and the metadata when `metadata`, by the next Sync() in the store's thread.
  struct Pending {
    bool metadata = false;
    std::optional<Checkpoint> checkpoint;
    h5::Size events = 0, samples = 0, sections = 0, loads = 0;
  };
  std::optional<Pending> pending;
  // Address space held for the library's allocations while the file is open (memory_reserve.hpp);
  // destroyed after the writer thread ends and before the handles close, which it makes room for.
  std::optional<h5::MemoryReserve> reserve;
  // Last member, destroyed first: its thread ends before the file's handles close.
  store::WriteBehind writer;
  void OpenGroups();
  void OpenColumns();
  // Every HDF5 call of the store comes after Sync(), in the store's own thread: the writer
  // thread's encoding under way ends first (its exception is thrown here), the reserve is held
  // (Room) then released for the calls that follow, and the flush the writer encoded is written.
  // HDF5 is only ever called by the store's thread while the writer waits.
  void Sync() {
    writer.Wait();
    Room();
    if (reserve) reserve->Release();
    if (pending) WritePending();
  }
  // The reserve held again (memory_reserve.hpp); when the system refuses it, std::bad_alloc and no
  // HDF5 call any more (h5::Abandon): the file keeps its last flush.
  void Room() {
    if (reserve && !reserve->Take()) {
      h5::Abandon();
      throw std::bad_alloc();
    }
  }
  // A run's periodic flush (write-behind): the rows buffered so far are set aside and encoded by
  // the writer thread while the run goes on, and written by the store's thread at the next one.
  void MaybeFlush();
  void WritePending();
  void StartWriter();  // the writer thread and its HDF5 state, set up with the file
  void CheckRoom();  // WriteError ("no space left") when a metadata flush may not fit
  // The checkpoint `c` (none: nothing) with the row counts at it.
  void WriteCheckpoint(const std::optional<Checkpoint>& c, h5::Size n_events, h5::Size n_samples, h5::Size n_sections,
                       h5::Size n_loads);
  std::vector<h5::Column*> Columns();  // every table's, /events' first
  std::vector<h5::Column*> OtherColumns();  // every table's but /events'
  void Close();
  void Flush();  // in the store's thread, after Sync()
 private:
  void FlushBehind(bool whole_chunks);
  // Writes the staged rows, then the checkpoint and the file's metadata (either thread).
  void WriteStagedAndMetadata(const std::optional<Checkpoint>& c, h5::Size n_events, h5::Size n_samples,
                              h5::Size n_sections, h5::Size n_loads);
};

}  // namespace vibro
