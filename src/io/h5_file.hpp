// A small RAII layer over the HDF5 C API for the store's files (docs/output.md). h5_file.cpp is
// the one file of vibro that includes the C header: the record writers and readers (hdf5_*.cpp) see
// handles as plain integers (hid_t is int64_t since HDF5 1.10) and element types as h5::Type.
//
// Errors: a failed call that vibro needs throws std::runtime_error("HDF5: <what> failed"); the
// Try*/Has* functions return an empty handle or false instead, for the optional parts of a file.
// A failed write or flush (full disk, I/O error) throws vibro::WriteError naming the system's
// reason and the file, and marks the file failed: nothing is written to it again (see Close).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "io/chunk_deflate.hpp"

namespace vibro::h5 {

using Id = std::int64_t;     // hid_t
using Size = std::uint64_t;  // hsize_t

using Closer = int (*)(Id);  // herr_t (*)(hid_t)
// Closes `id` with `closer`, unless it belongs to a file that a write failed on (see WriteError in
// vibro/hdf5_store.hpp): such a file is never touched again, not even by a close (which would
// flush half of a state over the last consistent one); its handles are left open.
void Close(Id id, Closer closer);

// Owns one hid_t and closes it with the matching H5?close.
class Handle {
 public:
  using Closer = h5::Closer;
  Handle() = default;
  Handle(Id id, Closer closer) : id_(id), closer_(closer) {}
  Handle(Handle&& o) noexcept : id_(o.id_), closer_(o.closer_) { o.id_ = -1; }
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      Reset();
      id_ = o.id_;
      closer_ = o.closer_;
      o.id_ = -1;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { Reset(); }
  Id get() const { return id_; }
  explicit operator bool() const { return id_ >= 0; }
  void Reset() {
    if (id_ >= 0 && closer_) Close(id_, closer_);
    id_ = -1;
  }

 private:
  Id id_ = -1;
  Closer closer_ = nullptr;
};

// An element type: how it is stored in the file (little-endian, fixed width) and its native
// memory form. Variable-length UTF-8 strings and enums are the same type in file and memory.
class Type {
 public:
  static Type F64();
  static Type I64();
  static Type I32();
  static Type I8();
  static Type U8();
  static Type String();  // variable-length UTF-8: memory elements are const char* / char*
  static Type Bool();    // h5py's bool: an int8 enum {FALSE = 0, TRUE = 1}
  static Type Enum8(const std::vector<std::pair<std::string, std::int8_t>>& members);
  Id file() const { return file_; }
  Id memory() const { return memory_; }
  size_t size() const { return size_; }  // bytes of one memory element

 private:
  Type(Id file, Id memory, size_t size) : file_(file), memory_(memory), size_(size) {}
  Type(Handle owned, size_t size);
  Handle owned_;
  Id file_ = -1, memory_ = -1;
  size_t size_ = 0;
};

// Turns the library's own error printing off (vibro reports errors itself). Idempotent.
void Silence();

// Marks a stretch of a store's HDF5 writes (RAII, any thread): HDF5 1.10 ends the process with
// exit(-1) when some allocations fail, and only an exit(-1) during such a stretch is reported as
// out of memory (exit 3); any other exit status, -1 included, is left as the program gave it.
class WritingScope {
 public:
  WritingScope();
  ~WritingScope();
  WritingScope(const WritingScope&) = delete;
  WritingScope& operator=(const WritingScope&) = delete;
};

// ---- Files ----
bool IsHdf5(const std::string& path);
// Creates (truncates) `path` for the store: freed space never reused, metadata written at
// flushes only (see vibro/hdf5_store.hpp). Throws runtime_error with the system's reason.
Handle CreateFile(const std::string& path);
// Opens `path` read-only, or read-write with the store's cache settings. Empty on failure.
Handle OpenFile(const std::string& path, bool write);
void FlushFile(Id file);
// The bytes of metadata a flush of `file` writes at most (the metadata cache's current size).
Size MetadataBytes(Id file);
// Marks `file` failed as a failed write does (Close): it is never written or closed again.
void MarkFailed(Id file);
// Makes no HDF5 call at all from now on, not even to mark a file (which may allocate): every
// handle is left open, the library's clean-up at exit is skipped, each file keeps its last flush.
// For a process that has no memory left to give the library (memory_reserve.hpp).
void Abandon();

// ---- Links and groups ----
bool Exists(Id loc, const std::string& path);
void DeleteLink(Id loc, const std::string& name);  // if it exists
Handle CreateGroup(Id loc, const std::string& name);
Handle OpenGroup(Id loc, const std::string& name);  // throws when missing
Handle TryOpenGroup(Id loc, const std::string& name);  // empty when missing or not a group
Handle OpenOrCreateGroup(Id loc, const std::string& name);
std::vector<std::string> ChildGroups(Id loc);  // names of the groups linked from loc, in order

// ---- Attributes ----
enum class Class { kString, kInteger, kFloat, kOther };
bool HasAttr(Id obj, const std::string& name);
void DeleteAttr(Id obj, const std::string& name);  // if it exists
std::vector<std::string> AttrNames(Id obj);
Class AttrClass(Id obj, const std::string& name);
void WriteString(Id obj, const std::string& name, const std::string& value);
void WriteDouble(Id obj, const std::string& name, double value);
void WriteInt(Id obj, const std::string& name, long long value);  // int64
void WriteBool(Id obj, const std::string& name, bool value);
// A float64 array, (n) or (n / cols, cols) when cols > 1.
void WriteDoubles(Id obj, const std::string& name, const std::vector<double>& v, Size cols = 1);
void WriteInts(Id obj, const std::string& name, const std::vector<int>& v);  // int32 (n)
void WriteStringArray(Id obj, const std::string& name, const std::vector<std::string>& v);
std::string ReadString(Id obj, const std::string& name);  // "" when absent
std::optional<std::int64_t> ReadInt(Id obj, const std::string& name);
std::optional<double> ReadDouble(Id obj, const std::string& name);
std::vector<double> ReadDoubles(Id obj, const std::string& name);  // empty when absent
// An attribute as text for `vibro info`: a string as it is, a scalar number in fmt's shortest
// form, an array as "[n values]"; "" when it cannot be read.
std::string AttrText(Id obj, const std::string& name);

// ---- Small datasets written or read at once ----
// A contiguous dataset of shape `dims` (dims[0] may be 0) from `data` in type's memory form;
// chunk: optional chunk shape (then deflated).
void WriteDataset(Id loc, const std::string& name, const Type& type, const void* data,
                  const std::vector<Size>& dims, const std::vector<Size>& chunk = {});
void WriteStrings(Id loc, const std::string& name, const std::vector<std::string>& v);
void WriteColumn(Id loc, const std::string& name, const std::vector<double>& v);  // float64 (n)
std::vector<std::string> DatasetNames(Id loc);  // the datasets linked from loc, by name
// Shape of dataset `name`; nullopt when it is missing or not a dataset.
std::optional<std::vector<Size>> DatasetShape(Id loc, const std::string& name);
bool IsStringDataset(Id loc, const std::string& name);
// The element class of dataset `name` (kOther when it is missing or not a dataset).
Class DatasetClass(Id loc, const std::string& name);
// Row `row` of the numeric dataset `name` of rank 1 (one value) or 2 (a row), as float64: only
// that row is read. Throws runtime_error when the row is beyond the dataset or the read fails.
std::vector<double> ReadDatasetRow(Id loc, const std::string& name, Size row);
std::vector<double> ReadDatasetDoubles(Id loc, const std::string& name);  // converted to float64
std::vector<std::string> ReadDatasetStrings(Id loc, const std::string& name);

// ---- Extendible tables ----
// A chunked, deflated dataset of `cols` columns (cols = 0: one-dimensional) that grows by rows
// buffered in memory and written at Flush. It has no chunk cache: Flush writes the rows' chunks
// to the file at once, so that a file's flush (FlushFile) writes metadata only.
// Flush is Stage (the buffered rows set aside: no HDF5 call) then WriteStaged (the HDF5 calls,
// which a writer thread may make while the rows that follow are buffered: the store's
// write-behind, docs/output.md). rows() counts the staged rows as written.
class Column {
 public:
  static constexpr Size kAnyCols = ~Size{0};
  Column() = default;
  // Creates dataset `name` in `group`.
  Column(Id group, const std::string& name, const Type& type, Size cols);
  // Opens an existing dataset and checks its rank (2 when cols > 0), its width (unless
  // kAnyCols: the caller checks cols()) and its element class against `type`.
  static Column Open(Id group, const std::string& name, const Type& type, Size cols = 0);
  Column(Column&&) noexcept = default;
  Column& operator=(Column&&) noexcept = default;

  Size cols() const { return cols_; }
  Size rows() const { return rows_ + pending(); }
  Size pending() const { return pending_bytes() / (elem_size_ * std::max<Size>(cols_, 1)); }
  Size pending_bytes() const { return used_ - kept_bytes_; }

  template <class T>
  void Push(const T& v) {
    if (buf_.size() - used_ >= sizeof(T)) {  // the common case: a store of a constant size, inlined
      std::memcpy(buf_.data() + used_, &v, sizeof(T));
      used_ += sizeof(T);
    } else {
      Append(&v, sizeof(T));
    }
  }
  void PushRow(const Eigen::VectorXd& v) { Append(v.data(), sizeof(double) * static_cast<size_t>(v.size())); }
  void Flush() {
    Stage();
    WriteStaged();
  }
  // Sets the buffered rows aside for WriteStaged (the rows staged before must have been written);
  // whole_chunks: only those that fill whole chunks of the dataset, the others stay buffered.
  // A column made here (not opened) stages whole chunks from a chunk's first row: the rows of its
  // last chunk, when a flush leaves it part-filled, stay buffered after their write too ("kept"),
  // so that the next flush encodes that chunk whole again instead of HDF5 reading it back.
  void Stage(bool whole_chunks = false);
  // Encodes the staged rows, chunk by chunk (chunk_deflate.hpp; a last part-filled chunk padded
  // with zeros as HDF5 pads an edge chunk), into the column's buffers: no HDF5 call and no shared
  // state, so the store's writer thread does it while the simulation goes on; the HDF5 calls that
  // write them are WriteStaged's, in the store's own thread (docs/output.md, "Writing").
  // (Nothing when the staged rows are encoded already: BeginStaged.)
  void EncodeStaged();
  // Whether BeginStaged may stage this column's rows: one element per row, whole chunks encoded
  // here (a column made here, not opened), no row buffered in the column.
  bool encodes_rows_given() const { return direct_ && chunk_rows_ > 0 && cols_ == 0 && used_ == 0; }
  Size chunk_rows() const { return chunk_rows_; }
  // Appends n rows of elements as the memory type lays them out (n · max(cols, 1) elements).
  void PushElems(const void* p, Size n) { Append(p, static_cast<size_t>(n) * elem_size_ * std::max<Size>(cols_, 1)); }
  // Stages rows [first, first + n) of a table whose rows are buffered elsewhere (the store's
  // events, hdf5_store_impl.hpp), each of its chunks then encoded by StageChunk: first is a
  // chunk's first row; the rows staged before must have been written (WriteStaged writes these).
  // No HDF5 call: the store's writer thread does it while the simulation goes on
  // (encodes_rows_given() required).
  void BeginStaged(Size first, Size n);
  // Encodes chunk i of the rows BeginStaged staged from its `count` elements at `elems` (the
  // last chunk, part-filled, padded with zeros as EncodeStaged pads it).
  void StageChunk(size_t i, const unsigned char* elems, Size count);
  // Writes the staged rows (nothing when none are staged): the chunks as EncodeStaged left them
  // (encoded here when it was not called) with H5Dwrite_chunk, or, for an opened column or one
  // whose file element differs from memory's, through the library's filters.
  void WriteStaged();
  void Truncate(Size rows);
  // Reads rows [first, first + n) into out (n · max(cols, 1) elements of the memory type).
  void Read(Size first, Size n, void* out) const;
  // Reads every row once, in blocks: a damaged compressed chunk fails here (runtime_error naming
  // the dataset) instead of in a reader of the file later.
  void ReadAllRows() const;

 private:
  Handle dset_;
  Handle mem_type_;  // a copy of the memory type
  size_t elem_size_ = 8;
  std::string name_;
  Size cols_ = 0;
  Size rows_ = 0;          // rows written or staged
  Size staged_first_ = 0;  // the first staged row
  Size chunk_rows_ = 0;    // rows per chunk (0: unknown, a dataset opened)
  bool direct_ = false;    // whole chunks encoded here and written with H5Dwrite_chunk (WriteStaged)
  // What EncodeStaged made of the staged rows: chunk i's bytes at packed_ + i · bound, packed_len_[i]
  // of them (buffers kept from one flush to the next, never cleared).
  bool encoded_ = false;
  Bytes packed_;
  std::vector<size_t> packed_len_;
  // A chunk of one element repeated (a column that the run leaves constant: a single contact's
  // index, NaN where no compliant phase is recorded) is encoded once: its element and its encoding
  // are kept and copied for the next such chunk of the same element.
  Bytes constant_elem_, constant_packed_;
  size_t kept_bytes_ = 0;  // the first bytes of buf_: rows already written, of a part-filled chunk
  // buf_: its first used_ bytes are rows; staged_: its first staged_bytes_ are the staged rows.
  // Stage swaps the two (no copy of the staged rows, only of the rows after them).
  Bytes buf_, staged_;
  size_t used_ = 0, staged_bytes_ = 0;

  // Encodes one chunk whose first `bytes` are `rows` (chunk_bytes in all, zeros after them) at
  // `out` (ZlibFixedBound(chunk_bytes) bytes of room); returns its length.
  size_t EncodeChunk(const unsigned char* rows, size_t bytes, size_t chunk_bytes, unsigned char* out);
  void Append(const void* p, size_t bytes) {
    if (buf_.size() - used_ < bytes) buf_.resize(std::max<size_t>({2 * buf_.size(), used_ + bytes, 4096}));
    std::memcpy(buf_.data() + used_, p, bytes);
    used_ += bytes;
  }
};

// Reads every attribute and every dataset (up to `max_bytes` each) of the file at `path`, for a
// child process that tests whether the library survives the file. False when an object fails
// cleanly; a corrupt file may crash the caller instead (that is what the child is for).
// With `only`, just those objects (absolute paths): a dataset with its attributes, a group's
// attributes; a missing one is skipped (the caller's own read reports it).
bool ReadEverything(const std::string& path, double max_bytes, const std::vector<std::string>& only = {});

}  // namespace vibro::h5
