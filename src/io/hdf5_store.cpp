// The HDF5 store of a run (docs/output.md): /events, /samples, /section and /checkpoint written
// as the run goes, flushes, resume and the final status. Studies, orbits, sweeps and branches
// are written by hdf5_study.cpp, hdf5_orbit.cpp, hdf5_sweep.cpp and hdf5_branch.cpp; the HDF5 C
// API itself is behind io/h5_file.hpp.
#include "vibro/hdf5_store.hpp"

#include <sys/stat.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <new>
#include <optional>
#include <stdexcept>

#include <initializer_list>

#include <fmt/format.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "io/hdf5_store_impl.hpp"
#include "vibro/scene_file.hpp"

namespace vibro {

namespace store {

h5::Type EventKindType() {
  std::vector<std::pair<std::string, std::int8_t>> members;
  for (auto k : {EventKind::kImpact, EventKind::kAccumulation, EventKind::kStick, EventKind::kRelease,
                 EventKind::kGrazing})
    members.emplace_back(ToString(k), static_cast<std::int8_t>(k));
  return h5::Type::Enum8(members);
}

void EventTable::Create(h5::Id g) {
  count = 0;
  const h5::Type kind_type = EventKindType();
  t = h5::Column(g, "t", h5::Type::F64(), 0);
  period = h5::Column(g, "period", h5::Type::I64(), 0);
  offset = h5::Column(g, "offset", h5::Type::F64(), 0);
  kind = h5::Column(g, "kind", kind_type, 0);
  xB = h5::Column(g, "x_B", h5::Type::F64(), 0);
  v_before = h5::Column(g, "v_before", h5::Type::F64(), 0);
  v_after = h5::Column(g, "v_after", h5::Type::F64(), 0);
  contact = h5::Column(g, "contact", h5::Type::I32(), 0);
  simultaneous = h5::Column(g, "simultaneous", h5::Type::I8(), 0);
  has_contact = true;
  impulse = h5::Column(g, "impulse", h5::Type::F64(), 0);
  energy = h5::Column(g, "energy_dissipated", h5::Type::F64(), 0);
  stick_duration = h5::Column(g, "stick_duration", h5::Type::F64(), 0);
  reaction_integral = h5::Column(g, "reaction_integral", h5::Type::F64(), 0);
  reaction_max = h5::Column(g, "reaction_max", h5::Type::F64(), 0);
  has_loads = true;
  peak_time = h5::Column(g, "peak_time", h5::Type::F64(), 0);
  penetration_max = h5::Column(g, "penetration_max", h5::Type::F64(), 0);
  has_compliant = true;
  encodes_rows = true;
  for (h5::Column* c : All()) encodes_rows = encodes_rows && c->encodes_rows_given();
  first = 0;
}

void EventTable::Open(h5::Id g) {
  const h5::Type kind_type = EventKindType();
  t = h5::Column::Open(g, "t", h5::Type::F64());
  period = h5::Column::Open(g, "period", h5::Type::I64());
  offset = h5::Column::Open(g, "offset", h5::Type::F64());
  kind = h5::Column::Open(g, "kind", kind_type);
  xB = h5::Column::Open(g, "x_B", h5::Type::F64());
  v_before = h5::Column::Open(g, "v_before", h5::Type::F64());
  v_after = h5::Column::Open(g, "v_after", h5::Type::F64());
  count = t.rows();
  // The optional columns come in groups, each whole or absent (a file cut by hand is refused).
  const auto group = [&](std::initializer_list<const char*> names) {
    size_t present = 0;
    for (const char* n : names) present += h5::Exists(g, n) ? 1 : 0;
    if (present != 0 && present != names.size())
      throw std::runtime_error(fmt::format("/events has {} of the {} columns {}, {}, …: all or none",
                                           present, names.size(), *names.begin(), *(names.begin() + 1)));
    return present != 0;
  };
  group({"contact", "simultaneous"});
  group({"impulse", "energy_dissipated", "stick_duration", "reaction_integral", "reaction_max"});
  group({"peak_time", "penetration_max"});
  has_contact = h5::Exists(g, "contact");
  if (has_contact) {
    contact = h5::Column::Open(g, "contact", h5::Type::I32());
    simultaneous = h5::Column::Open(g, "simultaneous", h5::Type::I8());
  }
  has_loads = h5::Exists(g, "impulse");
  if (has_loads) {
    impulse = h5::Column::Open(g, "impulse", h5::Type::F64());
    energy = h5::Column::Open(g, "energy_dissipated", h5::Type::F64());
    stick_duration = h5::Column::Open(g, "stick_duration", h5::Type::F64());
    reaction_integral = h5::Column::Open(g, "reaction_integral", h5::Type::F64());
    reaction_max = h5::Column::Open(g, "reaction_max", h5::Type::F64());
  }
  has_compliant = h5::Exists(g, "peak_time");
  if (has_compliant) {
    peak_time = h5::Column::Open(g, "peak_time", h5::Type::F64());
    penetration_max = h5::Column::Open(g, "penetration_max", h5::Type::F64());
  }
}

void EventTable::Block::Reserve(size_t rows) {
  if (rows <= capacity) return;
  for (size_t c = 0; c < kColumns; ++c) {
    h5::Bytes grown(rows * kElem[c]);
    if (n > 0) std::memcpy(grown.data(), col[c].data(), n * kElem[c]);
    col[c].swap(grown);
  }
  capacity = rows;
}

static_assert(EventTable::kRowBytes == 13 * 8 + 4 + 1 + 1, "a row of /events: 13 float64/int64, contact, kind, simultaneous");

void EventTable::Block::Append(const Block& b, size_t from, size_t rows) {
  if (rows == 0) return;
  Reserve(std::max({n + rows, capacity, kBlockRows}));
  for (size_t c = 0; c < kColumns; ++c)
    std::memcpy(col[c].data() + n * kElem[c], b.col[c].data() + from * kElem[c], rows * kElem[c]);
  n += rows;
}

namespace {

// Writes `count` elements of type T, field(tile[i]), at `out`: 8-byte words with non-temporal
// stores (the rows are read by the writer thread, not by the simulation's).
template <class T, class F>
void PutColumn(const Event* tile, size_t count, unsigned char* out, F field) {
#if defined(__SSE2__)
  constexpr size_t per_word = 8 / sizeof(T);
  size_t i = 0;
  for (; i + per_word <= count; i += per_word, out += 8) {
    T v[per_word];
    for (size_t k = 0; k < per_word; ++k) v[k] = static_cast<T>(field(tile[i + k]));
    long long w;
    std::memcpy(&w, v, 8);
    _mm_stream_si64(reinterpret_cast<long long*>(out), w);
  }
  for (; i < count; ++i, out += sizeof(T)) {
    const T v = static_cast<T>(field(tile[i]));
    std::memcpy(out, &v, sizeof(T));
  }
#else
  for (size_t i = 0; i < count; ++i, out += sizeof(T)) {
    const T v = static_cast<T>(field(tile[i]));
    std::memcpy(out, &v, sizeof(T));
  }
#endif
}

}  // namespace

void EventTable::PutTile() {
  if (filling.n + tile_n > filling.capacity) filling.Reserve(std::max(kBlockRows, 2 * filling.capacity));
  unsigned char* out[kColumns];
  for (size_t c = 0; c < kColumns; ++c) out[c] = filling.col[c].data() + filling.n * kElem[c];
  const Event* r = tile;
  const size_t m = tile_n;
  PutColumn<double>(r, m, out[0], [](const Event& e) { return e.t; });
  PutColumn<std::int64_t>(r, m, out[1], [](const Event& e) { return e.clock.period; });
  PutColumn<double>(r, m, out[2], [](const Event& e) { return e.clock.offset; });
  PutColumn<std::int8_t>(r, m, out[3], [](const Event& e) { return static_cast<std::int8_t>(e.kind); });
  PutColumn<double>(r, m, out[4], [](const Event& e) { return e.x_B; });
  PutColumn<double>(r, m, out[5], [](const Event& e) { return e.v_before; });
  PutColumn<double>(r, m, out[6], [](const Event& e) { return e.v_after; });
  PutColumn<std::int32_t>(r, m, out[7], [](const Event& e) { return e.contact; });
  PutColumn<std::int8_t>(r, m, out[8], [](const Event& e) { return e.simultaneous ? 1 : 0; });
  PutColumn<double>(r, m, out[9], [](const Event& e) { return e.impulse; });
  PutColumn<double>(r, m, out[10], [](const Event& e) { return e.energy_dissipated; });
  PutColumn<double>(r, m, out[11], [](const Event& e) { return e.stick_duration; });
  PutColumn<double>(r, m, out[12], [](const Event& e) { return e.reaction_integral; });
  PutColumn<double>(r, m, out[13], [](const Event& e) { return e.reaction_max; });
  PutColumn<double>(r, m, out[14], [](const Event& e) { return e.peak_time; });
  PutColumn<double>(r, m, out[15], [](const Event& e) { return e.penetration_max; });
  filling.n += m;
  tile_n = 0;
}

void EventTable::Hand(bool whole_chunks) {
  if (tile_n > 0) PutTile();
#if defined(__SSE2__)
  _mm_sfence();  // the non-temporal stores seen by the thread that stages the rows
#endif
  std::swap(filling, draining);
  filling.n = filling.written = 0;
  if (!encodes_rows) return;
  // A block begins at a chunk's first row: the rows after the last whole chunk begin the next one
  // (Hdf5Store::Impl::MaybeFlush hands the rows soon after a chunk is full: few of them). With
  // whole_chunks they are not staged now; otherwise they are, padded, and written again with the
  // rows that follow.
  const size_t chunk = static_cast<size_t>(t.chunk_rows()), rest = draining.n % chunk;
  filling.Append(draining, draining.n - rest, rest);
  if (!whole_chunks) {
    filling.written = rest;
  } else {
    draining.n -= rest;
    if (draining.n == 0) filling.written = draining.written;  // no whole chunk: as they were
  }
}

void EventTable::Drain() {
  const auto columns = Columns();
  for (size_t c = 0; c < kColumns; ++c) {
    const bool present = c < 7 || (c < 9 ? has_contact : c < 14 ? has_loads : has_compliant);
    if (present) columns[c]->PushElems(draining.col[c].data(), draining.n);
  }
  draining.n = 0;
}

void EventTable::Stage(bool whole_chunks) {
  if (!encodes_rows) {
    Drain();
    for (h5::Column* c : All()) c->Stage(whole_chunks);
    return;
  }
  const size_t n = draining.n, chunk = static_cast<size_t>(t.chunk_rows());
  // Nothing new: the part-filled chunk holds the rows it has in the file already.
  if (n > draining.written) {
    const auto columns = Columns();
    for (h5::Column* c : columns) c->BeginStaged(first, n);
    for (size_t k = 0; k * chunk < n; ++k)
      for (size_t c = 0; c < kColumns; ++c)
        columns[c]->StageChunk(k, draining.col[c].data() + k * chunk * kElem[c], std::min(chunk, n - k * chunk));
  }
  first += n / chunk * chunk;
  draining.n = draining.written = 0;
}

void EventTable::Truncate(h5::Size n) {
  for (h5::Column* c : All()) c->Truncate(n);
  filling.n = draining.n = filling.written = draining.written = tile_n = 0;
  encodes_rows = false;  // opened: its columns stage the rows appended to them
  count = n;
}

void StateTable::Create(h5::Id g, h5::Size n) {
  t = h5::Column(g, "t", h5::Type::F64(), 0);
  period = h5::Column(g, "period", h5::Type::I64(), 0);
  X = h5::Column(g, "X", h5::Type::F64(), n);
  V = h5::Column(g, "V", h5::Type::F64(), n);
  xB = h5::Column(g, "x_B", h5::Type::F64(), 0);
  mode = h5::Column(g, "mode", h5::Type::I8(), 0);
}

void StateTable::Open(h5::Id g, h5::Size dof) {
  t = h5::Column::Open(g, "t", h5::Type::F64());
  period = h5::Column::Open(g, "period", h5::Type::I64());
  X = h5::Column::Open(g, "X", h5::Type::F64(), dof);
  V = h5::Column::Open(g, "V", h5::Type::F64(), dof);
  xB = h5::Column::Open(g, "x_B", h5::Type::F64());
  mode = h5::Column::Open(g, "mode", h5::Type::I8());
}

void StateTable::Push(const Sample& s) {
  t.Push(s.t);
  period.Push(static_cast<std::int64_t>(s.clock.period));
  X.PushRow(s.X);
  V.PushRow(s.V);
  xB.Push(s.x_B);
  mode.Push(static_cast<std::int8_t>(s.mode));
}

void LoadsTable::Create(h5::Id g, h5::Size contacts) {
  impacts = h5::Column(g, "impacts", h5::Type::F64(), contacts);
  impulse = h5::Column(g, "impulse", h5::Type::F64(), contacts);
  reaction = h5::Column(g, "reaction_integral", h5::Type::F64(), contacts);
  energy = h5::Column(g, "energy_dissipated", h5::Type::F64(), contacts);
  work = h5::Column(g, "work", h5::Type::F64(), contacts);
  held = h5::Column(g, "held", h5::Type::F64(), contacts);
  partial = h5::Column(g, "partial", h5::Type::I8(), contacts);
  CreatePhases(g, contacts);
}

void LoadsTable::CreatePhases(h5::Id g, h5::Size contacts) {
  phases = h5::Column(g, "contact_phases", h5::Type::F64(), contacts);
  peak_sum = h5::Column(g, "peak_force_sum", h5::Type::F64(), contacts);
  duration_sum = h5::Column(g, "contact_duration_sum", h5::Type::F64(), contacts);
  peak_max = h5::Column(g, "peak_force_max", h5::Type::F64(), contacts);
  has_phases = true;
}

void LoadsTable::Open(h5::Id g) {
  impacts = h5::Column::Open(g, "impacts", h5::Type::F64(), h5::Column::kAnyCols);
  const h5::Size n = impacts.cols();
  impulse = h5::Column::Open(g, "impulse", h5::Type::F64(), n);
  reaction = h5::Column::Open(g, "reaction_integral", h5::Type::F64(), n);
  energy = h5::Column::Open(g, "energy_dissipated", h5::Type::F64(), n);
  work = h5::Column::Open(g, "work", h5::Type::F64(), n);
  held = h5::Column::Open(g, "held", h5::Type::F64(), n);
  partial = h5::Column::Open(g, "partial", h5::Type::I8(), n);
  has_phases = h5::Exists(g, "contact_phases");
  if (has_phases) {
    phases = h5::Column::Open(g, "contact_phases", h5::Type::F64(), n);
    peak_sum = h5::Column::Open(g, "peak_force_sum", h5::Type::F64(), n);
    duration_sum = h5::Column::Open(g, "contact_duration_sum", h5::Type::F64(), n);
    peak_max = h5::Column::Open(g, "peak_force_max", h5::Type::F64(), n);
  }
}

void LoadsTable::Push(const std::vector<LoadsRow>& rows) {
  for (const LoadsRow& r : rows) impacts.Push(r.impacts);
  for (const LoadsRow& r : rows) impulse.Push(r.impulse);
  for (const LoadsRow& r : rows) reaction.Push(r.reaction);
  for (const LoadsRow& r : rows) energy.Push(r.energy);
  for (const LoadsRow& r : rows) work.Push(r.work);
  for (const LoadsRow& r : rows) held.Push(r.held);
  for (const LoadsRow& r : rows) partial.Push(static_cast<std::int8_t>(r.partial ? 1 : 0));
  if (!has_phases) return;
  for (const LoadsRow& r : rows) phases.Push(r.phases);
  for (const LoadsRow& r : rows) peak_sum.Push(r.peak_sum);
  for (const LoadsRow& r : rows) duration_sum.Push(r.duration_sum);
  for (const LoadsRow& r : rows) peak_max.Push(r.peak_max);
}

}  // namespace store

namespace {

// No /loads table at a checkpoint (WriteCheckpoint).
constexpr h5::Size kNoLoads = ~h5::Size{0};

// The event counts, as attributes of a checkpoint or of the finished file.
void WriteCounts(h5::Id where, const EventCounts& counts) {
  h5::WriteInt(where, "impacts", counts.impacts);
  h5::WriteInt(where, "accumulations", counts.accumulations);
  h5::WriteInt(where, "sticks", counts.sticks);
  h5::WriteInt(where, "releases", counts.releases);
  h5::WriteInt(where, "grazings", counts.grazings);
}

// What to say when a resume is refused because the scenes differ: when they differ in run.periods
// alone (`stored` is the file's), how to resume the stored run or extend it; else nothing.
std::string PeriodsHint(const std::string& stored, const std::string& given, const std::string& path) {
  try {
    const auto held = ParseScene(stored, path);
    if (ParseScene(stored, path, {"run.periods=1"}).text_as_run != ParseScene(given, path, {"run.periods=1"}).text_as_run)
      return "";
    return fmt::format(" (only run.periods differs: the file's run is for {} periods; resume it with --set "
                       "run.periods={}, or continue it for N more periods with --extend N)",
                       held.scene.run.periods, held.scene.run.periods);
  } catch (const InputError&) {
    return "";
  }
}

}  // namespace

void Hdf5Store::Impl::OpenGroups() {
  events = h5::OpenGroup(file.get(), "/events");
  samples = h5::OpenGroup(file.get(), "/samples");
  section = h5::OpenGroup(file.get(), "/section");
  checkpoint = h5::OpenGroup(file.get(), "/checkpoint");
}

void Hdf5Store::Impl::OpenColumns() {
  ev.Open(events.get());
  sa.Open(samples.get(), static_cast<h5::Size>(header.dof));
  se.Open(section.get(), static_cast<h5::Size>(header.dof));
}

void Hdf5Store::Impl::MaybeFlush() {
  if ((++calls & 1023u) != 0) return;
  const auto now = std::chrono::steady_clock::now();
  // Also when the rows held reach 4 MiB, their whole chunks: a fast run would otherwise grow its
  // buffers for a whole interval (143 MiB for 20 000 periods of Fig. 8), and the page faults and
  // copies of that growth cost more than the writes; and the writer thread compresses and writes
  // them while the simulation computes the next rows (a short run would otherwise leave it all to
  // Finish).
  // The events count as pushed (EventTable::HeldBytes: the columns' rows are the writer's), the
  // other tables' rows as buffered in their columns.
  constexpr size_t kFlushBytes = store::EventTable::kHeldBytes;
  size_t held = ev.HeldBytes();
  for (h5::Column* c : OtherColumns()) held += c->pending_bytes();
  if (std::chrono::duration<double>(now - last_flush).count() >= flush_interval) {
    FlushBehind(false);
  } else if (held >= kFlushBytes || (held >= kFlushBytes / 2 && ev.RowsPastChunk() < 1024 + ev.kTile)) {
    // From half the rows on, as soon as the events fill a chunk (this is looked at every 1024
    // rows): few rows after it, which begin the next block (EventTable::Hand).
    FlushBehind(true);
  } else if (pending && !writer.Busy()) {
    // The writer has encoded the last flush: written now rather than at the next one.
    Sync();
    Room();
  } else {
    Room();  // taken back after a stretch of HDF5 calls that did not (a result written, stats())
  }
}

void Hdf5Store::Impl::WriteCheckpoint(const std::optional<Checkpoint>& checkpoint_at, h5::Size n_events,
                                      h5::Size n_samples, h5::Size n_sections, h5::Size n_loads) {
  if (!checkpoint_at) return;
  const Checkpoint& c = *checkpoint_at;
  const h5::Id g = checkpoint.get();
  h5::WriteInt(g, "period", c.clock.period);
  h5::WriteDouble(g, "offset", c.clock.offset);
  h5::WriteDoubles(g, "X", std::vector<double>(c.X.data(), c.X.data() + c.X.size()));
  h5::WriteDoubles(g, "V", std::vector<double>(c.V.data(), c.V.data() + c.V.size()));
  h5::WriteInt(g, "mode", static_cast<int>(c.mode));
  h5::WriteDouble(g, "gap", c.gap);
  h5::WriteInt(g, "start_kind", c.start_kind);
  h5::WriteDouble(g, "chatter_first_speed", c.chatter_first_speed);
  h5::WriteDouble(g, "chatter_last_speed", c.chatter_last_speed);
  h5::WriteInt(g, "sample_index", c.sample_index);
  WriteCounts(g, c.counts);
  h5::WriteInt(g, "chatter_accumulations_predicted", c.chatter_predicted);
  h5::WriteInt(g, "chatter_impacts_followed", c.chatter_followed);
  h5::WriteDouble(g, "chatter_max_estimated_error", c.chatter_max_error);
  if (!c.gaps.empty()) {
    // Several contacts (docs/contacts.md): the held or start contact, every gap and flight start,
    // and the counts per contact (rows of impacts, accumulations, sticks, releases, grazings,
    // simultaneous).
    h5::WriteInt(g, "contact", c.contact);
    h5::WriteDoubles(g, "gaps", c.gaps);
    h5::WriteDoubles(g, "start_kinds", std::vector<double>(c.start_kinds.begin(), c.start_kinds.end()));
    std::vector<double> counts;
    for (const EventCounts& k : c.contact_counts)
      for (long long v : {k.impacts, k.accumulations, k.sticks, k.releases, k.grazings, k.simultaneous})
        counts.push_back(static_cast<double>(v));
    h5::WriteDoubles(g, "contact_counts", counts, 6);
    if (!c.held.empty()) h5::WriteDoubles(g, "held", std::vector<double>(c.held.begin(), c.held.end()));
  }
  if (!c.stick_duration.empty()) {
    // The open sticking phase of each contact (docs/loads.md): duration, ∫R dt, max R (NaN: none).
    h5::WriteDoubles(g, "stick_duration", c.stick_duration);
    h5::WriteDoubles(g, "reaction_integral", c.reaction_integral);
    h5::WriteDoubles(g, "reaction_max", c.reaction_max);
  }
  if (!c.compliant_account.empty()) {
    // Compliant stops (docs/compliant.md): the open contact phase's account (4 per contact) and
    // the relaxing flight (its contact, −1: none, and the surface's offset).
    h5::WriteDoubles(g, "compliant_account", c.compliant_account, 4);
    h5::WriteInt(g, "relax_contact", c.relax_contact);
    h5::WriteDoubles(g, "relax_surface", std::vector<double>{c.relax_surface});
  }
  h5::WriteInt(g, "events", static_cast<long long>(n_events));
  h5::WriteInt(g, "samples", static_cast<long long>(n_samples));
  h5::WriteInt(g, "sections", static_cast<long long>(n_sections));
  // The rows of /loads at the checkpoint: the periods [/loads first_period, + loads_periods).
  if (n_loads == kNoLoads) h5::DeleteAttr(g, "loads_periods");
  else h5::WriteInt(g, "loads_periods", static_cast<long long>(n_loads));
}

std::vector<h5::Column*> Hdf5Store::Impl::Columns() {
  std::vector<h5::Column*> all = ev.All();
  for (h5::Column* c : OtherColumns()) all.push_back(c);
  return all;
}

std::vector<h5::Column*> Hdf5Store::Impl::OtherColumns() {
  std::vector<h5::Column*> all;
  for (auto* t : {&sa, &se})
    for (h5::Column* c : t->All()) all.push_back(c);
  if (cells)
    for (h5::Column* c : cells->All()) all.push_back(c);
  if (ld)
    for (h5::Column* c : ld->All()) all.push_back(c);
  return all;
}

void Hdf5Store::Impl::Close() {
  Sync();
  reserve.reset();  // its room is the closing's
  for (h5::Column* c : Columns()) *c = h5::Column();
  cells.reset();
  cells_group.Reset();
  ld.reset();
  loads.Reset();
  basin.Reset();
  events.Reset();
  samples.Reset();
  section.Reset();
  checkpoint.Reset();
  file.Reset();
}

void Hdf5Store::Impl::WriteStagedAndMetadata(const std::optional<Checkpoint>& c, h5::Size n_events,
                                              h5::Size n_samples, h5::Size n_sections, h5::Size n_loads) {
  h5::Silence();  // the writer thread's own error stack (HDF5 keeps one per thread)
  const h5::WritingScope writing;
  const auto t0 = std::chrono::steady_clock::now();
  // The rows' chunks first (a failed write leaves the file as it was: they lie past its end);
  // then, when there is room for it, the metadata that makes them part of the file.
  for (h5::Column* col : Columns()) col->WriteStaged();
  WriteCheckpoint(c, n_events, n_samples, n_sections, n_loads);
  CheckRoom();
  h5::FlushFile(file.get());
  ++stats.flushes;
  stats.flush_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void Hdf5Store::Impl::Flush() {
  Sync();
  const h5::WritingScope writing;
  ev.Hand(false);
  ev.Stage(false);
  for (h5::Column* c : OtherColumns()) c->Stage();
  if (last_checkpoint) checkpoint_on_disk = true;  // at the end of this flush
  WriteStagedAndMetadata(last_checkpoint, cp_events, cp_samples, cp_sections, ld ? cp_loads : kNoLoads);
  last_flush = std::chrono::steady_clock::now();
  Room();
}

void Hdf5Store::Impl::WritePending() {
  const Pending p = std::move(*pending);
  pending.reset();
  const h5::WritingScope writing;
  if (p.metadata) WriteStagedAndMetadata(p.checkpoint, p.events, p.samples, p.sections, p.loads);
  else WriteStagedAndMetadata(std::nullopt, 0, 0, 0, 0);
}

void Hdf5Store::Impl::StartWriter() {
  // The writer thread starts with the file: a thread the system refuses (ulimit -v) fails now,
  // before any computation, not at the first flush. It never calls HDF5.
  writer.Start([] {});
  Sync();
}

void Hdf5Store::Impl::FlushBehind(bool whole_chunks) {
  Sync();  // the flush before, encoded by the writer, written
  Room();   // the rows' buffers below are the run's memory, not the library's room
  // The writer encodes the staged rows' chunks (no HDF5 call), and the store's thread writes them
  // at the next Sync. The other tables' rows are staged here: their columns' buffers stay the
  // simulation's. The events are handed as they were pushed (EventTable::Hand): the writer splits
  // them into their columns and stages those, which the simulation's thread does not touch.
  // The checkpoint's rows are all in the file only when every row before it is staged (a flush of
  // whole chunks may leave some buffered): it is written with the interval's flushes, which stage
  // every row.
  ev.Hand(whole_chunks);
  for (h5::Column* c : OtherColumns()) c->Stage(whole_chunks);
  Pending p;
  if (!whole_chunks) {
    if (last_checkpoint) checkpoint_on_disk = true;
    p = {true, last_checkpoint, cp_events, cp_samples, cp_sections, ld ? cp_loads : kNoLoads};
    last_flush = std::chrono::steady_clock::now();
  }
  pending = std::move(p);
  writer.Start([this, columns = Columns(), whole_chunks] {
    ev.Stage(whole_chunks);
    for (h5::Column* c : columns) c->EncodeStaged();
  });
}

void Hdf5Store::Impl::CheckRoom() {
  // A metadata flush that may not fit is not started: a half-written one could spoil the
  // consistent state of the last flush, which the file then keeps (status "running", as after a
  // kill: --resume continues it).
  const double bytes = static_cast<double>(h5::MetadataBytes(file.get())) + 256.0 * 1024;
  struct statvfs vfs {};
  if (statvfs(path.c_str(), &vfs) != 0) return;
  if (static_cast<double>(vfs.f_bavail) * static_cast<double>(vfs.f_frsize) >= bytes) return;
  h5::MarkFailed(file.get());
  throw WriteError(fmt::format("no space left on device writing {}", path));
}

Hdf5Store::Hdf5Store(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Hdf5Store::~Hdf5Store() = default;

std::unique_ptr<Hdf5Store> Hdf5Store::Create(const std::string& path, const StoreHeader& h,
                                             double flush_interval) {
  h5::Silence();
  // One writer per file: an existing file is locked before it is examined, a new one as it is made.
  store::FileLock lock = store::FileLock::Acquire(path, false);
  bool existed = false;
  store::CheckReplaceable(path, h, existed);  // never clobber what is not ours
  bool created = false;
  if (!lock.held()) lock = store::FileLock::Acquire(path, true, &created);
  if (created) existed = false;
  auto impl = std::make_unique<Impl>();
  impl->lock = std::move(lock);
  impl->path = path;
  impl->header = h;
  impl->flush_interval = flush_interval;
  try {
    impl->file = h5::CreateFile(path);
    const h5::Id f = impl->file.get();
    for (const char* g : {"/events", "/samples", "/section", "/attractor", "/checkpoint", "/model"})
      h5::CreateGroup(f, g);
    impl->OpenGroups();
    impl->ev.Create(impl->events.get());
    impl->sa.Create(impl->samples.get(), static_cast<h5::Size>(h.dof));
    impl->se.Create(impl->section.get(), static_cast<h5::Size>(h.dof));
    store::WriteHeader(f, h);
    impl->Flush();
    impl->StartWriter();
    impl->reserve.emplace();  // the library's room from now on (memory_reserve.hpp)
    // A destination that is (nearly) full fails now, before any computation.
    struct statvfs vfs{};
    if (statvfs(path.c_str(), &vfs) == 0 &&
        static_cast<double>(vfs.f_bavail) * static_cast<double>(vfs.f_frsize) < 1024.0 * 1024.0)
      throw std::runtime_error("less than 1 MiB free on the destination");
  } catch (const std::exception& e) {
    impl.reset();
    // Remove only a regular file this call created (never a device such as /dev/full).
    struct stat now{};
    if (!existed && stat(path.c_str(), &now) == 0 && S_ISREG(now.st_mode)) std::remove(path.c_str());
    // Out of memory is a limit (exit 3, MemoryError in Python), not bad input.
    if (dynamic_cast<const std::bad_alloc*>(&e) != nullptr) throw;
    if (std::string(e.what()).rfind("pthread_create", 0) == 0) throw;  // the writer thread refused: a limit too
    throw InputError({fmt::format("{}: cannot write the output file: {}", path, e.what())});
  }
  impl->last_flush = std::chrono::steady_clock::now();
  return std::unique_ptr<Hdf5Store>(new Hdf5Store(std::move(impl)));
}

void Hdf5Store::OnEvent(const Event& e) {
  impl_->ev.Push(e);
  impl_->MaybeFlush();
}

void Hdf5Store::OnSample(const Sample& s) {
  impl_->sa.Push(s);
  impl_->MaybeFlush();
}

void Hdf5Store::OnSection(const Sample& s) {
  impl_->se.Push(s);
  impl_->MaybeFlush();
}

void Hdf5Store::OnCheckpoint(const Checkpoint& c) {
  auto& m = *impl_;
  m.last_checkpoint = c;
  m.cp_events = m.ev.Rows();
  m.cp_samples = m.sa.t.rows();
  m.cp_sections = m.se.t.rows();
  if (m.ld) m.cp_loads = m.ld->impacts.rows();
  // The first checkpoint (the start state) reaches the disk at once: a run killed in its first
  // second can be resumed too.
  if (!m.checkpoint_on_disk) m.Flush();
}

void Hdf5Store::OnPeriodLoads(long long period, const std::vector<LoadsRow>& rows) {
  auto& m = *impl_;
  if (m.loads_ended || rows.empty()) return;
  if (!m.ld) {
    // The first period to end: /loads begins with it (the run's first period, or the checkpoint's
    // of a run resumed from a file without /loads). Made between flushes.
    m.Sync();
    m.loads = h5::OpenOrCreateGroup(m.file.get(), "/loads");
    h5::WriteInt(m.loads.get(), "first_period", period);
    m.ld.emplace();
    m.ld->Create(m.loads.get(), static_cast<h5::Size>(rows.size()));
    m.loads_first = period;
    m.cp_loads = 0;
    m.Room();
  }
  if (period != m.loads_first + static_cast<long long>(m.ld->impacts.rows()) ||
      static_cast<h5::Size>(rows.size()) != m.ld->impacts.cols()) {
    m.loads_ended = true;  // not the next period: the rows kept end here
    return;
  }
  m.ld->Push(rows);
}

void Hdf5Store::ReplayLoads(const std::function<void(const std::vector<LoadsRow>&)>& each) const {
  auto& m = *impl_;
  if (!m.ld) return;
  m.Sync();
  const h5::Size n = m.cp_loads, w = m.ld->impacts.cols();
  constexpr h5::Size kBlock = 4096;
  std::vector<double> c[10];
  std::vector<std::int8_t> partial;
  std::vector<LoadsRow> rows(static_cast<size_t>(w));
  h5::Column* cols[10] = {&m.ld->impacts, &m.ld->impulse, &m.ld->reaction,     &m.ld->energy,   &m.ld->work,
                          &m.ld->held,    &m.ld->phases,  &m.ld->peak_sum,     &m.ld->duration_sum, &m.ld->peak_max};
  // A table written before the compliant stops' columns: its periods do not know their phases.
  const int q_end = m.ld->has_phases ? 10 : 6;
  const double unknown = std::numeric_limits<double>::quiet_NaN();
  for (h5::Size first = 0; first < n; first += kBlock) {
    const h5::Size k = std::min(kBlock, n - first);
    for (int q = 0; q < q_end; ++q) {
      c[q].resize(static_cast<size_t>(k * w));
      cols[q]->Read(first, k, c[q].data());
    }
    partial.resize(static_cast<size_t>(k * w));
    m.ld->partial.Read(first, k, partial.data());
    for (h5::Size i = 0; i < k; ++i) {
      for (h5::Size j = 0; j < w; ++j) {
        const auto at = static_cast<size_t>(i * w + j);
        LoadsRow& r = rows[static_cast<size_t>(j)];
        r = {c[0][at], c[1][at], c[2][at], c[3][at], c[4][at], c[5][at], partial[at] != 0};
        if (q_end == 10) {
          r.phases = c[6][at];
          r.peak_sum = c[7][at];
          r.duration_sum = c[8][at];
          r.peak_max = c[9][at];
        } else {
          r.phases = r.peak_sum = r.duration_sum = r.peak_max = unknown;
        }
      }
      each(rows);
    }
  }
}

void Hdf5Store::Finish(const RunResult& r, const Attractor& a) {
  auto& m = *impl_;
  m.Sync();
  m.reserve.reset();  // the store ends here: the room is its last writes' and the closing's
  const h5::Id f = m.file.get();
  h5::WriteString(f, "status", ToString(r.status));
  h5::WriteString(f, "message", r.message);
  h5::WriteDouble(f, "t_end", r.t_end);
  WriteCounts(f, r.counts);
  if (r.contact_counts.size() > 1) {
    // Several contacts: one row per contact (impacts, accumulations, sticks, releases, grazings,
    // simultaneous), docs/output.md.
    std::vector<double> rows;
    for (const EventCounts& k : r.contact_counts)
      for (long long v : {k.impacts, k.accumulations, k.sticks, k.releases, k.grazings, k.simultaneous})
        rows.push_back(static_cast<double>(v));
    h5::WriteDoubles(f, "contact_counts", rows, 6);
  }
  h5::WriteInt(f, "chatter_accumulations_predicted", r.chatter.accumulations_predicted);
  h5::WriteInt(f, "chatter_impacts_followed", r.chatter.impacts_followed);
  h5::WriteDouble(f, "chatter_max_estimated_error", r.chatter.max_estimated_error);
  if (m.header.engine == "cvode") {
    h5::WriteInt(f, "cvode_steps", r.solver.steps);
    h5::WriteInt(f, "cvode_rhs_evals", r.solver.rhs_evals);
    h5::WriteInt(f, "cvode_root_evals", r.solver.root_evals);
    h5::WriteInt(f, "cvode_jac_evals", r.solver.jac_evals);
    h5::WriteInt(f, "cvode_error_test_failures", r.solver.error_test_failures);
    h5::WriteInt(f, "cvode_reinits", r.solver.reinits);
    h5::WriteString(f, "cvode_method", m.header.method);
  }
  if (a.kind.empty()) {  // a study, branch or partition: no single attractor to describe
    h5::DeleteLink(f, "/attractor");
    m.Flush();
    m.Close();
    return;
  }
  h5::Handle g = h5::OpenOrCreateGroup(f, "/attractor");
  h5::WriteString(g.get(), "kind", a.kind);
  // Null values of the JSON summary are absent attributes.
  for (const char* k : {"period", "impacts_per_period", "sticking_fraction", "searched_period",
                        "recurrence_period", "recurrence_distance"})
    h5::DeleteAttr(g.get(), k);
  if (a.period) h5::WriteInt(g.get(), "period", *a.period);
  if (a.impacts_per_period) h5::WriteInt(g.get(), "impacts_per_period", *a.impacts_per_period);
  if (a.sticking_fraction) h5::WriteDouble(g.get(), "sticking_fraction", *a.sticking_fraction);
  if (a.searched_period) h5::WriteInt(g.get(), "searched_period", *a.searched_period);
  if (a.recurrence_period) h5::WriteInt(g.get(), "recurrence_period", *a.recurrence_period);
  if (a.recurrence_distance) h5::WriteDouble(g.get(), "recurrence_distance", *a.recurrence_distance);
  std::vector<double> phases;
  for (const auto& [s, e] : a.stick_phases) {
    phases.push_back(s);
    phases.push_back(e);
  }
  h5::WriteDoubles(g.get(), "stick_phases", phases, 2);
  h5::WriteInts(g.get(), "stick_contacts", a.stick_contacts);
  if (a.kind == "impact-periodic") {
    h5::WriteDoubles(g.get(), "impact_phases", a.impact_phases);
    h5::WriteDoubles(g.get(), "impact_velocities", a.impact_velocities);
    h5::WriteInts(g.get(), "impact_contacts", a.impact_contacts);
  }
  m.Flush();
  g.Reset();
  m.Close();
}

std::unique_ptr<Hdf5Store> Hdf5Store::Resume(const std::string& path, const StoreHeader& h,
                                             StoredRun& stored, double flush_interval) {
  return Continue(path, h, stored, flush_interval, false);
}

std::unique_ptr<Hdf5Store> Hdf5Store::Extend(const std::string& path, const StoreHeader& h,
                                             StoredRun& stored, double flush_interval) {
  return Continue(path, h, stored, flush_interval, true);
}

std::unique_ptr<Hdf5Store> Hdf5Store::Continue(const std::string& path, const StoreHeader& h,
                                               StoredRun& stored, double flush_interval, bool extend) {
  h5::Silence();
  // One writer per file: held from before the file is read until the resumed run closes it.
  store::FileLock lock = store::FileLock::Acquire(path, false);
  stored = ReadStoredRun(path, 4 * h.max_period + 2);  // what the attractor recorder keeps
  const char* verb = extend ? "extend" : "resume";
  if (extend) {
    // The file's scene with the new total must be the given one (which has it already).
    std::optional<LoadedScene> held;
    try {
      held = ParseScene(stored.scene_text, path, {fmt::format("run.periods={}", h.periods)});
    } catch (const InputError&) {
    }
    const bool longer = held && ParseScene(stored.scene_text, path).scene.run.periods < h.periods;
    if (!held || held->text_as_run != h.scene_text)
      throw InputError({fmt::format(
          "{}: cannot extend: the file holds a different scene (or different --set overrides) than "
          "the one given, apart from run.periods; extend with the scene of the stored run",
          path)});
    if (!longer) throw InputError({fmt::format("{}: cannot extend: the total must exceed the stored run.periods", path)});
    if (stored.status == ToString(RunStatus::kNumericalFailure) || stored.status == ToString(RunStatus::kUndetermined))
      throw InputError({fmt::format("{}: cannot extend: its run ended with status {}", path, stored.status)});
  } else if (stored.scene_text != h.scene_text) {
    throw InputError({fmt::format(
        "{}: cannot resume: the file holds a different scene (or different --set overrides) "
        "than the one given; resume with exactly the scene of the interrupted run{}",
        path, PeriodsHint(stored.scene_text, h.scene_text, path))});
  }
  if (!stored.checkpoint)
    throw InputError({fmt::format("{}: cannot {}: the file holds no checkpoint", path, verb)});
  if (stored.status == "ok" && !extend)
    throw InputError({fmt::format("{}: nothing to resume: the run finished (status ok; --extend N "
                                  "continues it for N more periods)",
                                  path)});
  if (stored.checkpoint->X.size() != h.dof)
    throw InputError({fmt::format("{}: cannot {}: the checkpoint has {} coordinates, the scene {}", path, verb,
                                  stored.checkpoint->X.size(), h.dof)});
  // Opens `file_path` and makes every change a resume makes before the run goes on; done first on
  // a copy (ProbeWrite), so that a file that cannot take them is refused unchanged.
  const auto prepare = [&](const std::string& file_path) {
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->header = h;
    impl->flush_interval = flush_interval;
    try {
      impl->file = h5::OpenFile(file_path, true);
      if (!impl->file) throw std::runtime_error("cannot open the file for writing");
      impl->OpenGroups();
      impl->OpenColumns();
      const h5::Id g = impl->checkpoint.get();
      impl->cp_events = static_cast<h5::Size>(*h5::ReadInt(g, "events"));
      impl->cp_samples = static_cast<h5::Size>(*h5::ReadInt(g, "samples"));
      impl->cp_sections = static_cast<h5::Size>(*h5::ReadInt(g, "sections"));
      // Rows written after the checkpoint are dropped: the run continues from it.
      impl->ev.Truncate(impl->cp_events);
      for (h5::Column* c : impl->sa.All()) c->Truncate(impl->cp_samples);
      for (h5::Column* c : impl->se.All()) c->Truncate(impl->cp_sections);
      // /loads (docs/loads.md §5): kept when its rows reach the checkpoint (those after it
      // dropped); a table that does not (a run whose loads were not stored to its end) is
      // removed, and the resumed run's periods begin a new one.
      const long long at = stored.checkpoint->clock.period;
      stored.loads_known_from = at;
      if (h5::TryOpenGroup(impl->file.get(), "/loads")) {
        impl->loads = h5::OpenGroup(impl->file.get(), "/loads");
        const auto first = h5::ReadInt(impl->loads.get(), "first_period");
        const auto rows = h5::ReadInt(g, "loads_periods");
        std::optional<store::LoadsTable> table;
        try {
          table.emplace();
          table->Open(impl->loads.get());
        } catch (const std::exception&) {
          table.reset();
        }
        if (table && first && rows && *rows >= 0 && *first + *rows == at &&
            table->impacts.rows() >= static_cast<h5::Size>(*rows)) {
          for (h5::Column* c : table->All()) c->Truncate(static_cast<h5::Size>(*rows));
          impl->ld = std::move(table);
          impl->loads_first = *first;
          impl->cp_loads = static_cast<h5::Size>(*rows);
          stored.loads_known_from = *first;
        } else {
          table.reset();
          impl->loads.Reset();
          h5::DeleteLink(impl->file.get(), "/loads");
        }
      }
      impl->last_checkpoint = *stored.checkpoint;
      if (extend) store::WriteExtension(impl->file.get(), h);
      h5::WriteString(impl->file.get(), "status", "running");
      impl->Flush();
    } catch (const WriteError& e) {
      if (e.from_system()) throw;  // a full disk: exit 3, as during the run
      throw InputError({fmt::format("{}: cannot {}: {}", path, verb, e.what())});
    } catch (const std::exception& e) {
      throw InputError({fmt::format("{}: cannot {}: {}", path, verb, e.what())});
    }
    return impl;
  };
  // The trial on the copy also makes what the resumed run will write later: rows appended to
  // every table (enough for new chunks), a checkpoint, and the final attributes and /attractor.
  // Damage that only a later write meets (a corrupt chunk index or heap) is refused now too.
  store::ProbeWrite(path, [&](const std::string& copy) {
    auto trial = prepare(copy);
    // Every row the resumed file keeps is read once: a flipped bit in a compressed chunk is
    // refused now, not found by a reader of a file that ends "ok".
    for (h5::Column* col : trial->Columns()) col->ReadAllRows();
    const Checkpoint& c = *trial->last_checkpoint;
    const Event e{EventKind::kImpact, c.clock, 0.0, 0.0, -1.0, 0.5};
    const Sample s{c.clock, 0.0, c.X, c.V, 0.0, c.mode, c.mode == Mode::kSticking ? 1 : 0};
    for (int i = 0; i < 20000; ++i) {
      trial->ev.Push(e);
      trial->sa.Push(s);
      trial->se.Push(s);
    }
    trial->Flush();
    Hdf5Store store(std::move(trial));
    RunResult r;
    r.status = RunStatus::kInterrupted;
    r.message = "trial";
    Attractor a;
    a.kind = "impact-periodic";
    a.period = 1;
    a.impacts_per_period = 1;
    a.sticking_fraction = 0.5;
    a.stick_phases = {{0.25, 0.5}};
    a.impact_phases = {0.125};
    a.impact_velocities = {1.0};
    store.Finish(r, a);
  });
  auto impl = prepare(path);
  impl->lock = std::move(lock);
  impl->StartWriter();
  impl->reserve.emplace();  // the library's room from now on (memory_reserve.hpp)
  impl->last_flush = std::chrono::steady_clock::now();
  return std::unique_ptr<Hdf5Store>(new Hdf5Store(std::move(impl)));
}

Hdf5Store::Stats Hdf5Store::stats() const {
  impl_->Sync();  // the writer thread's flush under way counted
  return impl_->stats;
}

}  // namespace vibro
