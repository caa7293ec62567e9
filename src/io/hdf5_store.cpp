// HDF5 store (docs/output.md). The one file of vibro that includes hdf5.h.
#include "vibro/hdf5_store.hpp"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <chrono>
#include <cstring>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <functional>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <hdf5.h>

#include "vibro/scene_file.hpp"

namespace vibro {
namespace {

constexpr hsize_t kChunkRows = 4096;
constexpr int kDeflate = 4;

// RAII for hid_t handles.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  Handle(Handle&& o) noexcept : id_(o.id_), closer_(o.closer_) { o.id_ = H5I_INVALID_HID; }
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      Reset();
      id_ = o.id_;
      closer_ = o.closer_;
      o.id_ = H5I_INVALID_HID;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { Reset(); }
  hid_t get() const { return id_; }
  explicit operator bool() const { return id_ >= 0; }
  void Reset() {
    if (id_ >= 0 && closer_) closer_(id_);
    id_ = H5I_INVALID_HID;
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

hid_t Check(hid_t id, const char* what) {
  if (id < 0) throw std::runtime_error(fmt::format("HDF5: {} failed", what));
  return id;
}
void Check(herr_t status, const char* what, int) {
  if (status < 0) throw std::runtime_error(fmt::format("HDF5: {} failed", what));
}

void SilenceHdf5() {
  static const bool once = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)once;
}

Handle StringType() {
  Handle t(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(t.get(), H5T_VARIABLE);
  H5Tset_cset(t.get(), H5T_CSET_UTF8);
  return t;
}

Handle KindType() {
  Handle t(H5Tenum_create(H5T_NATIVE_INT8), H5Tclose);
  for (auto k : {EventKind::kImpact, EventKind::kAccumulation, EventKind::kStick,
                 EventKind::kRelease, EventKind::kGrazing}) {
    const auto v = static_cast<std::int8_t>(k);
    H5Tenum_insert(t.get(), ToString(k), &v);
  }
  return t;
}

void DeleteAttr(hid_t obj, const char* name) {
  if (H5Aexists(obj, name) > 0) H5Adelete(obj, name);
}

void WriteString(hid_t obj, const char* name, const std::string& value) {
  DeleteAttr(obj, name);
  Handle type = StringType();
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle a(Check(H5Acreate2(obj, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), name),
           H5Aclose);
  const char* p = value.c_str();
  Check(H5Awrite(a.get(), type.get(), &p), name, 0);
}

template <class T>
void WriteScalar(hid_t obj, const char* name, T value, hid_t mem_type, hid_t file_type) {
  DeleteAttr(obj, name);
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle a(Check(H5Acreate2(obj, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), name),
           H5Aclose);
  Check(H5Awrite(a.get(), mem_type, &value), name, 0);
}
void WriteDouble(hid_t obj, const char* name, double v) {
  WriteScalar(obj, name, v, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE);
}
void WriteInt(hid_t obj, const char* name, long long v) {
  WriteScalar(obj, name, static_cast<std::int64_t>(v), H5T_NATIVE_INT64, H5T_STD_I64LE);
}
void WriteDoubles(hid_t obj, const char* name, const std::vector<double>& v, hsize_t cols = 1) {
  DeleteAttr(obj, name);
  const hsize_t dims[2] = {cols > 1 ? v.size() / cols : v.size(), cols};
  Handle space(H5Screate_simple(cols > 1 ? 2 : 1, dims, nullptr), H5Sclose);
  Handle a(Check(H5Acreate2(obj, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT), name),
           H5Aclose);
  if (!v.empty()) Check(H5Awrite(a.get(), H5T_NATIVE_DOUBLE, v.data()), name, 0);
}

void WriteStringArray(hid_t obj, const char* name, const std::vector<std::string>& v) {
  DeleteAttr(obj, name);
  std::vector<const char*> p;
  for (const auto& x : v) p.push_back(x.c_str());
  Handle type = StringType();
  const hsize_t dims[1] = {v.size()};
  Handle space(H5Screate_simple(1, dims, nullptr), H5Sclose);
  Handle a(Check(H5Acreate2(obj, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose);
  if (!v.empty()) Check(H5Awrite(a.get(), type.get(), p.data()), name, 0);
}

std::string ReadString(hid_t obj, const char* name) {
  if (H5Aexists(obj, name) <= 0) return {};
  Handle a(Check(H5Aopen(obj, name, H5P_DEFAULT), name), H5Aclose);
  Handle type = StringType();
  char* p = nullptr;
  Check(H5Aread(a.get(), type.get(), &p), name, 0);
  std::string s = p ? p : "";
  H5free_memory(p);
  return s;
}
template <class T>
std::optional<T> ReadScalar(hid_t obj, const char* name, hid_t mem_type) {
  if (H5Aexists(obj, name) <= 0) return std::nullopt;
  Handle a(Check(H5Aopen(obj, name, H5P_DEFAULT), name), H5Aclose);
  T v{};
  Check(H5Aread(a.get(), mem_type, &v), name, 0);
  return v;
}
std::vector<double> ReadDoubles(hid_t obj, const char* name) {
  if (H5Aexists(obj, name) <= 0) return {};
  Handle a(Check(H5Aopen(obj, name, H5P_DEFAULT), name), H5Aclose);
  Handle space(H5Aget_space(a.get()), H5Sclose);
  std::vector<double> v(static_cast<size_t>(H5Sget_simple_extent_npoints(space.get())));
  if (!v.empty()) Check(H5Aread(a.get(), H5T_NATIVE_DOUBLE, v.data()), name, 0);
  return v;
}

// An extendible dataset of `cols` columns (cols = 0: one-dimensional), buffered in memory.
class Column {
 public:
  Column() = default;
  Column(hid_t group, const char* name, hid_t file_type, hid_t mem_type, size_t elem_size,
         hsize_t cols)
      : mem_type_(mem_type), elem_size_(elem_size), cols_(cols) {
    const int rank = cols > 0 ? 2 : 1;
    const hsize_t dims[2] = {0, cols}, maxdims[2] = {H5S_UNLIMITED, cols};
    const hsize_t chunk[2] = {cols > 0 ? std::max<hsize_t>(64, kChunkRows / cols) : kChunkRows, cols};
    Handle space(H5Screate_simple(rank, dims, maxdims), H5Sclose);
    Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    H5Pset_chunk(dcpl.get(), rank, chunk);
    H5Pset_shuffle(dcpl.get());
    H5Pset_deflate(dcpl.get(), kDeflate);
    dset_ = Handle(Check(H5Dcreate2(group, name, file_type, space.get(), H5P_DEFAULT, dcpl.get(),
                                    H5P_DEFAULT),
                         name),
                   H5Dclose);
  }
  // Opens an existing column and checks its shape: one-dimensional when cols = 0, else two
  // columns... `cols` wide (kAnyCols: any width, checked by the caller with cols()).
  static constexpr hsize_t kAnyCols = ~hsize_t{0};
  Column(hid_t group, const char* name, hid_t mem_type, size_t elem_size, hsize_t cols = 0)
      : mem_type_(mem_type), elem_size_(elem_size), name_(name) {
    dset_ = Handle(Check(H5Dopen2(group, name, H5P_DEFAULT), name), H5Dclose);
    Handle space(Check(H5Dget_space(dset_.get()), name), H5Sclose);
    const int rank = H5Sget_simple_extent_ndims(space.get());
    if (rank != (cols > 0 ? 2 : 1))
      throw std::runtime_error(fmt::format("dataset {} has rank {}, expected {}", name, rank, cols > 0 ? 2 : 1));
    hsize_t dims[2] = {0, 0};
    H5Sget_simple_extent_dims(space.get(), dims, nullptr);
    rows_ = dims[0];
    cols_ = rank == 2 ? dims[1] : 0;
    if (rank == 2 && cols != kAnyCols && cols_ != cols)
      throw std::runtime_error(fmt::format("dataset {} has {} columns, expected {}", name, cols_, cols));
    if (rank == 2 && (cols_ == 0 || cols_ > (1u << 16)))
      throw std::runtime_error(fmt::format("dataset {} has {} columns", name, cols_));
    // The stored type must convert to the memory type's class (no string read as numbers).
    Handle type(Check(H5Dget_type(dset_.get()), name), H5Tclose);
    const H5T_class_t have = H5Tget_class(type.get()), want = H5Tget_class(mem_type);
    if (have != want)
      throw std::runtime_error(fmt::format("dataset {} has the wrong element type", name));
  }
  hsize_t cols() const { return cols_; }

  template <class T>
  void Push(const T& v) {
    const auto* p = reinterpret_cast<const unsigned char*>(&v);
    buf_.insert(buf_.end(), p, p + sizeof(T));
  }
  void PushRow(const Eigen::VectorXd& v) {
    const auto* p = reinterpret_cast<const unsigned char*>(v.data());
    buf_.insert(buf_.end(), p, p + sizeof(double) * static_cast<size_t>(v.size()));
  }
  hsize_t rows() const { return rows_ + pending(); }
  hsize_t pending() const { return buf_.size() / (elem_size_ * std::max<hsize_t>(cols_, 1)); }

  void Flush() {
    const hsize_t n = pending();
    if (n == 0) return;
    const int rank = cols_ > 0 ? 2 : 1;
    const hsize_t dims[2] = {rows_ + n, cols_}, start[2] = {rows_, 0}, count[2] = {n, cols_};
    Check(H5Dset_extent(dset_.get(), dims), "extend", 0);
    Handle fs(H5Dget_space(dset_.get()), H5Sclose);
    H5Sselect_hyperslab(fs.get(), H5S_SELECT_SET, start, nullptr, count, nullptr);
    Handle ms(H5Screate_simple(rank, count, nullptr), H5Sclose);
    Check(H5Dwrite(dset_.get(), mem_type_, ms.get(), fs.get(), H5P_DEFAULT, buf_.data()), "write", 0);
    rows_ += n;
    buf_.clear();
  }
  void Truncate(hsize_t rows) {
    buf_.clear();
    const hsize_t dims[2] = {rows, cols_};
    Check(H5Dset_extent(dset_.get(), dims), "truncate", 0);
    rows_ = rows;
  }
  // Reads rows [first, first + n) into out (n · max(cols, 1) elements of the memory type).
  void Read(hsize_t first, hsize_t n, void* out) const {
    if (n == 0) return;
    if (first > rows_ || n > rows_ - first)
      throw std::runtime_error(fmt::format("dataset {}: rows [{}, {}) beyond its {} rows", name_, first,
                                           first + n, rows_));
    const int rank = cols_ > 0 ? 2 : 1;
    const hsize_t start[2] = {first, 0}, count[2] = {n, cols_};
    Handle fs(H5Dget_space(dset_.get()), H5Sclose);
    H5Sselect_hyperslab(fs.get(), H5S_SELECT_SET, start, nullptr, count, nullptr);
    Handle ms(H5Screate_simple(rank, count, nullptr), H5Sclose);
    Check(H5Dread(dset_.get(), mem_type_, ms.get(), fs.get(), H5P_DEFAULT, out), "read", 0);
  }

 private:
  Handle dset_;
  hid_t mem_type_ = H5I_INVALID_HID;
  size_t elem_size_ = 8;
  std::string name_;
  hsize_t cols_ = 0;
  hsize_t rows_ = 0;
  std::vector<unsigned char> buf_;
};

// /events: one row per event.
struct EventTable {
  Column t, period, offset, kind, xB, v_before, v_after;
  void Create(hid_t g, hid_t kind_type) {
    t = Column(g, "t", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, 0);
    period = Column(g, "period", H5T_STD_I64LE, H5T_NATIVE_INT64, 8, 0);
    offset = Column(g, "offset", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, 0);
    kind = Column(g, "kind", kind_type, kind_type, 1, 0);
    xB = Column(g, "x_B", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, 0);
    v_before = Column(g, "v_before", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, 0);
    v_after = Column(g, "v_after", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, 0);
  }
  void Open(hid_t g, hid_t kind_type) {
    t = Column(g, "t", H5T_NATIVE_DOUBLE, 8);
    period = Column(g, "period", H5T_NATIVE_INT64, 8);
    offset = Column(g, "offset", H5T_NATIVE_DOUBLE, 8);
    kind = Column(g, "kind", kind_type, 1);
    xB = Column(g, "x_B", H5T_NATIVE_DOUBLE, 8);
    v_before = Column(g, "v_before", H5T_NATIVE_DOUBLE, 8);
    v_after = Column(g, "v_after", H5T_NATIVE_DOUBLE, 8);
  }
  void Push(const Event& e) {
    t.Push(e.t);
    period.Push(static_cast<std::int64_t>(e.clock.period));
    offset.Push(e.clock.offset);
    kind.Push(static_cast<std::int8_t>(e.kind));
    xB.Push(e.x_B);
    v_before.Push(e.v_before);
    v_after.Push(e.v_after);
  }
  std::vector<Column*> All() { return {&t, &period, &offset, &kind, &xB, &v_before, &v_after}; }
};

// /samples and /section: one row per state.
struct StateTable {
  Column t, period, X, V, xB, mode;
  void Create(hid_t g, hsize_t n) {
    t = Column(g, "t", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, 0);
    period = Column(g, "period", H5T_STD_I64LE, H5T_NATIVE_INT64, 8, 0);
    X = Column(g, "X", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, n);
    V = Column(g, "V", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, n);
    xB = Column(g, "x_B", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, 0);
    mode = Column(g, "mode", H5T_STD_I8LE, H5T_NATIVE_INT8, 1, 0);
  }
  // dof: width of X and V (Column::kAnyCols: checked later against the checkpoint).
  void Open(hid_t g, hsize_t dof) {
    t = Column(g, "t", H5T_NATIVE_DOUBLE, 8);
    period = Column(g, "period", H5T_NATIVE_INT64, 8);
    X = Column(g, "X", H5T_NATIVE_DOUBLE, 8, dof);
    V = Column(g, "V", H5T_NATIVE_DOUBLE, 8, dof);
    xB = Column(g, "x_B", H5T_NATIVE_DOUBLE, 8);
    mode = Column(g, "mode", H5T_NATIVE_INT8, 1);
  }
  void Push(const Sample& s) {
    t.Push(s.t);
    period.Push(static_cast<std::int64_t>(s.clock.period));
    X.PushRow(s.X);
    V.PushRow(s.V);
    xB.Push(s.x_B);
    mode.Push(static_cast<std::int8_t>(s.mode));
  }
  std::vector<Column*> All() { return {&t, &period, &X, &V, &xB, &mode}; }
};

Handle FileAccess() {
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  // No metadata reaches the disk between flushes (see the header).
  H5AC_cache_config_t cfg;
  cfg.version = H5AC__CURR_CACHE_CONFIG_VERSION;
  H5Pget_mdc_config(fapl.get(), &cfg);
  cfg.incr_mode = H5C_incr__off;
  cfg.flash_incr_mode = H5C_flash_incr__off;
  cfg.decr_mode = H5C_decr__off;
  cfg.evictions_enabled = 0;
  cfg.max_size = 128 * 1024 * 1024;
  cfg.min_size = 1024 * 1024;
  cfg.set_initial_size = 1;
  cfg.initial_size = 16 * 1024 * 1024;
  Check(H5Pset_mdc_config(fapl.get(), &cfg), "metadata cache configuration", 0);
  // No file lock: h5py users may watch a long run as it goes (the file is consistent as of the
  // last flush; a read that meets a flush in progress may fail and should be retried).
  H5Pset_file_locking(fapl.get(), 0, 1);
  return fapl;
}

std::string NowIso8601() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace

namespace {

// /basin/cells: one row per finished cell of a study, appended as batches finish (resume).
struct CellTable {
  Column index, state, kind, period, impacts, sticking_fraction, periods, stop, stick_count,
      impact_count, z, phases;
  std::vector<Column*> All() {
    return {&index, &state, &kind, &period, &impacts, &sticking_fraction, &periods, &stop,
            &stick_count, &impact_count, &z, &phases};
  }
  void Create(hid_t g, hsize_t zcols) {
    index = Column(g, "index", H5T_STD_I64LE, H5T_NATIVE_INT64, 8, 0);
    state = Column(g, "state", H5T_STD_I8LE, H5T_NATIVE_INT8, 1, 0);
    kind = Column(g, "kind", H5T_STD_I8LE, H5T_NATIVE_INT8, 1, 0);
    period = Column(g, "period", H5T_STD_I32LE, H5T_NATIVE_INT32, 4, 0);
    impacts = Column(g, "impacts_per_period", H5T_STD_I64LE, H5T_NATIVE_INT64, 8, 0);
    sticking_fraction = Column(g, "sticking_fraction", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, 0);
    periods = Column(g, "periods", H5T_STD_I64LE, H5T_NATIVE_INT64, 8, 0);
    stop = Column(g, "stop", H5T_STD_I8LE, H5T_NATIVE_INT8, 1, 0);
    stick_count = Column(g, "stick_phase_count", H5T_STD_I32LE, H5T_NATIVE_INT32, 4, 0);
    impact_count = Column(g, "impact_count", H5T_STD_I32LE, H5T_NATIVE_INT32, 4, 0);
    z = Column(g, "z", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, zcols);
    phases = Column(g, "phases", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, 0);
  }
  void Open(hid_t g, hsize_t zcols) {
    index = Column(g, "index", H5T_NATIVE_INT64, 8);
    state = Column(g, "state", H5T_NATIVE_INT8, 1);
    kind = Column(g, "kind", H5T_NATIVE_INT8, 1);
    period = Column(g, "period", H5T_NATIVE_INT32, 4);
    impacts = Column(g, "impacts_per_period", H5T_NATIVE_INT64, 8);
    sticking_fraction = Column(g, "sticking_fraction", H5T_NATIVE_DOUBLE, 8);
    periods = Column(g, "periods", H5T_NATIVE_INT64, 8);
    stop = Column(g, "stop", H5T_NATIVE_INT8, 1);
    stick_count = Column(g, "stick_phase_count", H5T_NATIVE_INT32, 4);
    impact_count = Column(g, "impact_count", H5T_NATIVE_INT32, 4);
    z = Column(g, "z", H5T_NATIVE_DOUBLE, 8, zcols);
    phases = Column(g, "phases", H5T_NATIVE_DOUBLE, 8);
  }
  void Push(size_t i, const CellResult& c, hsize_t zcols) {
    const Attractor& a = c.attractor;
    index.Push(static_cast<std::int64_t>(i));
    state.Push(static_cast<std::int8_t>(c.state));
    kind.Push(static_cast<std::int8_t>(KindCode(a.kind)));
    period.Push(static_cast<std::int32_t>(a.period.value_or(0)));
    impacts.Push(static_cast<std::int64_t>(a.impacts_per_period.value_or(-1)));
    sticking_fraction.Push(a.sticking_fraction.value_or(std::numeric_limits<double>::quiet_NaN()));
    periods.Push(static_cast<std::int64_t>(c.periods));
    stop.Push(c.stop);
    stick_count.Push(static_cast<std::int32_t>(a.stick_phases.size()));
    impact_count.Push(static_cast<std::int32_t>(a.impact_phases.size()));
    Eigen::VectorXd zz = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(zcols));
    if (c.z.size() == zz.size()) zz = c.z;
    z.PushRow(zz);
    for (const auto& [b, e] : a.stick_phases) {
      phases.Push(b);
      phases.Push(e);
    }
    for (double v : a.impact_phases) phases.Push(v);
    for (double v : a.impact_velocities) phases.Push(v);
  }
};

}  // namespace

struct Hdf5Store::Impl {
  std::string path;
  StoreHeader header;
  Handle file, events, samples, section, checkpoint;
  EventTable ev;
  StateTable sa, se;
  Handle kind_type;
  std::optional<Checkpoint> last_checkpoint;
  hsize_t cp_events = 0, cp_samples = 0, cp_sections = 0;  // rows at the last checkpoint
  double flush_interval = 1.0;
  std::chrono::steady_clock::time_point last_flush;
  unsigned calls = 0;
  Stats stats;
  Handle basin, cells_group;
  std::optional<CellTable> cells;
  hsize_t zcols = 0;

  void OpenGroups() {
    events = Handle(Check(H5Gopen2(file.get(), "/events", H5P_DEFAULT), "/events"), H5Gclose);
    samples = Handle(Check(H5Gopen2(file.get(), "/samples", H5P_DEFAULT), "/samples"), H5Gclose);
    section = Handle(Check(H5Gopen2(file.get(), "/section", H5P_DEFAULT), "/section"), H5Gclose);
    checkpoint = Handle(Check(H5Gopen2(file.get(), "/checkpoint", H5P_DEFAULT), "/checkpoint"), H5Gclose);
  }

  void MaybeFlush() {
    if ((++calls & 1023u) != 0) return;
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - last_flush).count() >= flush_interval) Flush();
  }

  void WriteCheckpoint() {
    if (!last_checkpoint) return;
    const Checkpoint& c = *last_checkpoint;
    const hid_t g = checkpoint.get();
    WriteInt(g, "period", c.clock.period);
    WriteDouble(g, "offset", c.clock.offset);
    WriteDoubles(g, "X", std::vector<double>(c.X.data(), c.X.data() + c.X.size()));
    WriteDoubles(g, "V", std::vector<double>(c.V.data(), c.V.data() + c.V.size()));
    WriteInt(g, "mode", static_cast<int>(c.mode));
    WriteDouble(g, "gap", c.gap);
    WriteInt(g, "start_kind", c.start_kind);
    WriteDouble(g, "chatter_first_speed", c.chatter_first_speed);
    WriteDouble(g, "chatter_last_speed", c.chatter_last_speed);
    WriteInt(g, "sample_index", c.sample_index);
    WriteInt(g, "impacts", c.counts.impacts);
    WriteInt(g, "accumulations", c.counts.accumulations);
    WriteInt(g, "sticks", c.counts.sticks);
    WriteInt(g, "releases", c.counts.releases);
    WriteInt(g, "grazings", c.counts.grazings);
    WriteInt(g, "events", static_cast<long long>(cp_events));
    WriteInt(g, "samples", static_cast<long long>(cp_samples));
    WriteInt(g, "sections", static_cast<long long>(cp_sections));
  }

  std::vector<Column*> Columns() {
    std::vector<Column*> all = ev.All();
    for (auto* t : {&sa, &se})
      for (Column* c : t->All()) all.push_back(c);
    if (cells)
      for (Column* c : cells->All()) all.push_back(c);
    return all;
  }

  void OpenColumns() {
    ev.Open(events.get(), kind_type.get());
    sa.Open(samples.get(), static_cast<hsize_t>(header.dof));
    se.Open(section.get(), static_cast<hsize_t>(header.dof));
  }

  void Close() {
    for (Column* c : Columns()) *c = Column();
    cells.reset();
    cells_group.Reset();
    basin.Reset();
    events.Reset();
    samples.Reset();
    section.Reset();
    checkpoint.Reset();
    file.Reset();
  }

  void Flush() {
    const auto t0 = std::chrono::steady_clock::now();
    for (Column* c : Columns()) c->Flush();
    WriteCheckpoint();
    Check(H5Fflush(file.get(), H5F_SCOPE_LOCAL), "flush", 0);
    last_flush = std::chrono::steady_clock::now();
    ++stats.flushes;
    stats.flush_seconds += std::chrono::duration<double>(last_flush - t0).count();
  }
};

Hdf5Store::Hdf5Store(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Hdf5Store::~Hdf5Store() = default;

std::unique_ptr<Hdf5Store> Hdf5Store::Create(const std::string& path, const StoreHeader& h,
                                             double flush_interval) {
  SilenceHdf5();
  // Never clobber what is not ours: an existing path must be a regular file holding a vibro run.
  struct stat st{};
  const bool existed = stat(path.c_str(), &st) == 0;
  if (existed && S_ISREG(st.st_mode)) {
    bool ours = false;
    if (H5Fis_hdf5(path.c_str()) > 0) {
      Handle probe(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
      ours = probe && H5Aexists(probe.get(), "vibro_version") > 0;
    }
    if (!ours)
      throw InputError({fmt::format("{}: exists and is not a vibro output file; refusing to "
                                    "overwrite it (remove it or choose another --out)",
                                    path)});    if (!h.force) {  // a vibro file of another scene or command is someone's result
      Handle probe(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
      const std::string scene = probe ? ReadString(probe.get(), "scene") : "";
      const std::string command = probe && H5Aexists(probe.get(), "command") > 0
                                      ? ReadString(probe.get(), "command") : "";
      if (scene != h.scene_text || (!command.empty() && command != h.command))
        throw InputError({fmt::format(
            "{}: holds a vibro {} of {}; refusing to overwrite it (--force to replace it, or "
            "choose another --out)",
            path, command.empty() ? "run" : "'" + command + "' run",
            scene != h.scene_text ? "another scene" : "another command")});
    }
  }
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->header = h;
  impl->flush_interval = flush_interval;
  try {
    Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
    // Freed space is never reused: a flushed file never points at overwritten bytes.
    Check(H5Pset_file_space_strategy(fcpl.get(), H5F_FSPACE_STRATEGY_NONE, 0, 1), "file space", 0);
    Handle fapl = FileAccess();
    errno = 0;
    impl->file = Handle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get()), H5Fclose);
    if (!impl->file)
      throw std::runtime_error(errno != 0 ? std::strerror(errno) : "HDF5 could not create it");
    const hid_t f = impl->file.get();
    for (const char* g : {"/events", "/samples", "/section", "/attractor", "/checkpoint", "/model"})
      Handle(Check(H5Gcreate2(f, g, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), g), H5Gclose);
    impl->OpenGroups();
    impl->kind_type = KindType();
    impl->ev.Create(impl->events.get(), impl->kind_type.get());
    impl->sa.Create(impl->samples.get(), static_cast<hsize_t>(h.dof));
    impl->se.Create(impl->section.get(), static_cast<hsize_t>(h.dof));
    WriteString(f, "vibro_version", VIBRO_VERSION);
    WriteString(f, "git_commit", VIBRO_GIT_COMMIT);
    WriteString(f, "command", h.command);
    for (const auto& [name, value] : h.provenance) WriteString(f, name.c_str(), value);
    WriteString(f, "scene", h.scene_text);
    WriteString(f, "engine", h.engine);
    WriteDouble(f, "rtol", h.rtol);
    WriteDouble(f, "atol", h.atol);
    WriteString(f, "chatter", h.chatter);
    WriteString(f, "status", "running");
    WriteString(f, "message", "");
    WriteString(f, "created", NowIso8601());
    WriteInt(f, "periods", h.periods);
    WriteInt(f, "samples_per_period", h.samples_per_period);
    WriteDouble(f, "forcing_period", h.period);
    WriteDouble(f, "initial_time", h.initial_time);
    {
      Handle mg(Check(H5Gopen2(f, "/model", H5P_DEFAULT), "/model"), H5Gclose);
      const auto vec = [](const Eigen::VectorXd& v) {
        return std::vector<double>(v.data(), v.data() + v.size());
      };
      WriteDoubles(mg.get(), "frequencies", vec(h.frequencies));
      WriteDoubles(mg.get(), "forcing", vec(h.forcing));
      WriteDoubles(mg.get(), "contact", vec(h.contact));
      WriteDoubles(mg.get(), "contact_shape", vec(h.contact_shape));
      WriteDoubles(mg.get(), "damping_ratios", vec(h.damping_ratios));
      WriteDoubles(mg.get(), "constrained_frequencies", vec(h.constrained_frequencies));
      WriteDouble(mg.get(), "s_A", h.s_A);
      WriteDouble(mg.get(), "s_B", h.s_B);
      WriteDouble(mg.get(), "stop", h.stop);
      WriteDouble(mg.get(), "restitution", h.restitution);
      WriteDouble(mg.get(), "amplitude", h.amplitude);
      WriteDouble(mg.get(), "frequency", h.frequency);
      WriteString(mg.get(), "form", h.mode_shapes.size() > 0 ? "physical" : "modal");
      if (h.mode_shapes.size() > 0) {  // (N, n), row-major as HDF5 stores it
        std::vector<double> rows;
        for (Eigen::Index i = 0; i < h.mode_shapes.rows(); ++i)
          for (Eigen::Index j = 0; j < h.mode_shapes.cols(); ++j) rows.push_back(h.mode_shapes(i, j));
        WriteDoubles(mg.get(), "mode_shapes", rows, static_cast<hsize_t>(h.mode_shapes.cols()));
        WriteStringArray(mg.get(), "dof_labels", h.dof_labels);
      }
    }
    impl->Flush();
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
  m.cp_events = m.ev.t.rows();
  m.cp_samples = m.sa.t.rows();
  m.cp_sections = m.se.t.rows();
}

void Hdf5Store::Finish(const RunResult& r, const Attractor& a) {
  auto& m = *impl_;
  const hid_t f = m.file.get();
  WriteString(f, "status", ToString(r.status));
  WriteString(f, "message", r.message);
  WriteDouble(f, "t_end", r.t_end);
  WriteInt(f, "impacts", r.counts.impacts);
  WriteInt(f, "accumulations", r.counts.accumulations);
  WriteInt(f, "sticks", r.counts.sticks);
  WriteInt(f, "releases", r.counts.releases);
  WriteInt(f, "grazings", r.counts.grazings);
  WriteInt(f, "chatter_accumulations_predicted", r.chatter.accumulations_predicted);
  WriteInt(f, "chatter_impacts_followed", r.chatter.impacts_followed);
  WriteDouble(f, "chatter_max_estimated_error", r.chatter.max_estimated_error);
  if (m.header.engine == "cvode") {
    WriteInt(f, "cvode_steps", r.solver.steps);
    WriteInt(f, "cvode_rhs_evals", r.solver.rhs_evals);
    WriteInt(f, "cvode_root_evals", r.solver.root_evals);
    WriteInt(f, "cvode_jac_evals", r.solver.jac_evals);
    WriteInt(f, "cvode_error_test_failures", r.solver.error_test_failures);
    WriteInt(f, "cvode_reinits", r.solver.reinits);
    WriteString(f, "cvode_method", m.header.method);
  }
  if (a.kind.empty()) {  // a study, branch or partition: no single attractor to describe
    if (H5Lexists(f, "/attractor", H5P_DEFAULT) > 0) H5Ldelete(f, "/attractor", H5P_DEFAULT);
    m.Flush();
    m.Close();
    return;
  }
  Handle g(Check(H5Lexists(f, "/attractor", H5P_DEFAULT) > 0
                     ? H5Gopen2(f, "/attractor", H5P_DEFAULT)
                     : H5Gcreate2(f, "/attractor", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                 "/attractor"),
           H5Gclose);
  WriteString(g.get(), "kind", a.kind);
  // Null values of the JSON summary are absent attributes.
  for (const char* k : {"period", "impacts_per_period", "sticking_fraction"}) DeleteAttr(g.get(), k);
  if (a.period) WriteInt(g.get(), "period", *a.period);
  if (a.impacts_per_period) WriteInt(g.get(), "impacts_per_period", *a.impacts_per_period);
  if (a.sticking_fraction) WriteDouble(g.get(), "sticking_fraction", *a.sticking_fraction);
  std::vector<double> phases;
  for (const auto& [s, e] : a.stick_phases) {
    phases.push_back(s);
    phases.push_back(e);
  }
  WriteDoubles(g.get(), "stick_phases", phases, 2);
  if (a.kind == "impact-periodic") {
    WriteDoubles(g.get(), "impact_phases", a.impact_phases);
    WriteDoubles(g.get(), "impact_velocities", a.impact_velocities);
  }
  m.Flush();
  g.Reset();
  m.Close();
}

namespace {
void ProbeWrite(const std::string& path, const std::function<void(const std::string&)>& changes);  // below
}  // namespace

std::unique_ptr<Hdf5Store> Hdf5Store::Resume(const std::string& path, const StoreHeader& h,
                                             StoredRun& stored, double flush_interval) {
  stored = ReadStoredRun(path, 4 * h.max_period + 2);  // what the attractor recorder keeps
  if (stored.scene_text != h.scene_text)
    throw InputError({fmt::format(
        "{}: cannot resume: the file holds a different scene (or different --set overrides) "
        "than the one given; resume with exactly the scene of the interrupted run",
        path)});
  if (!stored.checkpoint)
    throw InputError({fmt::format("{}: cannot resume: the file holds no checkpoint", path)});
  if (stored.status == "ok")
    throw InputError({fmt::format("{}: nothing to resume: the run finished (status ok)", path)});
  if (stored.checkpoint->X.size() != h.dof)
    throw InputError({fmt::format("{}: cannot resume: the checkpoint has {} coordinates, the scene {}", path,
                                  stored.checkpoint->X.size(), h.dof)});
  // Opens `file_path` and makes every change a resume makes before the run goes on; done first on
  // a copy (ProbeWrite), so that a file that cannot take them is refused unchanged.
  const auto prepare = [&](const std::string& file_path) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->header = h;
  impl->flush_interval = flush_interval;
  try {
    Handle fapl = FileAccess();
    impl->file = Handle(H5Fopen(file_path.c_str(), H5F_ACC_RDWR, fapl.get()), H5Fclose);
    if (!impl->file) throw std::runtime_error("cannot open the file for writing");
    impl->OpenGroups();
    impl->kind_type = KindType();
    impl->OpenColumns();
    const Checkpoint& cp = *stored.checkpoint;
    const hid_t g = impl->checkpoint.get();
    impl->cp_events = static_cast<hsize_t>(*ReadScalar<std::int64_t>(g, "events", H5T_NATIVE_INT64));
    impl->cp_samples = static_cast<hsize_t>(*ReadScalar<std::int64_t>(g, "samples", H5T_NATIVE_INT64));
    impl->cp_sections = static_cast<hsize_t>(*ReadScalar<std::int64_t>(g, "sections", H5T_NATIVE_INT64));
    // Rows written after the checkpoint are dropped: the run continues from it.
    for (Column* c : impl->ev.All()) c->Truncate(impl->cp_events);
    for (Column* c : impl->sa.All()) c->Truncate(impl->cp_samples);
    for (Column* c : impl->se.All()) c->Truncate(impl->cp_sections);
    impl->last_checkpoint = cp;
    WriteString(impl->file.get(), "status", "running");
    impl->Flush();
  } catch (const std::exception& e) {
    throw InputError({fmt::format("{}: cannot resume: {}", path, e.what())});
  }
  return impl;
  };
  ProbeWrite(path, prepare);
  auto impl = prepare(path);
  impl->last_flush = std::chrono::steady_clock::now();
  return std::unique_ptr<Hdf5Store>(new Hdf5Store(std::move(impl)));
}

namespace {

// ---- A contained first read of a file given to vibro ----
// The HDF5 library trusts a file's metadata: a flipped byte in a global heap makes H5Aread copy
// out of bounds and crash. Before vibro reads a file it is read once in full by a child process
// (every attribute, every dataset up to kProbeBytes): if that child dies, the file is reported as
// corrupt (bad input) and vibro itself never touches it.
constexpr double kProbeBytes = 64e6;

bool ReadAll(hid_t obj, hid_t file_type, hid_t space, bool attribute) {
  Handle mtype(H5Tget_native_type(file_type, H5T_DIR_ASCEND), H5Tclose);
  if (!mtype) return false;
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  const size_t size = H5Tget_size(mtype.get());
  if (n < 0 || size == 0) return false;
  Handle mem_space(H5Scopy(space), H5Sclose);
  hssize_t count = n;
  if (static_cast<double>(n) * static_cast<double>(size) > kProbeBytes && !attribute) {
    // The first rows of a large dataset (its metadata is what can be corrupt, not its values).
    const int rank = H5Sget_simple_extent_ndims(space);
    if (rank < 1 || rank > 8) return false;
    hsize_t dims[8] = {0}, start[8] = {0};
    H5Sget_simple_extent_dims(space, dims, nullptr);
    const hssize_t row = dims[0] > 0 ? n / static_cast<hssize_t>(dims[0]) : 1;
    dims[0] = std::max<hsize_t>(1, static_cast<hsize_t>(kProbeBytes / static_cast<double>(size) / static_cast<double>(std::max<hssize_t>(row, 1))));
    H5Sselect_hyperslab(space, H5S_SELECT_SET, start, nullptr, dims, nullptr);
    mem_space = Handle(H5Screate_simple(rank, dims, nullptr), H5Sclose);
    count = H5Sget_simple_extent_npoints(mem_space.get());
  }
  std::vector<unsigned char> buf(static_cast<size_t>(count) * size + 16);
  const herr_t st = attribute ? H5Aread(obj, mtype.get(), buf.data())
                              : H5Dread(obj, mtype.get(), mem_space.get(), space, H5P_DEFAULT, buf.data());
  if (st < 0) return false;
  if (H5Tdetect_class(mtype.get(), H5T_VLEN) > 0 || H5Tis_variable_str(mtype.get()) > 0)
    H5Dvlen_reclaim(mtype.get(), mem_space.get(), H5P_DEFAULT, buf.data());
  return true;
}

herr_t ProbeAttribute(hid_t loc, const char* name, const H5A_info_t*, void*) {
  Handle a(H5Aopen(loc, name, H5P_DEFAULT), H5Aclose);
  if (!a) return -1;
  Handle type(H5Aget_type(a.get()), H5Tclose);
  Handle space(H5Aget_space(a.get()), H5Sclose);
  return type && space && ReadAll(a.get(), type.get(), space.get(), true) ? 0 : -1;
}

herr_t ProbeObject(hid_t root, const char* name, const H5O_info_t* info, void*) {
  if (H5Aiterate_by_name(root, name, H5_INDEX_NAME, H5_ITER_NATIVE, nullptr, ProbeAttribute, nullptr,
                         H5P_DEFAULT) < 0)
    return -1;
  if (info->type != H5O_TYPE_DATASET) return 0;
  Handle d(H5Dopen2(root, name, H5P_DEFAULT), H5Dclose);
  if (!d) return -1;
  Handle type(H5Dget_type(d.get()), H5Tclose);
  Handle space(H5Dget_space(d.get()), H5Sclose);
  return type && space && ReadAll(d.get(), type.get(), space.get(), false) ? 0 : -1;
}

void ProbeInChild(const std::string& path) {
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return;  // no child: vibro's own checked reads follow
  if (pid == 0) {
    alarm(120);  // a corrupt file that makes the library loop is reported too
    SilenceHdf5();
    Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    // Not readable as HDF5 at all, or an object that fails cleanly: vibro's own reads report it.
    if (file) H5Ovisit2(file.get(), H5_INDEX_NAME, H5_ITER_NATIVE, ProbeObject, nullptr, H5O_INFO_BASIC);
    _exit(0);
  }
  int st = 0;
  while (waitpid(pid, &st, 0) < 0 && errno == EINTR) {
  }
  // The child exits 0 whatever it read; a signal or another exit (a sanitizer's report) is a crash.
  if (WIFSIGNALED(st) || (WIFEXITED(st) && WEXITSTATUS(st) != 0))
    throw InputError({fmt::format("{}: a corrupt HDF5 file: reading it makes the HDF5 library fail "
                                  "(status {} of a test read); the file was not changed",
                                  path, WIFSIGNALED(st) ? WTERMSIG(st) : WEXITSTATUS(st))});
}

// Before a resume changes a file, `changes` (every change it makes before the run goes on) are
// made to a copy in a child process: a file whose metadata cannot take them (a failed truncation
// would leave it half changed) is refused unchanged. A refusal for a reason of the input itself
// (InputError) is left to the real call, which throws it before changing anything.
void ProbeWrite(const std::string& path, const std::function<void(const std::string&)>& changes) {
  struct stat st_file {};
  if (stat(path.c_str(), &st_file) != 0 || st_file.st_size > (off_t{1} << 30)) return;  // no copy of GBs
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return;
  if (pid == 0) {
    alarm(120);
    SilenceHdf5();
    char copy[] = "/tmp/vibro-resume-probe-XXXXXX";
    const int fd = mkstemp(copy);
    if (fd < 0) _exit(0);  // no room for a copy: go on without the trial
    bool ok = false;
    if (FILE* in = std::fopen(path.c_str(), "rb")) {
      char buf[1 << 16];
      size_t n;
      ok = true;
      while (ok && (n = std::fread(buf, 1, sizeof buf, in)) > 0) ok = write(fd, buf, n) == static_cast<ssize_t>(n);
      std::fclose(in);
    }
    close(fd);
    int code = 0;
    if (ok) {
      try {
        changes(copy);
      } catch (const InputError& e) {
        // "cannot resume: <HDF5 failure>" is the file's damage; other refusals are the input's.
        code = std::string(e.what()).find("HDF5") != std::string::npos ? 3 : 0;
      } catch (const std::exception&) {
        code = 3;
      }
    }
    unlink(copy);
    _exit(code);
  }
  int st = 0;
  while (waitpid(pid, &st, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(st) || (WIFEXITED(st) && WEXITSTATUS(st) != 0))
    throw InputError({fmt::format("{}: cannot resume: a corrupt HDF5 file (a test write to a copy of it "
                                  "failed); the file was not changed",
                                  path)});
}


// H5Literate callback: appends the names of the groups among the links to a vector<string>.
herr_t ListGroup(hid_t loc, const char* name, const H5L_info_t*, void* names) {
  Handle g(H5Gopen2(loc, name, H5P_DEFAULT), H5Gclose);  // fails (silently) for a dataset
  if (g) static_cast<std::vector<std::string>*>(names)->push_back(name);
  return 0;
}
}  // namespace

namespace {
// An attribute as text for `vibro info`: strings as they are, a scalar number with fmt's
// shortest form, an array as its length.
std::string AttrText(hid_t obj, const char* name) {
  Handle a(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  if (!a) return "";
  Handle type(H5Aget_type(a.get()), H5Tclose);
  Handle space(H5Aget_space(a.get()), H5Sclose);
  if (H5Tget_class(type.get()) == H5T_STRING) return ReadString(obj, name);
  const auto n = H5Sget_simple_extent_npoints(space.get());
  if (H5Sget_simple_extent_ndims(space.get()) > 0) return fmt::format("[{} values]", n);
  double v = 0;
  if (H5Aread(a.get(), H5T_NATIVE_DOUBLE, &v) < 0) return "";
  return fmt::format("{}", v);
}

// What a result group holds, in a line: its rows and main attributes.
std::string DescribeGroup(hid_t f, const std::string& name) {
  Handle g(H5Gopen2(f, name.c_str(), H5P_DEFAULT), H5Gclose);
  if (!g) return "";
  std::vector<std::string> parts;
  for (const char* d : {"value", "labels", "t", "kind", "value1", "index"}) {
    if (H5Lexists(g.get(), d, H5P_DEFAULT) <= 0) continue;
    Handle ds(H5Dopen2(g.get(), d, H5P_DEFAULT), H5Dclose);
    if (!ds) continue;
    Handle space(H5Dget_space(ds.get()), H5Sclose);
    hsize_t dims[2] = {0, 0};
    const int rank = H5Sget_simple_extent_dims(space.get(), dims, nullptr);
    parts.push_back(rank == 2 && std::string(d) == "labels" ? fmt::format("{} × {} cells", dims[1], dims[0])
                                                             : fmt::format("{} rows", dims[0]));
    break;
  }
  for (const char* k : {"param", "param1", "param2", "x", "y", "period", "stable", "residual", "end", "status",
                        "unresolved_fraction"}) {
    if (H5Aexists(g.get(), k) <= 0) continue;
    const auto text = AttrText(g.get(), k);
    if (!text.empty()) parts.push_back(fmt::format("{} = {}", k, text));
  }
  std::string line;
  for (const auto& p : parts) line += (line.empty() ? "" : ", ") + p;
  return line;
}
}  // namespace

StoredRun ReadStoredRun(const std::string& path, int tail_periods) {
  SilenceHdf5();
  ProbeInChild(path);
  StoredRun out;
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file) throw InputError({fmt::format("{}: cannot open as an HDF5 file", path)});
  const hid_t f = file.get();
  if (H5Aexists(f, "vibro_version") <= 0)
    throw InputError({fmt::format("{}: not a vibro output file (no vibro_version attribute)", path)});
  try {
    out.version = ReadString(f, "vibro_version");
    out.scene_text = ReadString(f, "scene");
    out.engine = ReadString(f, "engine");
    out.chatter = ReadString(f, "chatter");
    out.status = ReadString(f, "status");
    out.message = ReadString(f, "message");
    out.created = ReadString(f, "created");
    Handle ev(Check(H5Gopen2(f, "/events", H5P_DEFAULT), "/events"), H5Gclose);
    Handle sa(Check(H5Gopen2(f, "/samples", H5P_DEFAULT), "/samples"), H5Gclose);
    Handle se(Check(H5Gopen2(f, "/section", H5P_DEFAULT), "/section"), H5Gclose);
    Handle kind_type = KindType();
    EventTable events;
    StateTable samples, sections;
    events.Open(ev.get(), kind_type.get());
    samples.Open(sa.get(), Column::kAnyCols);
    sections.Open(se.get(), Column::kAnyCols);
    out.events = static_cast<long long>(events.t.rows());
    out.samples = static_cast<long long>(samples.t.rows());
    out.sections = static_cast<long long>(sections.t.rows());

    Handle cpg(Check(H5Gopen2(f, "/checkpoint", H5P_DEFAULT), "/checkpoint"), H5Gclose);
    const hid_t g = cpg.get();
    hsize_t cp_events = events.t.rows(), cp_sections = sections.t.rows();
    if (auto period = ReadScalar<std::int64_t>(g, "period", H5T_NATIVE_INT64)) {
      Checkpoint c{};
      c.clock = {*period, *ReadScalar<double>(g, "offset", H5T_NATIVE_DOUBLE)};
      const auto X = ReadDoubles(g, "X"), V = ReadDoubles(g, "V");
      // Every value of the checkpoint in its range before it is used (a resume starts from it).
      const auto bad = [](const std::string& what) {
        throw std::runtime_error("checkpoint " + what + " out of range");
      };
      if (*period < 0 || !std::isfinite(c.clock.offset) || c.clock.offset < 0) bad("period/offset");
      if (X.empty() || X.size() != V.size() || X.size() != sections.X.cols() ||
          V.size() != sections.V.cols() || samples.X.cols() != X.size() || samples.V.cols() != X.size())
        bad("X/V (their length must be the width of /section/X, /section/V, /samples/X, /samples/V)");
      for (double x : X) if (!std::isfinite(x)) bad("X");
      for (double x : V) if (!std::isfinite(x)) bad("V");
      c.X = Eigen::Map<const Eigen::VectorXd>(X.data(), static_cast<Eigen::Index>(X.size()));
      c.V = Eigen::Map<const Eigen::VectorXd>(V.data(), static_cast<Eigen::Index>(V.size()));
      c.mode = static_cast<Mode>(*ReadScalar<std::int64_t>(g, "mode", H5T_NATIVE_INT64));
      c.gap = *ReadScalar<double>(g, "gap", H5T_NATIVE_DOUBLE);
      c.start_kind = static_cast<int>(*ReadScalar<std::int64_t>(g, "start_kind", H5T_NATIVE_INT64));
      c.chatter_first_speed = *ReadScalar<double>(g, "chatter_first_speed", H5T_NATIVE_DOUBLE);
      c.chatter_last_speed = *ReadScalar<double>(g, "chatter_last_speed", H5T_NATIVE_DOUBLE);
      c.sample_index = *ReadScalar<std::int64_t>(g, "sample_index", H5T_NATIVE_INT64);
      c.counts.impacts = *ReadScalar<std::int64_t>(g, "impacts", H5T_NATIVE_INT64);
      c.counts.accumulations = *ReadScalar<std::int64_t>(g, "accumulations", H5T_NATIVE_INT64);
      c.counts.sticks = *ReadScalar<std::int64_t>(g, "sticks", H5T_NATIVE_INT64);
      c.counts.releases = *ReadScalar<std::int64_t>(g, "releases", H5T_NATIVE_INT64);
      c.counts.grazings = *ReadScalar<std::int64_t>(g, "grazings", H5T_NATIVE_INT64);
      cp_events = static_cast<hsize_t>(*ReadScalar<std::int64_t>(g, "events", H5T_NATIVE_INT64));
      cp_sections = static_cast<hsize_t>(*ReadScalar<std::int64_t>(g, "sections", H5T_NATIVE_INT64));
      const auto cp_samples = *ReadScalar<std::int64_t>(g, "samples", H5T_NATIVE_INT64);
      if (static_cast<int>(c.mode) != 0 && static_cast<int>(c.mode) != 1) bad("mode");
      if (c.start_kind < 0 || c.start_kind > 8 || !std::isfinite(c.gap)) bad("start");
      if (!std::isfinite(c.chatter_first_speed) || !std::isfinite(c.chatter_last_speed)) bad("chatter speeds");
      if (c.sample_index < 0 || c.counts.impacts < 0 || c.counts.accumulations < 0 || c.counts.sticks < 0 ||
          c.counts.releases < 0 || c.counts.grazings < 0)
        bad("counts");
      if (cp_events > events.t.rows() || cp_sections > sections.t.rows() || cp_samples < 0 ||
          static_cast<hsize_t>(cp_samples) > samples.t.rows())
        bad("row counts (more rows than the tables hold)");
      for (Column* col : events.All())
        if (col->rows() < cp_events) bad("events (a column of /events is short)");
      for (Column* col : sections.All())
        if (col->rows() < cp_sections) bad("sections (a column of /section is short)");
      for (Column* col : samples.All())
        if (col->rows() < static_cast<hsize_t>(cp_samples)) bad("samples (a column of /samples is short)");
      out.checkpoint = c;
    }

    if (tail_periods > 0 && out.checkpoint) {
      const long long from = out.checkpoint->clock.period - tail_periods;
      // Sections: one row per period, the last tail_periods + 1 before the checkpoint.
      const hsize_t n_se = std::min<hsize_t>(cp_sections, static_cast<hsize_t>(tail_periods + 1));
      const hsize_t first = cp_sections - n_se;
      const auto dof = static_cast<size_t>(out.checkpoint->X.size());
      std::vector<std::int64_t> per(n_se);
      std::vector<double> X(n_se * dof), V(n_se * dof);
      std::vector<std::int8_t> mode(n_se);
      sections.period.Read(first, n_se, per.data());
      sections.X.Read(first, n_se, X.data());
      sections.V.Read(first, n_se, V.data());
      sections.mode.Read(first, n_se, mode.data());
      for (hsize_t i = 0; i < n_se; ++i) {
        out.tail_section_clocks.push_back({per[i], 0.0});
        out.tail_section_X.emplace_back(Eigen::Map<Eigen::VectorXd>(X.data() + i * dof, static_cast<Eigen::Index>(dof)));
        out.tail_section_V.emplace_back(Eigen::Map<Eigen::VectorXd>(V.data() + i * dof, static_cast<Eigen::Index>(dof)));
        out.tail_section_modes.push_back(static_cast<Mode>(mode[i]));
      }
      // Events: read backwards in blocks until before `from`.
      hsize_t first_ev = cp_events;
      std::vector<std::int64_t> block;
      while (first_ev > 0) {
        const hsize_t n = std::min<hsize_t>(first_ev, 65536);
        block.resize(n);
        events.period.Read(first_ev - n, n, block.data());
        first_ev -= n;
        if (block.front() < from) {
          hsize_t skip = 0;
          while (skip < n && block[skip] < from) ++skip;
          first_ev += skip;
          break;
        }
      }
      const hsize_t n_ev = cp_events - first_ev;
      std::vector<double> t(n_ev), off(n_ev), xB(n_ev), vb(n_ev), va(n_ev);
      std::vector<std::int64_t> ep(n_ev);
      std::vector<std::int8_t> kind(n_ev);
      events.offset.Read(first_ev, n_ev, off.data());
      events.t.Read(first_ev, n_ev, t.data());
      events.period.Read(first_ev, n_ev, ep.data());
      events.kind.Read(first_ev, n_ev, kind.data());
      events.xB.Read(first_ev, n_ev, xB.data());
      events.v_before.Read(first_ev, n_ev, vb.data());
      events.v_after.Read(first_ev, n_ev, va.data());
      for (hsize_t i = 0; i < n_ev; ++i)
        out.tail_events.push_back({static_cast<EventKind>(kind[i]), {ep[i], off[i]}, t[i], xB[i], vb[i], va[i]});
    }

    // Studies and branches (and their files since provenance was stored) have no /attractor.
    out.attractor.kind.clear();
    if (H5Lexists(f, "/attractor", H5P_DEFAULT) > 0) {
      Handle ag(Check(H5Gopen2(f, "/attractor", H5P_DEFAULT), "/attractor"), H5Gclose);
      out.attractor.kind = ReadString(ag.get(), "kind");
      if (auto p = ReadScalar<std::int64_t>(ag.get(), "period", H5T_NATIVE_INT64))
        out.attractor.period = static_cast<int>(*p);
      if (auto p = ReadScalar<std::int64_t>(ag.get(), "impacts_per_period", H5T_NATIVE_INT64))
        out.attractor.impacts_per_period = *p;
      out.attractor.sticking_fraction = ReadScalar<double>(ag.get(), "sticking_fraction", H5T_NATIVE_DOUBLE);
      const auto ph = ReadDoubles(ag.get(), "stick_phases");
      for (size_t i = 0; i + 1 < ph.size(); i += 2) out.attractor.stick_phases.emplace_back(ph[i], ph[i + 1]);
      out.attractor.impact_phases = ReadDoubles(ag.get(), "impact_phases");
      out.attractor.impact_velocities = ReadDoubles(ag.get(), "impact_velocities");
    }
    if (H5Aexists(f, "command") > 0) out.command = ReadString(f, "command");
    if (H5Aexists(f, "git_commit") > 0) out.git_commit = ReadString(f, "git_commit");
    H5Literate(f, H5_INDEX_NAME, H5_ITER_INC, nullptr, ListGroup, &out.groups);
    for (const auto& name : out.groups) out.group_notes.push_back(DescribeGroup(f, name));
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {  // also a missing attribute (bad_optional_access)
    throw InputError({fmt::format("{}: not a readable vibro output file: {}", path, e.what())});
  }
  return out;
}

Hdf5Store::Stats Hdf5Store::stats() const { return impl_->stats; }

namespace {

void DeleteLink(hid_t loc, const char* name) {
  if (H5Lexists(loc, name, H5P_DEFAULT) > 0) H5Ldelete(loc, name, H5P_DEFAULT);
}

}  // namespace

void Hdf5Store::BeginStudy(const StudyGrid& grid) {
  auto& m = *impl_;
  const hid_t f = m.file.get();
  m.basin = Handle(Check(H5Gcreate2(f, "/basin", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "/basin"), H5Gclose);
  const hid_t b = m.basin.get();
  WriteString(b, "x", grid.x.name);
  WriteString(b, "y", grid.y.name);
  WriteDoubles(b, "x_range", {grid.x.from, grid.x.to});
  WriteDoubles(b, "y_range", {grid.y.from, grid.y.to});
  WriteInt(b, "nx", grid.nx);
  WriteInt(b, "ny", grid.ny);
  WriteInt(b, "early_stop", grid.early_stop ? 1 : 0);
  m.cells_group = Handle(Check(H5Gcreate2(b, "cells", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "cells"), H5Gclose);
  m.zcols = static_cast<hsize_t>(2 * m.header.dof);
  m.cells.emplace();
  m.cells->Create(m.cells_group.get(), m.zcols);
  m.Flush();
}

void Hdf5Store::WriteCells(const std::vector<size_t>& indices, const std::vector<CellResult>& cells) {
  auto& m = *impl_;
  for (size_t i : indices)
    if (cells[i].state != CellResult::State::kPending) m.cells->Push(i, cells[i], m.zcols);
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - m.last_flush).count() >= m.flush_interval) m.Flush();
}

std::unique_ptr<Hdf5Store> Hdf5Store::ResumeStudy(const std::string& path, const StoreHeader& h,
                                                  const StudyGrid& grid, std::vector<CellResult>& cells,
                                                  double flush_interval) {
  SilenceHdf5();
  const StoredRun stored = ReadStoredRun(path);
  if (stored.scene_text != h.scene_text)
    throw InputError({fmt::format(
        "{}: cannot resume: the file holds a different scene (or different --set overrides) "
        "than the one given; resume with exactly the scene of the interrupted study",
        path)});
  if (stored.status == "ok")
    throw InputError({fmt::format("{}: nothing to resume: the study finished (status ok)", path)});
  // As in Resume: every change is made first on a copy (ProbeWrite).
  const auto prepare = [&](const std::string& file_path) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->header = h;
  impl->flush_interval = flush_interval;
  impl->zcols = static_cast<hsize_t>(2 * h.dof);
  std::vector<std::string> problems;
  try {
    Handle fapl = FileAccess();
    impl->file = Handle(H5Fopen(file_path.c_str(), H5F_ACC_RDWR, fapl.get()), H5Fclose);
    if (!impl->file) throw std::runtime_error("cannot open the file for writing");
    const hid_t f = impl->file.get();
    if (H5Lexists(f, "/basin", H5P_DEFAULT) <= 0 || H5Lexists(f, "/basin/cells", H5P_DEFAULT) <= 0)
      throw InputError({fmt::format("{}: cannot resume: the file holds no basin study", path)});
    impl->basin = Handle(Check(H5Gopen2(f, "/basin", H5P_DEFAULT), "/basin"), H5Gclose);
    const hid_t b = impl->basin.get();
    // The same grid, or nothing.
    const auto same = [&](const std::string& what, const std::string& stored_value,
                          const std::string& given) {
      if (stored_value != given)
        problems.push_back(fmt::format("{}: cannot resume: {} is {} in the file but {} here", path, what,
                                       stored_value, given));
    };
    same("--x", ReadString(b, "x"), grid.x.name);
    same("--y", ReadString(b, "y"), grid.y.name);
    const auto range = [](const std::vector<double>& r) {
      return r.size() == 2 ? fmt::format("{},{}", r[0], r[1]) : std::string("?");
    };
    same("--x-range", range(ReadDoubles(b, "x_range")), range({grid.x.from, grid.x.to}));
    same("--y-range", range(ReadDoubles(b, "y_range")), range({grid.y.from, grid.y.to}));
    same("--grid",
         fmt::format("{},{}", ReadScalar<std::int64_t>(b, "nx", H5T_NATIVE_INT64).value_or(-1),
                     ReadScalar<std::int64_t>(b, "ny", H5T_NATIVE_INT64).value_or(-1)),
         fmt::format("{},{}", grid.nx, grid.ny));
    same("--full-periods",
         ReadScalar<std::int64_t>(b, "early_stop", H5T_NATIVE_INT64).value_or(1) ? "off" : "on",
         grid.early_stop ? "off" : "on");
    if (!problems.empty()) throw InputError(problems);
    // Everything is read and checked before anything is changed: a refused resume leaves the
    // file as it was.
    impl->cells_group = Handle(Check(H5Gopen2(b, "cells", H5P_DEFAULT), "cells"), H5Gclose);
    impl->cells.emplace();
    CellTable& t = *impl->cells;
    t.Open(impl->cells_group.get(), impl->zcols);
    hsize_t rows = t.index.rows();
    for (Column* c : t.All())
      if (c != &t.phases) rows = std::min(rows, c->rows());
    const auto n = static_cast<size_t>(rows);
    std::vector<std::int64_t> index(n), impacts(n), periods(n);
    std::vector<std::int8_t> state(n), kind(n), stop(n);
    std::vector<std::int32_t> period(n), ns(n), ni(n);
    std::vector<double> sp(n), z(n * impl->zcols);
    t.index.Read(0, rows, index.data());
    t.state.Read(0, rows, state.data());
    t.kind.Read(0, rows, kind.data());
    t.period.Read(0, rows, period.data());
    t.impacts.Read(0, rows, impacts.data());
    t.sticking_fraction.Read(0, rows, sp.data());
    t.periods.Read(0, rows, periods.data());
    t.stop.Read(0, rows, stop.data());
    t.stick_count.Read(0, rows, ns.data());
    t.impact_count.Read(0, rows, ni.data());
    t.z.Read(0, rows, z.data());
    hsize_t values = 0;
    for (size_t i = 0; i < n; ++i) {
      // Each cell's fields in range (a flipped bit must not index past the tables).
      if (ns[i] < 0 || ni[i] < 0 || ns[i] > (1 << 20) || ni[i] > (1 << 20))
        throw std::runtime_error(fmt::format("cell row {}: phase counts {}, {} out of range", i, ns[i], ni[i]));
      if (state[i] < 0 || state[i] > 3 || kind[i] < 0 || kind[i] > 5 || periods[i] < 0 || period[i] < 0)
        throw std::runtime_error(fmt::format("cell row {}: state, kind or period out of range", i));
      if (index[i] < 0 || static_cast<size_t>(index[i]) >= cells.size())
        throw std::runtime_error("a cell index beyond the grid");
      if (!std::isnan(sp[i]) && !(sp[i] >= 0 && sp[i] <= 1))
        throw std::runtime_error(fmt::format("cell row {}: sticking fraction {} outside [0, 1]", i, sp[i]));
      values += static_cast<hsize_t>(2 * ns[i] + 2 * ni[i]);
    }
    if (values > t.phases.rows()) throw std::runtime_error("the cell table is incomplete");
    std::vector<double> ph(static_cast<size_t>(values));
    t.phases.Read(0, values, ph.data());
    const double* p = ph.data();
    const auto dof = static_cast<Eigen::Index>(h.dof);
    for (size_t i = 0; i < n; ++i) {
      if (index[i] < 0 || static_cast<size_t>(index[i]) >= cells.size())
        throw std::runtime_error("a cell index beyond the grid");
      CellResult c;
      c.state = static_cast<CellResult::State>(state[i]);
      c.attractor.kind = KindName(kind[i]);
      if (period[i] > 0) c.attractor.period = period[i];
      if (impacts[i] >= 0) c.attractor.impacts_per_period = impacts[i];
      if (!std::isnan(sp[i])) c.attractor.sticking_fraction = sp[i];
      c.periods = periods[i];
      c.stop = stop[i];
      for (int k = 0; k < ns[i]; ++k, p += 2) c.attractor.stick_phases.emplace_back(p[0], p[1]);
      c.attractor.impact_phases.assign(p, p + ni[i]);
      c.attractor.impact_velocities.assign(p + ni[i], p + 2 * ni[i]);
      p += 2 * ni[i];
      c.z = Eigen::Map<const Eigen::VectorXd>(z.data() + i * impl->zcols, 2 * dof);
      cells[static_cast<size_t>(index[i])] = std::move(c);
    }
    // Now the file changes, first its status (a file whose metadata cannot take a write fails
    // here, before anything else changed); then rows after the last complete batch are dropped,
    // and the label map and table of the interrupted run removed (written again at the end).
    WriteString(f, "status", "running");
    WriteString(f, "message", "");
    for (Column* c : t.All()) c->Truncate(c == &t.phases ? values : rows);
    DeleteLink(b, "labels");
    DeleteLink(f, "/attractors");
    impl->OpenGroups();
    impl->kind_type = KindType();
    impl->OpenColumns();
    impl->Flush();
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError({fmt::format("{}: cannot resume: {}", path, e.what())});
  }
  return impl;
  };
  ProbeWrite(path, prepare);
  auto impl = prepare(path);
  impl->last_flush = std::chrono::steady_clock::now();
  return std::unique_ptr<Hdf5Store>(new Hdf5Store(std::move(impl)));
}

namespace {
void WriteAttractorTable(hid_t f, const StudyResult& st);
}  // namespace

void Hdf5Store::WriteStudy(const StudyResult& st, const StudyGrid& grid) {
  auto& m = *impl_;
  const hid_t f = m.file.get();
  if (!m.basin) {
    m.basin = Handle(Check(H5Gcreate2(f, "/basin", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "/basin"), H5Gclose);
    WriteString(m.basin.get(), "x", grid.x.name);
    WriteString(m.basin.get(), "y", grid.y.name);
    WriteDoubles(m.basin.get(), "x_range", {grid.x.from, grid.x.to});
    WriteDoubles(m.basin.get(), "y_range", {grid.y.from, grid.y.to});
    WriteInt(m.basin.get(), "nx", grid.nx);
    WriteInt(m.basin.get(), "ny", grid.ny);
    WriteInt(m.basin.get(), "early_stop", grid.early_stop ? 1 : 0);
  }
  const hid_t basin = m.basin.get();
  DeleteLink(basin, "labels");
  DeleteLink(f, "/attractors");
  const hsize_t dims[2] = {static_cast<hsize_t>(grid.ny), static_cast<hsize_t>(grid.nx)};
  Handle space(H5Screate_simple(2, dims, nullptr), H5Sclose);
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  const hsize_t chunk[2] = {std::min<hsize_t>(dims[0], 64), std::min<hsize_t>(dims[1], 512)};
  H5Pset_chunk(dcpl.get(), 2, chunk);
  H5Pset_deflate(dcpl.get(), kDeflate);
  Handle labels(Check(H5Dcreate2(basin, "labels", H5T_STD_I32LE, space.get(), H5P_DEFAULT,
                                 dcpl.get(), H5P_DEFAULT),
                      "labels"),
                H5Dclose);
  Check(H5Dwrite(labels.get(), H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, st.labels.data()),
        "labels", 0);
  WriteDouble(basin, "unresolved_fraction", st.unresolved_fraction);
  WriteDouble(basin, "inadmissible_fraction", st.inadmissible_fraction);
  WriteDouble(basin, "pending_fraction", st.pending_fraction);
  // /attractors: a table, one dataset per column, row k ↔ label k.
  WriteAttractorTable(f, st);
}

namespace {

// A small contiguous dataset of any rank written at once (studies, sweeps, continuation).
void WriteDataset(hid_t loc, const char* name, hid_t file_type, hid_t mem_type, const void* data,
                  std::vector<hsize_t> dims) {
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  Handle d(Check(H5Dcreate2(loc, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name),
           H5Dclose);
  if (dims[0] > 0) Check(H5Dwrite(d.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name, 0);
}
void WriteArray(hid_t loc, const char* name, hid_t file_type, hid_t mem_type, const void* data,
                hsize_t rows, hsize_t cols = 0) {
  WriteDataset(loc, name, file_type, mem_type, data, cols > 0 ? std::vector<hsize_t>{rows, cols}
                                                              : std::vector<hsize_t>{rows});
}
void WriteColumn(hid_t g, const char* name, const std::vector<double>& v) {
  WriteArray(g, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v.data(), v.size());
}
Handle NewGroup(hid_t f, const char* name) {
  return Handle(Check(H5Gcreate2(f, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name), H5Gclose);
}

void WriteStrings(hid_t loc, const char* name, const std::vector<std::string>& v) {
  std::vector<const char*> p;
  for (const auto& x : v) p.push_back(x.c_str());
  Handle type = StringType();
  WriteArray(loc, name, type.get(), type.get(), p.data(), p.size());
}

// The attractors of a study as a table: one dataset per column, row k ↔ label k. Integer
// columns are integers (−1 for a null period or impact count, stable −1 when the orbit was not
// solved), null floats NaN, strings variable-length UTF-8; the multipliers of row k are the
// rows multiplier_offset[k] … + multiplier_count[k] − 1 of floquet_multipliers (M, 2) [re, im].
void WriteAttractorTable(hid_t f, const StudyResult& st) {
  Handle table = NewGroup(f, "/attractors");
  const hid_t g = table.get();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::int32_t> period, merged, count, offset;
  std::vector<std::int64_t> impacts;
  std::vector<std::int8_t> stable;
  std::vector<double> sp, frac, err, residual, mu, lead;
  std::vector<std::string> kinds, status;
  for (const auto& a : st.attractors) {
    period.push_back(a.attractor.period ? *a.attractor.period : -1);
    impacts.push_back(a.attractor.impacts_per_period ? *a.attractor.impacts_per_period : -1);
    sp.push_back(a.attractor.sticking_fraction.value_or(nan));
    frac.push_back(a.basin_fraction);
    err.push_back(a.basin_fraction_error);
    kinds.push_back(a.attractor.kind);
    status.push_back(a.orbit.status);
    stable.push_back(a.orbit.stable ? (*a.orbit.stable ? 1 : 0) : -1);
    residual.push_back(a.orbit.residual);
    merged.push_back(a.orbit.merged);
    offset.push_back(static_cast<std::int32_t>(mu.size() / 2));
    count.push_back(static_cast<std::int32_t>(a.orbit.multipliers.size()));
    double l = a.orbit.multipliers.empty() ? nan : 0;
    for (const auto& z : a.orbit.multipliers) {
      mu.push_back(z.real());
      mu.push_back(z.imag());
      l = std::max(l, std::abs(z));
    }
    lead.push_back(l);
  }
  const hsize_t n = st.attractors.size();
  WriteStrings(g, "kind", kinds);
  WriteArray(g, "period", H5T_STD_I32LE, H5T_NATIVE_INT32, period.data(), n);
  WriteArray(g, "impacts_per_period", H5T_STD_I64LE, H5T_NATIVE_INT64, impacts.data(), n);
  WriteColumn(g, "sticking_fraction", sp);
  WriteColumn(g, "basin_fraction", frac);
  WriteColumn(g, "basin_fraction_error", err);
  // The Poincaré solver's orbit of each class (vibro extension).
  WriteStrings(g, "orbit_status", status);
  WriteArray(g, "stable", H5T_STD_I8LE, H5T_NATIVE_INT8, stable.data(), n);
  WriteColumn(g, "orbit_residual", residual);
  WriteArray(g, "merged_classes", H5T_STD_I32LE, H5T_NATIVE_INT32, merged.data(), n);
  WriteArray(g, "multiplier_count", H5T_STD_I32LE, H5T_NATIVE_INT32, count.data(), n);
  WriteArray(g, "multiplier_offset", H5T_STD_I32LE, H5T_NATIVE_INT32, offset.data(), n);
  WriteArray(g, "floquet_multipliers", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, mu.data(), mu.size() / 2, 2);
  WriteColumn(g, "leading_multiplier", lead);
  WriteInt(g, "rows", static_cast<long long>(n));
}

}  // namespace

void Hdf5Store::WriteSweep(const std::vector<SweepPoint>& sweep, const SweepSpec& spec) {
  const hid_t f = impl_->file.get();
  Handle g(Check(H5Gcreate2(f, "/sweep", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "/sweep"), H5Gclose);
  const hsize_t n = sweep.size(), rec = static_cast<hsize_t>(std::max(spec.record, 1));
  std::vector<double> value, sp, xB(n * rec, std::numeric_limits<double>::quiet_NaN()), vB = xB;
  std::vector<std::uint8_t> up;
  std::vector<std::int32_t> period;
  std::vector<std::int64_t> impacts;
  std::vector<std::string> kind;
  for (hsize_t i = 0; i < n; ++i) {
    const SweepPoint& p = sweep[i];
    value.push_back(p.value);
    up.push_back(p.upward ? 1 : 0);
    kind.push_back(p.attractor.kind);
    period.push_back(p.attractor.period.value_or(-1));
    impacts.push_back(p.attractor.impacts_per_period.value_or(-1));
    sp.push_back(p.attractor.sticking_fraction.value_or(std::numeric_limits<double>::quiet_NaN()));
    // The last `record` section points, the most recent last (rows of shorter runs NaN-padded in front).
    const hsize_t k = std::min<hsize_t>(p.x_B.size(), rec);
    for (hsize_t j = 0; j < k; ++j) {
      xB[i * rec + rec - k + j] = p.x_B[p.x_B.size() - k + j];
      vB[i * rec + rec - k + j] = p.v_B[p.v_B.size() - k + j];
    }
  }
  const hid_t gg = g.get();
  WriteArray(gg, "value", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, value.data(), n);
  WriteArray(gg, "upward", H5T_STD_U8LE, H5T_NATIVE_UINT8, up.data(), n);
  WriteStrings(gg, "kind", kind);
  WriteArray(gg, "period", H5T_STD_I32LE, H5T_NATIVE_INT32, period.data(), n);
  WriteArray(gg, "impacts_per_period", H5T_STD_I64LE, H5T_NATIVE_INT64, impacts.data(), n);
  WriteArray(gg, "sticking_fraction", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, sp.data(), n);
  WriteArray(gg, "x_B", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, xB.data(), n, rec);
  WriteArray(gg, "v_B", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, vB.data(), n, rec);
  WriteString(gg, "param", spec.param);
  WriteDouble(gg, "from", spec.from);
  WriteDouble(gg, "to", spec.to);
  WriteInt(gg, "steps", spec.steps);
  WriteInt(gg, "record", spec.record);
  WriteInt(gg, "both_ways", spec.both_ways ? 1 : 0);
}

void Hdf5Store::WriteGroup(const std::string& group,
                           const std::vector<std::pair<std::string, std::vector<double>>>& values) {
  const hid_t f = impl_->file.get();
  Handle g(H5Lexists(f, group.c_str(), H5P_DEFAULT) > 0
               ? H5Gopen2(f, group.c_str(), H5P_DEFAULT)
               : H5Gcreate2(f, group.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
           H5Gclose);
  Check(g.get(), group.c_str());
  for (const auto& [name, v] : values) WriteDoubles(g.get(), name.c_str(), v);
}


namespace {
// h5py's bool: an int8 enum {FALSE = 0, TRUE = 1}.
Handle BoolType() {
  Handle t(H5Tenum_create(H5T_NATIVE_INT8), H5Tclose);
  const std::int8_t no = 0, yes = 1;
  H5Tenum_insert(t.get(), "FALSE", &no);
  H5Tenum_insert(t.get(), "TRUE", &yes);
  return t;
}
}  // namespace

void Hdf5Store::WriteOrbit(const OrbitResult& orbit) {
  const hid_t f = impl_->file.get();
  Handle g(H5Lexists(f, "/orbit", H5P_DEFAULT) > 0 ? H5Gopen2(f, "/orbit", H5P_DEFAULT)
                                                   : H5Gcreate2(f, "/orbit", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
           H5Gclose);
  Check(g.get(), "/orbit");
  WriteInt(g.get(), "period", orbit.period);
  WriteInt(g.get(), "newton_iterations", orbit.newton_iterations);
  Handle bool_type = BoolType();
  WriteScalar(g.get(), "stable", static_cast<std::int8_t>(orbit.stable ? 1 : 0), bool_type.get(), bool_type.get());
  WriteDouble(g.get(), "residual", orbit.residual);
  WriteDouble(g.get(), "section_time", orbit.section_time);
  WriteDoubles(g.get(), "X", {orbit.X.data(), orbit.X.data() + orbit.X.size()});
  WriteDoubles(g.get(), "V", {orbit.V.data(), orbit.V.data() + orbit.V.size()});
  std::vector<double> mu;
  for (const auto& z : orbit.multipliers) {
    mu.push_back(z.real());
    mu.push_back(z.imag());
  }
  // (m, 2) as [re, im]; (0, 2) for none (one-DOF sticking orbits).
  DeleteAttr(g.get(), "multipliers");
  const hsize_t dims[2] = {orbit.multipliers.size(), 2};
  Handle space(H5Screate_simple(2, dims, nullptr), H5Sclose);
  Handle a(Check(H5Acreate2(g.get(), "multipliers", H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                 "multipliers"),
           H5Aclose);
  if (!mu.empty()) Check(H5Awrite(a.get(), H5T_NATIVE_DOUBLE, mu.data()), "multipliers", 0);
}

const H5Table::Array* H5Table::Find(const std::string& name) const {
  for (const auto& a : arrays)
    if (a.name == name) return &a;
  return nullptr;
}

void Hdf5Store::WriteTable(const std::string& group, const H5Table& t) {
  const Handle g = NewGroup(impl_->file.get(), group.c_str());
  for (const auto& a : t.arrays) {
    const std::vector<hsize_t> dims(a.dims.begin(), a.dims.end());
    if (a.type == 'u') {
      std::vector<std::uint8_t> v(a.data.begin(), a.data.end());
      WriteDataset(g.get(), a.name.c_str(), H5T_STD_U8LE, H5T_NATIVE_UINT8, v.data(), dims);
    } else if (a.type == 'i') {
      std::vector<std::int64_t> v(a.data.begin(), a.data.end());
      WriteDataset(g.get(), a.name.c_str(), H5T_STD_I64LE, H5T_NATIVE_INT64, v.data(), dims);
    } else {
      WriteDataset(g.get(), a.name.c_str(), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, a.data.data(), dims);
    }
  }
  for (const auto& [name, v] : t.strings) WriteStrings(g.get(), name.c_str(), v);
  for (const auto& [name, v] : t.text) WriteString(g.get(), name.c_str(), v);
  for (const auto& [name, v] : t.integers) WriteInt(g.get(), name.c_str(), v);
}

H5Table ReadTable(const std::string& path, const std::string& group) {
  SilenceHdf5();
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file) throw InputError({fmt::format("{}: cannot open as an HDF5 file", path)});
  if (H5Lexists(file.get(), group.c_str(), H5P_DEFAULT) <= 0)
    throw InputError({fmt::format("{}: no group {} in this file", path, group)});
  Handle g(Check(H5Gopen2(file.get(), group.c_str(), H5P_DEFAULT), group.c_str()), H5Gclose);
  H5Table t;
  H5G_info_t info;
  Check(H5Gget_info(g.get(), &info), group.c_str(), 0);
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    char name[256];
    H5Lget_name_by_idx(g.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
    Handle d(H5Dopen2(g.get(), name, H5P_DEFAULT), H5Dclose);
    if (!d) continue;
    Handle type(H5Dget_type(d.get()), H5Tclose);
    Handle space(H5Dget_space(d.get()), H5Sclose);
    const int rank = H5Sget_simple_extent_ndims(space.get());
    std::vector<hsize_t> dims(static_cast<size_t>(std::max(rank, 0)));
    H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
    const auto npts = static_cast<size_t>(H5Sget_simple_extent_npoints(space.get()));
    if (H5Tget_class(type.get()) == H5T_STRING) {
      Handle st = StringType();
      std::vector<char*> p(npts, nullptr);
      if (npts > 0) Check(H5Dread(d.get(), st.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()), name, 0);
      std::vector<std::string> v;
      for (char* x : p) {
        v.emplace_back(x ? x : "");
        H5free_memory(x);
      }
      t.strings.emplace_back(name, v);
    } else {
      H5Table::Array a{name, std::vector<size_t>(dims.begin(), dims.end()), std::vector<double>(npts)};
      if (npts > 0)
        Check(H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, a.data.data()), name, 0);
      t.arrays.push_back(std::move(a));
    }
  }
  std::vector<std::string> names;
  H5Aiterate2(g.get(), H5_INDEX_NAME, H5_ITER_INC, nullptr,
              [](hid_t, const char* attr, const H5A_info_t*, void* data) -> herr_t {
                static_cast<std::vector<std::string>*>(data)->emplace_back(attr);
                return 0;
              },
              &names);
  for (const auto& attr : names) {
    const char* name = attr.c_str();
    Handle a(H5Aopen(g.get(), name, H5P_DEFAULT), H5Aclose);
    if (!a) continue;
    Handle type(H5Aget_type(a.get()), H5Tclose);
    if (H5Tget_class(type.get()) == H5T_STRING)
      t.text.emplace_back(name, ReadString(g.get(), name));
    else if (H5Tget_class(type.get()) == H5T_INTEGER)
      t.integers.emplace_back(name, ReadScalar<long long>(g.get(), name, H5T_NATIVE_LLONG).value_or(0));
  }
  return t;
}

void Hdf5Store::WritePartition(const std::string& param1, const std::string& param2,
                               const std::vector<double>& levels,
                               const std::vector<PartitionColumn>& columns) {
  const Handle g = NewGroup(impl_->file.get(), "/partition");
  WriteString(g.get(), "param1", param1);
  WriteString(g.get(), "param2", param2);
  WriteDoubles(g.get(), "levels", levels);
  std::vector<double> cv, xv1, xl, xv2, bv1, bv2;
  std::vector<std::string> cs, bk;
  for (const auto& c : columns) {
    cv.push_back(c.value1);
    cs.push_back(c.status);
    for (const auto& x : c.crossings) {
      xv1.push_back(c.value1);
      xl.push_back(x.level);
      xv2.push_back(x.value);
    }
    for (const auto& b : c.bifurcations) {
      bv1.push_back(c.value1);
      bv2.push_back(b.value);
      bk.push_back(b.kind);
    }
  }
  WriteColumn(g.get(), "column_value1", cv);
  WriteStrings(g.get(), "column_status", cs);
  WriteColumn(g.get(), "crossing_value1", xv1);
  WriteColumn(g.get(), "crossing_level", xl);
  WriteColumn(g.get(), "crossing_value2", xv2);
  WriteColumn(g.get(), "boundary_value1", bv1);
  WriteColumn(g.get(), "boundary_value2", bv2);
  WriteStrings(g.get(), "boundary_kind", bk);
}

}  // namespace vibro
