// The HDF5 C API behind h5_file.hpp. The one file of vibro that includes hdf5.h; it loads the HDF5
// library at first use (below), so that processes that open no HDF5 file never map it.
#include "io/h5_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <new>
#include <set>
#include <stdexcept>
#include <type_traits>

#include <fmt/format.h>

#include "io/chunk_deflate.hpp"
#include "vibro/hdf5_store.hpp"

// ---- The HDF5 C API, loaded at first use ----
// This file calls HDF5 through a table of entry points filled at first use by dlopen(3) of the
// HDF5 library found at configure time.
//
// Why: libhdf5 links libcurl (its read-only S3 driver), and libcurl GnuTLS, Kerberos and LDAP,
// about 30 shared libraries that cost a process about 4 ms of CPU to map and relocate
// (docs/performance.md, "Start-up"). Loaded at first use, they cost nothing to the commands and
// runs that open no HDF5 file (`vibro --version`, `vibro simulate SCENE` without --out).
//
// The declarations come from <hdf5.h> as usual (decltype of each function and variable); the
// macros after the loader send every name this file uses, including those behind HDF5's own macros
// (H5T_NATIVE_DOUBLE → H5T_NATIVE_DOUBLE_g, H5Dopen → H5Dopen2), to the table. A name missing
// here is a link error of libvibro (it links no HDF5), never a silent direct call.
#include <dlfcn.h>

#include <string>

#include <hdf5.h>

// Every function and variable of the HDF5 library that h5_file.cpp uses (`nm -u` of this object).
#define VIBRO_HDF5_FUNCTIONS(X) \
    X(H5Aclose) X(H5Acreate2) X(H5Adelete) X(H5Aexists) X(H5Aget_space) X(H5Aget_type) \
    X(H5Aiterate2) X(H5Aiterate_by_name) X(H5Aopen) X(H5Aread) X(H5Awrite) X(H5Dclose) \
    X(H5Dcreate2) X(H5Dget_space) X(H5Dget_type) X(H5Dopen2) X(H5Dread) X(H5Dset_extent) \
    X(H5Dvlen_reclaim) X(H5Dwrite) X(H5Dwrite_chunk) X(H5Eset_auto2) X(H5Ewalk2) X(H5Fclose) X(H5Fcreate) \
    X(H5Fflush) X(H5Fget_mdc_size) X(H5Fget_name) X(H5Fget_vfd_handle) X(H5Fis_hdf5) X(H5Fopen) \
    X(H5Gclose) X(H5Gcreate2) X(H5Gget_info) X(H5Gopen2) X(H5Idec_ref) X(H5Iget_file_id) \
    X(H5Iget_type) X(H5Ldelete) X(H5Lexists) X(H5Lget_name_by_idx) X(H5Literate) \
    X(H5Oget_info_by_name2) X(H5Ovisit2) X(H5Pclose) X(H5Pcreate) X(H5Pget_mdc_config) \
    X(H5Pset_chunk) X(H5Pset_chunk_cache) X(H5Pset_deflate) X(H5Pset_file_locking) \
    X(H5Pset_file_space_strategy) X(H5Pset_mdc_config) X(H5Pset_shuffle) X(H5Sclose) X(H5Scopy) \
    X(H5Screate) X(H5Screate_simple) X(H5Sget_simple_extent_dims) X(H5Sget_simple_extent_ndims) \
    X(H5Sget_simple_extent_npoints) X(H5Sselect_hyperslab) X(H5Tclose) X(H5Tcopy) \
    X(H5Tdetect_class) X(H5Tenum_create) X(H5Tequal) X(H5Tenum_insert) X(H5Tget_class) X(H5Tget_native_type) \
    X(H5Tget_size) X(H5Tis_variable_str) X(H5Tset_cset) X(H5Tset_size) X(H5check_version) \
    X(H5free_memory) X(H5open)

#define VIBRO_HDF5_VARIABLES(X) \
    X(H5E_CANTALLOC_g) X(H5E_NOSPACE_g) X(H5P_CLS_DATASET_ACCESS_ID_g) X(H5P_CLS_DATASET_CREATE_ID_g) X(H5P_CLS_FILE_ACCESS_ID_g) \
    X(H5P_CLS_FILE_CREATE_ID_g) X(H5T_C_S1_g) X(H5T_IEEE_F64LE_g) X(H5T_NATIVE_DOUBLE_g) \
    X(H5T_NATIVE_INT32_g) X(H5T_NATIVE_INT64_g) X(H5T_NATIVE_INT8_g) X(H5T_NATIVE_UINT8_g) \
    X(H5T_STD_I32LE_g) X(H5T_STD_I64LE_g) X(H5T_STD_I8LE_g) X(H5T_STD_U8LE_g)

namespace vibro::h5 {

struct Hdf5Api {
#define VIBRO_HDF5_ENTRY(name) decltype(&::name) name;
  VIBRO_HDF5_FUNCTIONS(VIBRO_HDF5_ENTRY)
  VIBRO_HDF5_VARIABLES(VIBRO_HDF5_ENTRY)
#undef VIBRO_HDF5_ENTRY
};

// The table, the library loaded on the first call (thread-safe). Throws std::runtime_error naming
// the library and dlerror(3)'s reason when it cannot be loaded or lacks an entry point.
// VIBRO_HDF5_LIBRARY is the soname of the library the headers belong to (CMakeLists.txt), so the
// table and the declarations it is checked against are of one HDF5 release.
inline Hdf5Api LoadHdf5() {
  // RTLD_GLOBAL, and each entry looked up in the global scope (RTLD_DEFAULT): the resolution a
  // linked libhdf5 would get, so that a preloaded library that wraps an HDF5 call (LD_PRELOAD, as
  // the tests' hang shim does) still comes first and finds the real one with RTLD_NEXT.
  // RTLD_NODELETE: HDF5's atexit handlers stay valid however the handle is treated.
  // The library and what it needs (curl, GnuTLS, ...: about 20 MB of address space) are mapped,
  // their constructors run and the library initialises itself with allocations it does not all
  // check: under an address-space limit that leaves less, GnuTLS's constructor failed and HDF5's
  // initialisation crashed (H5E__get_stack). Address space is asked for first (never touched),
  // and its refusal is an out-of-memory like any other (exit 3, MemoryError in Python).
  constexpr size_t kLoadHeadroom = size_t{48} << 20;
  if (void* probe = std::malloc(kLoadHeadroom)) {
    std::free(probe);
  } else {
    throw std::bad_alloc();
  }
  void* lib = dlopen(VIBRO_HDF5_LIBRARY, RTLD_NOW | RTLD_GLOBAL | RTLD_NODELETE);
  if (lib == nullptr) {
    const std::string why = dlerror();
    // Under an address-space limit (ulimit -v) the loader cannot map the library: out of memory
    // (exit 3, MemoryError in Python), not a broken installation.
    if (why.find("failed to map segment") != std::string::npos ||
        why.find("cannot allocate memory") != std::string::npos)
      throw std::bad_alloc();
    throw std::runtime_error("cannot load the HDF5 library " VIBRO_HDF5_LIBRARY ": " + why);
  }
  Hdf5Api api{};
  auto entry = [&](const char* name) {
    void* p = dlsym(RTLD_DEFAULT, name);
    if (p == nullptr)
      throw std::runtime_error(std::string("the HDF5 library " VIBRO_HDF5_LIBRARY " lacks ") + name);
    return p;
  };
#define VIBRO_HDF5_ENTRY(name) api.name = reinterpret_cast<decltype(api.name)>(entry(#name));
  VIBRO_HDF5_FUNCTIONS(VIBRO_HDF5_ENTRY)
  VIBRO_HDF5_VARIABLES(VIBRO_HDF5_ENTRY)
#undef VIBRO_HDF5_ENTRY
  // Initialised now, within the headroom just asked for (its first call would do it anyway).
  if (api.H5open() < 0) throw std::runtime_error("the HDF5 library " VIBRO_HDF5_LIBRARY " could not initialise");
  return api;
}

inline const Hdf5Api& Hdf5() {
  static const Hdf5Api api = LoadHdf5();
  return api;
}

}  // namespace vibro::h5

// From here on, each name is the table's entry.
#define H5Aclose (::vibro::h5::Hdf5().H5Aclose)
#define H5Acreate2 (::vibro::h5::Hdf5().H5Acreate2)
#define H5Adelete (::vibro::h5::Hdf5().H5Adelete)
#define H5Aexists (::vibro::h5::Hdf5().H5Aexists)
#define H5Aget_space (::vibro::h5::Hdf5().H5Aget_space)
#define H5Aget_type (::vibro::h5::Hdf5().H5Aget_type)
#define H5Aiterate2 (::vibro::h5::Hdf5().H5Aiterate2)
#define H5Aiterate_by_name (::vibro::h5::Hdf5().H5Aiterate_by_name)
#define H5Aopen (::vibro::h5::Hdf5().H5Aopen)
#define H5Aread (::vibro::h5::Hdf5().H5Aread)
#define H5Awrite (::vibro::h5::Hdf5().H5Awrite)
#define H5Dclose (::vibro::h5::Hdf5().H5Dclose)
#define H5Dcreate2 (::vibro::h5::Hdf5().H5Dcreate2)
#define H5Dget_space (::vibro::h5::Hdf5().H5Dget_space)
#define H5Dget_type (::vibro::h5::Hdf5().H5Dget_type)
#define H5Dopen2 (::vibro::h5::Hdf5().H5Dopen2)
#define H5Dread (::vibro::h5::Hdf5().H5Dread)
#define H5Dset_extent (::vibro::h5::Hdf5().H5Dset_extent)
#define H5Dvlen_reclaim (::vibro::h5::Hdf5().H5Dvlen_reclaim)
#define H5Dwrite (::vibro::h5::Hdf5().H5Dwrite)
#define H5Dwrite_chunk (::vibro::h5::Hdf5().H5Dwrite_chunk)
#define H5Eset_auto2 (::vibro::h5::Hdf5().H5Eset_auto2)
#define H5Ewalk2 (::vibro::h5::Hdf5().H5Ewalk2)
#define H5Fclose (::vibro::h5::Hdf5().H5Fclose)
#define H5Fcreate (::vibro::h5::Hdf5().H5Fcreate)
#define H5Fflush (::vibro::h5::Hdf5().H5Fflush)
#define H5Fget_mdc_size (::vibro::h5::Hdf5().H5Fget_mdc_size)
#define H5Fget_name (::vibro::h5::Hdf5().H5Fget_name)
#define H5Fget_vfd_handle (::vibro::h5::Hdf5().H5Fget_vfd_handle)
#define H5Fis_hdf5 (::vibro::h5::Hdf5().H5Fis_hdf5)
#define H5Fopen (::vibro::h5::Hdf5().H5Fopen)
#define H5Gclose (::vibro::h5::Hdf5().H5Gclose)
#define H5Gcreate2 (::vibro::h5::Hdf5().H5Gcreate2)
#define H5Gget_info (::vibro::h5::Hdf5().H5Gget_info)
#define H5Gopen2 (::vibro::h5::Hdf5().H5Gopen2)
#define H5Idec_ref (::vibro::h5::Hdf5().H5Idec_ref)
#define H5Iget_file_id (::vibro::h5::Hdf5().H5Iget_file_id)
#define H5Iget_type (::vibro::h5::Hdf5().H5Iget_type)
#define H5Ldelete (::vibro::h5::Hdf5().H5Ldelete)
#define H5Lexists (::vibro::h5::Hdf5().H5Lexists)
#define H5Lget_name_by_idx (::vibro::h5::Hdf5().H5Lget_name_by_idx)
#define H5Literate (::vibro::h5::Hdf5().H5Literate)
#define H5Oget_info_by_name2 (::vibro::h5::Hdf5().H5Oget_info_by_name2)
#define H5Ovisit2 (::vibro::h5::Hdf5().H5Ovisit2)
#define H5Pclose (::vibro::h5::Hdf5().H5Pclose)
#define H5Pcreate (::vibro::h5::Hdf5().H5Pcreate)
#define H5Pget_mdc_config (::vibro::h5::Hdf5().H5Pget_mdc_config)
#define H5Pset_chunk (::vibro::h5::Hdf5().H5Pset_chunk)
#define H5Pset_chunk_cache (::vibro::h5::Hdf5().H5Pset_chunk_cache)
#define H5Pset_deflate (::vibro::h5::Hdf5().H5Pset_deflate)
#define H5Pset_file_locking (::vibro::h5::Hdf5().H5Pset_file_locking)
#define H5Pset_file_space_strategy (::vibro::h5::Hdf5().H5Pset_file_space_strategy)
#define H5Pset_mdc_config (::vibro::h5::Hdf5().H5Pset_mdc_config)
#define H5Pset_shuffle (::vibro::h5::Hdf5().H5Pset_shuffle)
#define H5Sclose (::vibro::h5::Hdf5().H5Sclose)
#define H5Scopy (::vibro::h5::Hdf5().H5Scopy)
#define H5Screate (::vibro::h5::Hdf5().H5Screate)
#define H5Screate_simple (::vibro::h5::Hdf5().H5Screate_simple)
#define H5Sget_simple_extent_dims (::vibro::h5::Hdf5().H5Sget_simple_extent_dims)
#define H5Sget_simple_extent_ndims (::vibro::h5::Hdf5().H5Sget_simple_extent_ndims)
#define H5Sget_simple_extent_npoints (::vibro::h5::Hdf5().H5Sget_simple_extent_npoints)
#define H5Sselect_hyperslab (::vibro::h5::Hdf5().H5Sselect_hyperslab)
#define H5Tclose (::vibro::h5::Hdf5().H5Tclose)
#define H5Tcopy (::vibro::h5::Hdf5().H5Tcopy)
#define H5Tdetect_class (::vibro::h5::Hdf5().H5Tdetect_class)
#define H5Tenum_create (::vibro::h5::Hdf5().H5Tenum_create)
#define H5Tenum_insert (::vibro::h5::Hdf5().H5Tenum_insert)
#define H5Tequal (::vibro::h5::Hdf5().H5Tequal)
#define H5Tget_class (::vibro::h5::Hdf5().H5Tget_class)
#define H5Tget_native_type (::vibro::h5::Hdf5().H5Tget_native_type)
#define H5Tget_size (::vibro::h5::Hdf5().H5Tget_size)
#define H5Tis_variable_str (::vibro::h5::Hdf5().H5Tis_variable_str)
#define H5Tset_cset (::vibro::h5::Hdf5().H5Tset_cset)
#define H5Tset_size (::vibro::h5::Hdf5().H5Tset_size)
#define H5check_version (::vibro::h5::Hdf5().H5check_version)
#define H5free_memory (::vibro::h5::Hdf5().H5free_memory)
#define H5open (::vibro::h5::Hdf5().H5open)
#define H5P_CLS_DATASET_ACCESS_ID_g (*::vibro::h5::Hdf5().H5P_CLS_DATASET_ACCESS_ID_g)
#define H5P_CLS_DATASET_CREATE_ID_g (*::vibro::h5::Hdf5().H5P_CLS_DATASET_CREATE_ID_g)
#define H5P_CLS_FILE_ACCESS_ID_g (*::vibro::h5::Hdf5().H5P_CLS_FILE_ACCESS_ID_g)
#define H5P_CLS_FILE_CREATE_ID_g (*::vibro::h5::Hdf5().H5P_CLS_FILE_CREATE_ID_g)
#define H5T_C_S1_g (*::vibro::h5::Hdf5().H5T_C_S1_g)
#define H5T_IEEE_F64LE_g (*::vibro::h5::Hdf5().H5T_IEEE_F64LE_g)
#define H5T_NATIVE_DOUBLE_g (*::vibro::h5::Hdf5().H5T_NATIVE_DOUBLE_g)
#define H5E_NOSPACE_g (*::vibro::h5::Hdf5().H5E_NOSPACE_g)
#define H5E_CANTALLOC_g (*::vibro::h5::Hdf5().H5E_CANTALLOC_g)
#define H5T_NATIVE_INT32_g (*::vibro::h5::Hdf5().H5T_NATIVE_INT32_g)
#define H5T_NATIVE_INT64_g (*::vibro::h5::Hdf5().H5T_NATIVE_INT64_g)
#define H5T_NATIVE_INT8_g (*::vibro::h5::Hdf5().H5T_NATIVE_INT8_g)
#define H5T_NATIVE_UINT8_g (*::vibro::h5::Hdf5().H5T_NATIVE_UINT8_g)
#define H5T_STD_I32LE_g (*::vibro::h5::Hdf5().H5T_STD_I32LE_g)
#define H5T_STD_I64LE_g (*::vibro::h5::Hdf5().H5T_STD_I64LE_g)
#define H5T_STD_I8LE_g (*::vibro::h5::Hdf5().H5T_STD_I8LE_g)
#define H5T_STD_U8LE_g (*::vibro::h5::Hdf5().H5T_STD_U8LE_g)

namespace vibro::h5 {

static_assert(std::is_same_v<hid_t, Id>, "h5::Id must be hid_t (HDF5 ≥ 1.10)");
static_assert(std::is_same_v<hsize_t, Size> || sizeof(hsize_t) == sizeof(Size), "h5::Size must be hsize_t");
static_assert(std::is_same_v<herr_t, int>, "h5::Handle::Closer must match herr_t (*)(hid_t)");

namespace {

// Rows per chunk of a table: 128 KiB of float64 (deflate compresses a periodic run's columns to
// about half the size of 4096-row chunks at the same cost per byte).
constexpr hsize_t kChunkRows = 16384;
// Deflate level 1: files about 10 % larger than at level 4, and a long run with the store keeps
// 0.70 of its throughput instead of 0.59 (instructions of a 2000-period Fig. 8 run, docs/performance.md).
constexpr int kDeflate = 1;

hid_t Check(hid_t id, const std::string& what) {
  if (id < 0) throw std::runtime_error(fmt::format("HDF5: {} failed", what));
  return id;
}
void CheckStatus(herr_t status, const std::string& what) {
  if (status < 0) throw std::runtime_error(fmt::format("HDF5: {} failed", what));
}

// Files a write failed on (the ids of their open files, never closed and so never reused): never
// written or closed again (Close).
std::mutex g_failed_mutex;
std::set<hid_t> g_failed_files;
std::atomic<bool> g_any_failed{false};
std::atomic<bool> g_abandoned{false};  // Abandon: every handle left open, no close at all

// The id of the open file `obj` belongs to (one per H5Fcreate/H5Fopen, shared by all its
// objects); false for objects of no file (types, property lists).
bool FileNumber(hid_t obj, hid_t& number) {
  if (H5Iget_type(obj) == H5I_FILE) {
    number = obj;
    return true;
  }
  const hid_t file = H5Iget_file_id(obj);  // the file's id, one more reference to it
  if (file < 0) return false;
  number = file;
  H5Idec_ref(file);  // back to the count before (the file stays open)
  return true;
}

// The system's reason for the failure just reported, from HDF5's error stack (its file driver
// pushes "... errno = 28, error message = 'No space left on device' ..."): strerror's text with a
// lower-case first letter, or "" when the stack names no errno.
std::string SystemReason() {
  int err = 0;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_DOWNWARD,
      [](unsigned, const H5E_error2_t* e, void* out) -> herr_t {
        const char* p = e->desc ? std::strstr(e->desc, "errno = ") : nullptr;
        if (p == nullptr) return 0;
        *static_cast<int*>(out) = std::atoi(p + 8);
        return 1;  // the deepest one is enough
      },
      &err);
  if (err <= 0) return "";
  std::string text = std::strerror(err);
  if (!text.empty() && text[0] >= 'A' && text[0] <= 'Z') text[0] = static_cast<char>(text[0] - 'A' + 'a');
  return text;
}

void MarkFileFailed(hid_t obj) {
  hid_t number = -1;
  if (!FileNumber(obj, number)) return;
  {
    const std::lock_guard<std::mutex> hold(g_failed_mutex);
    if (!g_failed_files.insert(number).second) return;
    g_any_failed.store(true);
  }
  // The file's descriptor now reads /dev/null: whatever the library still does with this file
  // (a close at exit) cannot reach its bytes.
  void* handle = nullptr;
  if (H5Fget_vfd_handle(number, H5P_DEFAULT, &handle) >= 0 && handle != nullptr) {
    const int null_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
    if (null_fd >= 0) {
      dup2(null_fd, *static_cast<int*>(handle));
      close(null_fd);
    }
  }
}

// Whether HDF5's error stack says an allocation failed (its "no space available for allocation"
// or "can't allocate space", which HDF5 also uses for memory; a full disk names errno 28 instead).
bool AllocationFailed() {
  bool failed = false;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_DOWNWARD,
      [](unsigned, const H5E_error2_t* e, void* out) -> herr_t {
        if (e->min_num == H5E_NOSPACE_g || e->min_num == H5E_CANTALLOC_g) *static_cast<bool*>(out) = true;
        return 0;
      },
      &failed);
  return failed;
}

// A failed write or flush to the file of `obj`: the file is marked failed, WriteError says why;
// a write that failed for want of memory is the out-of-memory it is (std::bad_alloc: exit 3,
// MemoryError in Python; it read as "HDF5 could not write kind" under `ulimit -v`).
void CheckWrite(herr_t status, hid_t obj, const std::string& what) {
  if (status >= 0) return;
  if (errno == ENOMEM || (SystemReason().empty() && AllocationFailed())) {
    MarkFileFailed(obj);
    throw std::bad_alloc();
  }
  // errno is the system's reason only for the errors a write can meet (it may be left over from
  // an earlier call that did not fail the write: a stale ENOENT made a damaged file a "system"
  // failure, exit 3, where it is bad input).
  const int err = errno;
  const bool write_errno = err == ENOSPC || err == EDQUOT || err == EIO || err == EFBIG || err == EROFS;
  std::string reason = SystemReason();
  const bool from_system = !reason.empty() || write_errno;
  if (reason.empty()) reason = write_errno ? std::strerror(err) : fmt::format("HDF5 could not write {}", what);
  char name[4096] = "the output file";
  if (H5Fget_name(obj, name, sizeof name) < 0) std::strcpy(name, "the output file");
  MarkFileFailed(obj);
  throw WriteError(fmt::format("{} writing {}", reason, name), from_system);
}

// No chunk cache: a Column's rows reach the file when written (see Column in h5_file.hpp).
Handle NoChunkCache() {
  Handle dapl(H5Pcreate(H5P_DATASET_ACCESS), H5Pclose);
  H5Pset_chunk_cache(dapl.get(), 0, 0, H5D_CHUNK_CACHE_W0_DEFAULT);
  return dapl;
}

Handle StringMemType() {
  Handle t(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(t.get(), H5T_VARIABLE);
  H5Tset_cset(t.get(), H5T_CSET_UTF8);
  return t;
}

Handle FileAccess() {
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  // No metadata reaches the disk between flushes (see vibro/hdf5_store.hpp).
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
  CheckStatus(H5Pset_mdc_config(fapl.get(), &cfg), "metadata cache configuration");
  // No file lock: h5py users may watch a long run as it goes (the file is consistent as of the
  // last flush; a read that meets a flush in progress may fail and should be retried).
  H5Pset_file_locking(fapl.get(), 0, 1);
  return fapl;
}

}  // namespace

// ---- Types ----

Type::Type(Handle owned, size_t size) : owned_(std::move(owned)), size_(size) {
  file_ = memory_ = owned_.get();
}
Type Type::F64() { return {H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8}; }
Type Type::I64() { return {H5T_STD_I64LE, H5T_NATIVE_INT64, 8}; }
Type Type::I32() { return {H5T_STD_I32LE, H5T_NATIVE_INT32, 4}; }
Type Type::I8() { return {H5T_STD_I8LE, H5T_NATIVE_INT8, 1}; }
Type Type::U8() { return {H5T_STD_U8LE, H5T_NATIVE_UINT8, 1}; }
Type Type::String() { return {StringMemType(), sizeof(char*)}; }
Type Type::Bool() { return Enum8({{"FALSE", 0}, {"TRUE", 1}}); }
Type Type::Enum8(const std::vector<std::pair<std::string, std::int8_t>>& members) {
  Handle t(H5Tenum_create(H5T_NATIVE_INT8), H5Tclose);
  for (const auto& [name, value] : members) H5Tenum_insert(t.get(), name.c_str(), &value);
  return {std::move(t), 1};
}

void Close(Id id, Closer closer) {
  if (g_abandoned.load()) return;  // no HDF5 call at all any more (Abandon)
  if (g_any_failed.load()) {
    hid_t number = -1;
    if (FileNumber(id, number)) {
      const std::lock_guard<std::mutex> hold(g_failed_mutex);
      if (g_failed_files.count(number)) return;  // left open: a close would write to it
    }
  }
  closer(id);
}

// HDF5's clean-up at exit (H5_term_library, an atexit handler) closes every file still open,
// the failed ones too, which vibro leaves open on purpose: it crashed doing so (SIGSEGV in
// H5F__close_cb after a chunk allocation had failed under `ulimit -v`). This handler, registered
// after HDF5's (so run before it), ends the process with its status before that clean-up when a
// file has failed; every other file was closed by its owner and stdio is flushed.
// HDF5 1.10 also ends the process itself, with exit(-1) and no message, when some of its
// allocations fail (H5I_register under an exhausted `ulimit -v`, seen in H5Dget_space and
// H5Screate on the writer thread); its clean-up then crashed on the call under way. An exit(-1)
// during a store's writes (WritingScope) is reported as the out-of-memory it is (exit 3, the file
// keeping its last flush, written with no reuse of freed space: docs/output.md); outside them the
// status is the program's own (a Python sys.exit(-1) stays 255).
std::atomic<int> g_writing{0};  // stretches of store writes under way (WritingScope)

void SkipCleanUpAfterFailure(int status, void*) {
  if (status == -1 && g_writing.load() > 0) {
    static const char kLine[] =
        "vibro: out of memory (the HDF5 library could not allocate and ended the process); the output file keeps "
        "what was written up to its last flush\n";
    std::fflush(nullptr);
    const ssize_t written = write(2, kLine, sizeof kLine - 1);
    (void)written;
    _exit(3);
  }
  if (!g_any_failed.load()) return;
  std::fflush(nullptr);
  _exit(status);
}

WritingScope::WritingScope() { g_writing.fetch_add(1); }
WritingScope::~WritingScope() { g_writing.fetch_sub(1); }

void Silence() {
  // Each thread has its own error stack and its own printing of it (a thread-safe HDF5).
  thread_local const bool once = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)once;
  static const bool hooked = [] {
    H5open();  // HDF5's atexit handler is registered by its initialisation: this one comes after
    on_exit(SkipCleanUpAfterFailure, nullptr);
    return true;
  }();
  (void)hooked;
}

// ---- Files ----

namespace {

// HDF5 1.10 does not check every allocation of a file's metadata cache (H5AC_create): under an
// address-space limit (ulimit -v) that leaves it less than that, H5Fcreate and H5Fopen crash the
// process (SIGSEGV). Address space for the cache and the first chunks is asked for first, and
// its refusal is an out-of-memory like any other (std::bad_alloc: exit 3, MemoryError in Python).
void EnsureHeadroom() {
  constexpr size_t kHeadroom = size_t{16} << 20;  // reserved, never touched: address space only
  void* probe = std::malloc(kHeadroom);
  if (probe == nullptr) throw std::bad_alloc();
  std::free(probe);
}

}  // namespace

bool IsHdf5(const std::string& path) { return H5Fis_hdf5(path.c_str()) > 0; }

Handle CreateFile(const std::string& path) {
  Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
  // Freed space is never reused: a flushed file never points at overwritten bytes.
  CheckStatus(H5Pset_file_space_strategy(fcpl.get(), H5F_FSPACE_STRATEGY_NONE, 0, 1), "file space");
  Handle fapl = FileAccess();
  EnsureHeadroom();
  errno = 0;
  Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get()), H5Fclose);
  if (!file) throw std::runtime_error(errno != 0 ? std::strerror(errno) : "HDF5 could not create it");
  return file;
}

Handle OpenFile(const std::string& path, bool write) {
  EnsureHeadroom();
  if (!write) return Handle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  Handle fapl = FileAccess();
  return Handle(H5Fopen(path.c_str(), H5F_ACC_RDWR, fapl.get()), H5Fclose);
}

void FlushFile(Id file) { CheckWrite(H5Fflush(file, H5F_SCOPE_LOCAL), file, "flush"); }

Size MetadataBytes(Id file) {
  size_t max_size = 0, min_clean = 0, cur_size = 0;
  int entries = 0;
  if (H5Fget_mdc_size(file, &max_size, &min_clean, &cur_size, &entries) < 0) return 16u << 20;
  return cur_size;
}

void MarkFailed(Id file) { MarkFileFailed(file); }

void Abandon() {
  g_abandoned.store(true);
  g_any_failed.store(true);  // the clean-up at exit skipped too (SkipCleanUpAfterFailure)
}

// ---- Links and groups ----

bool Exists(Id loc, const std::string& path) { return H5Lexists(loc, path.c_str(), H5P_DEFAULT) > 0; }

void DeleteLink(Id loc, const std::string& name) {
  if (Exists(loc, name)) H5Ldelete(loc, name.c_str(), H5P_DEFAULT);
}

Handle CreateGroup(Id loc, const std::string& name) {
  return Handle(Check(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name), H5Gclose);
}

Handle OpenGroup(Id loc, const std::string& name) {
  return Handle(Check(H5Gopen2(loc, name.c_str(), H5P_DEFAULT), name), H5Gclose);
}

Handle TryOpenGroup(Id loc, const std::string& name) {
  return Handle(H5Gopen2(loc, name.c_str(), H5P_DEFAULT), H5Gclose);
}

Handle OpenOrCreateGroup(Id loc, const std::string& name) {
  return Exists(loc, name) ? OpenGroup(loc, name) : CreateGroup(loc, name);
}

std::vector<std::string> ChildGroups(Id loc) {
  std::vector<std::string> names;
  H5Literate(loc, H5_INDEX_NAME, H5_ITER_INC, nullptr,
             [](hid_t l, const char* name, const H5L_info_t*, void* out) -> herr_t {
               Handle g(H5Gopen2(l, name, H5P_DEFAULT), H5Gclose);  // fails (silently) for a dataset
               if (g) static_cast<std::vector<std::string>*>(out)->push_back(name);
               return 0;
             },
             &names);
  return names;
}

// ---- Attributes ----

bool HasAttr(Id obj, const std::string& name) { return H5Aexists(obj, name.c_str()) > 0; }

void DeleteAttr(Id obj, const std::string& name) {
  if (HasAttr(obj, name)) H5Adelete(obj, name.c_str());
}

std::vector<std::string> AttrNames(Id obj) {
  std::vector<std::string> names;
  H5Aiterate2(obj, H5_INDEX_NAME, H5_ITER_INC, nullptr,
              [](hid_t, const char* attr, const H5A_info_t*, void* data) -> herr_t {
                static_cast<std::vector<std::string>*>(data)->emplace_back(attr);
                return 0;
              },
              &names);
  return names;
}

Class AttrClass(Id obj, const std::string& name) {
  Handle a(H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose);
  if (!a) return Class::kOther;
  Handle type(H5Aget_type(a.get()), H5Tclose);
  switch (H5Tget_class(type.get())) {
    case H5T_STRING: return Class::kString;
    case H5T_INTEGER: return Class::kInteger;
    case H5T_FLOAT: return Class::kFloat;
    default: return Class::kOther;
  }
}

namespace {

// A new attribute `name` of `file_type` and the given shape (empty dims: scalar), replacing one.
Handle NewAttr(Id obj, const std::string& name, hid_t file_type, const std::vector<hsize_t>& dims) {
  DeleteAttr(obj, name);
  Handle space(dims.empty() ? H5Screate(H5S_SCALAR)
                            : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
               H5Sclose);
  return Handle(Check(H5Acreate2(obj, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), name),
                H5Aclose);
}

template <class T>
void WriteScalar(Id obj, const std::string& name, T value, const Type& type) {
  Handle a = NewAttr(obj, name, type.file(), {});
  CheckWrite(H5Awrite(a.get(), type.memory(), &value), obj, name);
}

// An attribute of one element (scalar or of shape (1)): an array read into one value would
// overrun it.
void RequireOneElement(hid_t a, const std::string& name) {
  Handle space(Check(H5Aget_space(a), name), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n != 1) throw std::runtime_error(fmt::format("attribute {}: expected one value, found {}", name, n));
}

template <class T>
std::optional<T> ReadScalar(Id obj, const std::string& name, hid_t mem_type) {
  if (!HasAttr(obj, name)) return std::nullopt;
  Handle a(Check(H5Aopen(obj, name.c_str(), H5P_DEFAULT), name), H5Aclose);
  RequireOneElement(a.get(), name);
  T v{};
  CheckStatus(H5Aread(a.get(), mem_type, &v), name);
  return v;
}

}  // namespace

void WriteString(Id obj, const std::string& name, const std::string& value) {
  const Type type = Type::String();
  Handle a = NewAttr(obj, name, type.file(), {});
  const char* p = value.c_str();
  CheckWrite(H5Awrite(a.get(), type.memory(), &p), obj, name);
}

void WriteDouble(Id obj, const std::string& name, double value) { WriteScalar(obj, name, value, Type::F64()); }

void WriteInt(Id obj, const std::string& name, long long value) {
  WriteScalar(obj, name, static_cast<std::int64_t>(value), Type::I64());
}

void WriteBool(Id obj, const std::string& name, bool value) {
  WriteScalar(obj, name, static_cast<std::int8_t>(value ? 1 : 0), Type::Bool());
}

void WriteDoubles(Id obj, const std::string& name, const std::vector<double>& v, Size cols) {
  const std::vector<hsize_t> dims =
      cols > 1 ? std::vector<hsize_t>{v.size() / cols, cols} : std::vector<hsize_t>{v.size()};
  Handle a = NewAttr(obj, name, H5T_IEEE_F64LE, dims);
  if (!v.empty()) CheckWrite(H5Awrite(a.get(), H5T_NATIVE_DOUBLE, v.data()), obj, name);
}

void WriteInts(Id obj, const std::string& name, const std::vector<int>& v) {
  Handle a = NewAttr(obj, name, H5T_STD_I32LE, {v.size()});
  static_assert(sizeof(int) == 4);
  if (!v.empty()) CheckWrite(H5Awrite(a.get(), H5T_NATIVE_INT32, v.data()), obj, name);
}

void WriteStringArray(Id obj, const std::string& name, const std::vector<std::string>& v) {
  std::vector<const char*> p;
  for (const auto& x : v) p.push_back(x.c_str());
  const Type type = Type::String();
  Handle a = NewAttr(obj, name, type.file(), {v.size()});
  if (!v.empty()) CheckWrite(H5Awrite(a.get(), type.memory(), p.data()), obj, name);
}

std::string ReadString(Id obj, const std::string& name) {
  if (!HasAttr(obj, name)) return {};
  Handle a(Check(H5Aopen(obj, name.c_str(), H5P_DEFAULT), name), H5Aclose);
  RequireOneElement(a.get(), name);
  Handle stored(Check(H5Aget_type(a.get()), name), H5Tclose);
  if (H5Tget_class(stored.get()) != H5T_STRING)
    throw std::runtime_error(fmt::format("attribute {}: expected a string", name));
  Handle type = StringMemType();
  char* p = nullptr;
  CheckStatus(H5Aread(a.get(), type.get(), &p), name);
  std::string s = p ? p : "";
  H5free_memory(p);
  return s;
}

std::optional<std::int64_t> ReadInt(Id obj, const std::string& name) {
  return ReadScalar<std::int64_t>(obj, name, H5T_NATIVE_INT64);
}

std::optional<double> ReadDouble(Id obj, const std::string& name) {
  return ReadScalar<double>(obj, name, H5T_NATIVE_DOUBLE);
}

std::vector<double> ReadDoubles(Id obj, const std::string& name) {
  if (!HasAttr(obj, name)) return {};
  Handle a(Check(H5Aopen(obj, name.c_str(), H5P_DEFAULT), name), H5Aclose);
  Handle space(H5Aget_space(a.get()), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n < 0 || n > (hssize_t{1} << 24))  // an attribute is small (the object header holds it)
    throw std::runtime_error(fmt::format("attribute {}: {} values", name, n));
  std::vector<double> v(static_cast<size_t>(n));
  if (!v.empty()) CheckStatus(H5Aread(a.get(), H5T_NATIVE_DOUBLE, v.data()), name);
  return v;
}

std::string AttrText(Id obj, const std::string& name) {
  Handle a(H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose);
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

// ---- Small datasets ----

void WriteDataset(Id loc, const std::string& name, const Type& type, const void* data,
                  const std::vector<Size>& dims, const std::vector<Size>& chunk) {
  const std::vector<hsize_t> d(dims.begin(), dims.end());
  Handle space(H5Screate_simple(static_cast<int>(d.size()), d.data(), nullptr), H5Sclose);
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  if (!chunk.empty()) {
    const std::vector<hsize_t> c(chunk.begin(), chunk.end());
    H5Pset_chunk(dcpl.get(), static_cast<int>(c.size()), c.data());
    H5Pset_deflate(dcpl.get(), kDeflate);
  }
  Handle ds(Check(H5Dcreate2(loc, name.c_str(), type.file(), space.get(), H5P_DEFAULT,
                             chunk.empty() ? H5P_DEFAULT : dcpl.get(), H5P_DEFAULT),
                  name),
            H5Dclose);
  if (!d.empty() && d[0] > 0)
    CheckWrite(H5Dwrite(ds.get(), type.memory(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data), loc, name);
}

void WriteStrings(Id loc, const std::string& name, const std::vector<std::string>& v) {
  std::vector<const char*> p;
  for (const auto& x : v) p.push_back(x.c_str());
  WriteDataset(loc, name, Type::String(), p.data(), {p.size()});
}

void WriteColumn(Id loc, const std::string& name, const std::vector<double>& v) {
  WriteDataset(loc, name, Type::F64(), v.data(), {v.size()});
}

std::vector<std::string> DatasetNames(Id loc) {
  std::vector<std::string> names;
  H5G_info_t info;
  CheckStatus(H5Gget_info(loc, &info), "group info");
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    char name[256];
    H5Lget_name_by_idx(loc, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
    Handle d(H5Dopen2(loc, name, H5P_DEFAULT), H5Dclose);
    if (d) names.emplace_back(name);
  }
  return names;
}

std::optional<std::vector<Size>> DatasetShape(Id loc, const std::string& name) {
  if (!Exists(loc, name)) return std::nullopt;
  Handle ds(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!ds) return std::nullopt;
  Handle space(H5Dget_space(ds.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(static_cast<size_t>(std::max(rank, 0)));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return std::vector<Size>(dims.begin(), dims.end());
}

bool IsStringDataset(Id loc, const std::string& name) {
  // A missing or unreadable dataset is not one of strings: the caller names what it expected
  // (a damaged input file is bad input, never an internal error).
  return DatasetClass(loc, name) == Class::kString;
}

Class DatasetClass(Id loc, const std::string& name) {
  if (!Exists(loc, name)) return Class::kOther;
  Handle d(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d) return Class::kOther;
  Handle type(H5Dget_type(d.get()), H5Tclose);
  switch (H5Tget_class(type.get())) {
    case H5T_STRING: return Class::kString;
    case H5T_INTEGER: return Class::kInteger;
    case H5T_FLOAT: return Class::kFloat;
    default: return Class::kOther;
  }
}

std::vector<double> ReadDatasetRow(Id loc, const std::string& name, Size row) {
  Handle d(Check(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), name), H5Dclose);
  Handle space(Check(H5Dget_space(d.get()), name), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank != 1 && rank != 2) throw std::runtime_error(fmt::format("dataset {} has rank {}", name, rank));
  hsize_t dims[2] = {0, 1};
  H5Sget_simple_extent_dims(space.get(), dims, nullptr);
  if (row >= dims[0] || dims[1] == 0 || dims[1] > (1u << 16))
    throw std::runtime_error(fmt::format("dataset {}: no row {}", name, row));
  const hsize_t start[2] = {row, 0}, count[2] = {1, dims[1]};
  CheckStatus(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), name);
  Handle mem(H5Screate_simple(rank, count, nullptr), H5Sclose);
  std::vector<double> v(static_cast<size_t>(rank == 2 ? dims[1] : 1));
  CheckStatus(H5Dread(d.get(), H5T_NATIVE_DOUBLE, mem.get(), space.get(), H5P_DEFAULT, v.data()), name);
  return v;
}

std::vector<double> ReadDatasetDoubles(Id loc, const std::string& name) {
  Handle d(Check(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), name), H5Dclose);
  Handle space(H5Dget_space(d.get()), H5Sclose);
  std::vector<double> v(static_cast<size_t>(H5Sget_simple_extent_npoints(space.get())));
  if (!v.empty()) CheckStatus(H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), name);
  return v;
}

std::vector<std::string> ReadDatasetStrings(Id loc, const std::string& name) {
  Handle d(Check(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), name), H5Dclose);
  Handle space(H5Dget_space(d.get()), H5Sclose);
  const auto n = static_cast<size_t>(H5Sget_simple_extent_npoints(space.get()));
  Handle st = StringMemType();
  std::vector<char*> p(n, nullptr);
  if (n > 0) CheckStatus(H5Dread(d.get(), st.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()), name);
  std::vector<std::string> v;
  for (char* x : p) {
    v.emplace_back(x ? x : "");
    H5free_memory(x);
  }
  return v;
}

// ---- Extendible tables ----

Column::Column(Id group, const std::string& name, const Type& type, Size cols)
    : mem_type_(H5Tcopy(type.memory()), H5Tclose), elem_size_(type.size()), name_(name), cols_(cols) {
  const int rank = cols > 0 ? 2 : 1;
  const hsize_t dims[2] = {0, cols}, maxdims[2] = {H5S_UNLIMITED, cols};
  const hsize_t chunk[2] = {cols > 0 ? std::max<hsize_t>(64, kChunkRows / cols) : kChunkRows, cols};
  Handle space(H5Screate_simple(rank, dims, maxdims), H5Sclose);
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  H5Pset_chunk(dcpl.get(), rank, chunk);
  chunk_rows_ = chunk[0];
  H5Pset_shuffle(dcpl.get());
  H5Pset_deflate(dcpl.get(), kDeflate);
  dset_ = Handle(Check(H5Dcreate2(group, name.c_str(), type.file(), space.get(), H5P_DEFAULT, dcpl.get(),
                                  NoChunkCache().get()),
                       name),
                 H5Dclose);
  // Whole chunks are encoded by the store itself (chunk_deflate.hpp) and written as they are, when
  // the file's element is the memory's, byte for byte.
  direct_ = H5Tequal(type.file(), type.memory()) > 0 && H5Tget_size(type.file()) == elem_size_;
}

Column Column::Open(Id group, const std::string& name, const Type& type, Size cols) {
  Column c;
  c.mem_type_ = Handle(H5Tcopy(type.memory()), H5Tclose);
  c.elem_size_ = type.size();
  c.name_ = name;
  c.dset_ = Handle(Check(H5Dopen2(group, name.c_str(), NoChunkCache().get()), name), H5Dclose);
  Handle space(Check(H5Dget_space(c.dset_.get()), name), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank != (cols > 0 ? 2 : 1))
    throw std::runtime_error(fmt::format("dataset {} has rank {}, expected {}", name, rank, cols > 0 ? 2 : 1));
  hsize_t dims[2] = {0, 0};
  H5Sget_simple_extent_dims(space.get(), dims, nullptr);
  c.rows_ = dims[0];
  c.cols_ = rank == 2 ? dims[1] : 0;
  if (rank == 2 && cols != kAnyCols && c.cols_ != cols)
    throw std::runtime_error(fmt::format("dataset {} has {} columns, expected {}", name, c.cols_, cols));
  if (rank == 2 && (c.cols_ == 0 || c.cols_ > (1u << 16)))
    throw std::runtime_error(fmt::format("dataset {} has {} columns", name, c.cols_));
  // The stored type must convert to the memory type's class (no string read as numbers).
  Handle stored(Check(H5Dget_type(c.dset_.get()), name), H5Tclose);
  if (H5Tget_class(stored.get()) != H5Tget_class(type.memory()))
    throw std::runtime_error(fmt::format("dataset {} has the wrong element type", name));
  return c;
}

void Column::Stage(bool whole_chunks) {
  if (direct_ && chunk_rows_ > 0) {
    // buf_ begins at a chunk's first row (kept rows first): the rows staged are whole chunks, and
    // with !whole_chunks the last part-filled one too, whose rows are kept for the next flush.
    const size_t row_bytes = elem_size_ * std::max<Size>(cols_, 1);
    const Size total = used_ / row_bytes, kept = kept_bytes_ / row_bytes;
    const Size full = total / chunk_rows_ * chunk_rows_;
    const Size n = whole_chunks ? full : total;
    if (total == kept || n == 0) return;
    staged_first_ = rows_ - kept;
    const size_t from = static_cast<size_t>(full) * row_bytes, rest = used_ - from;
    if (staged_.size() < rest) staged_.resize(std::max(rest, buf_.size()));
    if (rest > 0) std::memcpy(staged_.data(), buf_.data() + from, rest);
    std::swap(buf_, staged_);
    staged_bytes_ = static_cast<size_t>(n) * row_bytes;
    encoded_ = false;
    used_ = rest;
    kept_bytes_ = whole_chunks ? 0 : rest;
    rows_ = staged_first_ + n;
    return;
  }
  Size n = pending();
  if (whole_chunks && chunk_rows_ > 0) n = (rows_ + n) / chunk_rows_ * chunk_rows_ - std::min(rows_, (rows_ + n) / chunk_rows_ * chunk_rows_);
  if (n == 0) return;
  staged_first_ = rows_;
  const size_t bytes = static_cast<size_t>(n) * elem_size_ * std::max<Size>(cols_, 1), rest = used_ - bytes;
  // The staged rows stay where they are: the buffers swap, and only the rows after them (less than
  // a chunk when whole_chunks) are copied to the front of the other one.
  if (staged_.size() < rest) staged_.resize(std::max(rest, buf_.size()));
  if (rest > 0) std::memcpy(staged_.data(), buf_.data() + bytes, rest);
  std::swap(buf_, staged_);
  staged_bytes_ = bytes;
  encoded_ = false;
  used_ = rest;
  rows_ += n;
}

namespace {
// The shuffled bytes of a chunk: one buffer per thread (the writer's, or the store's own when it
// encodes), not one per column.
thread_local Bytes shuffled;
}  // namespace

size_t Column::EncodeChunk(const unsigned char* rows, size_t bytes, size_t chunk_bytes, unsigned char* out) {
  // Every element equal to the first (each byte equal to the one an element further on); the
  // last chunk, part-filled, is padded with zeros (the fill value HDF5 pads edge chunks with), so
  // it is constant only when its rows are zeros.
  const bool constant = std::memcmp(rows, rows + elem_size_, bytes - elem_size_) == 0 &&
                        (bytes == chunk_bytes || std::all_of(rows, rows + elem_size_, [](unsigned char b) { return b == 0; }));
  if (constant) {
    if (constant_elem_.size() != elem_size_ || std::memcmp(constant_elem_.data(), rows, elem_size_) != 0) {
      constant_elem_.assign(rows, rows + elem_size_);
      const size_t len = ShuffleDeflatePadded(rows, bytes, chunk_bytes, elem_size_, shuffled, out);
      constant_packed_.assign(out, out + len);
    }
    std::memcpy(out, constant_packed_.data(), constant_packed_.size());
    return constant_packed_.size();
  }
  return bytes < chunk_bytes ? ShuffleDeflatePadded(rows, bytes, chunk_bytes, elem_size_, shuffled, out)
                             : ShuffleDeflate(rows, chunk_bytes, elem_size_, shuffled, out);
}

void Column::EncodeStaged() {
  if (encoded_) return;
  encoded_ = true;
  if (!direct_ || chunk_rows_ == 0) return;  // written through the library's filters
  const size_t row_bytes = elem_size_ * std::max<Size>(cols_, 1);
  const size_t chunk_bytes = static_cast<size_t>(chunk_rows_) * row_bytes, bound = ZlibFixedBound(chunk_bytes);
  const size_t chunks = (staged_bytes_ + chunk_bytes - 1) / chunk_bytes;
  if (packed_.size() < chunks * bound) packed_.resize(chunks * bound);
  packed_len_.resize(chunks);
  for (size_t i = 0; i < chunks; ++i) {
    const size_t bytes = std::min(chunk_bytes, staged_bytes_ - i * chunk_bytes);
    packed_len_[i] = EncodeChunk(staged_.data() + i * chunk_bytes, bytes, chunk_bytes, packed_.data() + i * bound);
  }
}

void Column::BeginStaged(Size first, Size n) {
  const size_t chunk_bytes = static_cast<size_t>(chunk_rows_) * elem_size_, bound = ZlibFixedBound(chunk_bytes);
  const size_t chunks = static_cast<size_t>((n + chunk_rows_ - 1) / chunk_rows_);
  if (packed_.size() < chunks * bound) packed_.resize(chunks * bound);
  packed_len_.resize(chunks);
  staged_first_ = first;
  staged_bytes_ = static_cast<size_t>(n) * elem_size_;
  encoded_ = true;
  rows_ = first + n;
}

void Column::StageChunk(size_t i, const unsigned char* elems, Size count) {
  const size_t chunk_bytes = static_cast<size_t>(chunk_rows_) * elem_size_;
  packed_len_[i] = EncodeChunk(elems, static_cast<size_t>(count) * elem_size_, chunk_bytes,
                               packed_.data() + i * ZlibFixedBound(chunk_bytes));
}

void Column::WriteStaged() {
  const hsize_t n = staged_bytes_ / (elem_size_ * std::max<Size>(cols_, 1));
  if (n == 0) return;
  if (!encoded_) EncodeStaged();
  const int rank = cols_ > 0 ? 2 : 1;
  const hsize_t dims[2] = {staged_first_ + n, cols_};
  CheckWrite(H5Dset_extent(dset_.get(), dims), dset_.get(), "extend");
  if (direct_ && chunk_rows_ > 0) {
    const size_t bound = ZlibFixedBound(static_cast<size_t>(chunk_rows_) * elem_size_ * std::max<Size>(cols_, 1));
    for (size_t i = 0; i < packed_len_.size(); ++i) {
      const hsize_t offset[2] = {staged_first_ + i * chunk_rows_, 0};
      CheckWrite(H5Dwrite_chunk(dset_.get(), H5P_DEFAULT, 0, offset, packed_len_[i], packed_.data() + i * bound),
                 dset_.get(), name_);
    }
  } else {
    const hsize_t start_at[2] = {staged_first_, 0}, rows_cols[2] = {n, cols_};
    Handle fs(H5Dget_space(dset_.get()), H5Sclose);
    H5Sselect_hyperslab(fs.get(), H5S_SELECT_SET, start_at, nullptr, rows_cols, nullptr);
    Handle ms(H5Screate_simple(rank, rows_cols, nullptr), H5Sclose);
    CheckWrite(H5Dwrite(dset_.get(), mem_type_.get(), ms.get(), fs.get(), H5P_DEFAULT, staged_.data()), dset_.get(),
               name_);
  }
  staged_bytes_ = 0;
  encoded_ = false;
}

void Column::Truncate(Size rows) {
  used_ = 0;
  staged_bytes_ = 0;
  encoded_ = false;
  kept_bytes_ = 0;
  direct_ = direct_ && chunk_rows_ > 0 && rows % chunk_rows_ == 0;  // buf_ from a chunk's first row
  const hsize_t dims[2] = {rows, cols_};
  CheckWrite(H5Dset_extent(dset_.get(), dims), dset_.get(), "truncate");
  rows_ = rows;
}

void Column::Read(Size first, Size n, void* out) const {
  if (n == 0) return;
  if (first > rows_ || n > rows_ - first)
    throw std::runtime_error(
        fmt::format("dataset {}: rows [{}, {}) beyond its {} rows", name_, first, first + n, rows_));
  const int rank = cols_ > 0 ? 2 : 1;
  const hsize_t start[2] = {first, 0}, count[2] = {n, cols_};
  Handle fs(H5Dget_space(dset_.get()), H5Sclose);
  H5Sselect_hyperslab(fs.get(), H5S_SELECT_SET, start, nullptr, count, nullptr);
  Handle ms(H5Screate_simple(rank, count, nullptr), H5Sclose);
  CheckStatus(H5Dread(dset_.get(), mem_type_.get(), ms.get(), fs.get(), H5P_DEFAULT, out), "read");
}

void Column::ReadAllRows() const {
  const Size row_bytes = elem_size_ * std::max<Size>(cols_, 1);
  const Size block = std::max<Size>(1, (Size{8} << 20) / row_bytes);
  std::vector<unsigned char> buf(static_cast<size_t>(std::min(block, std::max<Size>(rows_, 1)) * row_bytes));
  for (Size first = 0; first < rows_; first += block) {
    try {
      Read(first, std::min(block, rows_ - first), buf.data());
    } catch (const std::runtime_error&) {
      throw std::runtime_error(fmt::format("dataset {}: rows from {} cannot be read (a damaged chunk)", name_, first));
    }
    // Variable-length elements (none in the tables) would need reclaiming here.
  }
}

// ---- A full read, for the child process of a contained first read ----

namespace {

// max_bytes reaches the H5Ovisit2/H5Aiterate callbacks through their user data.
bool ReadAll(hid_t obj, hid_t file_type, hid_t space, bool attribute, double max_bytes) {
  Handle mtype(H5Tget_native_type(file_type, H5T_DIR_ASCEND), H5Tclose);
  if (!mtype) return false;
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  const size_t size = H5Tget_size(mtype.get());
  if (n < 0 || size == 0) return false;
  Handle mem_space(H5Scopy(space), H5Sclose);
  hssize_t count = n;
  if (static_cast<double>(n) * static_cast<double>(size) > max_bytes && !attribute) {
    // The first rows of a large dataset (its metadata is what can be corrupt, not its values).
    const int rank = H5Sget_simple_extent_ndims(space);
    if (rank < 1 || rank > 8) return false;
    hsize_t dims[8] = {0}, start[8] = {0};
    H5Sget_simple_extent_dims(space, dims, nullptr);
    const hssize_t row = dims[0] > 0 ? n / static_cast<hssize_t>(dims[0]) : 1;
    dims[0] = std::max<hsize_t>(1, static_cast<hsize_t>(max_bytes / static_cast<double>(size) /
                                                        static_cast<double>(std::max<hssize_t>(row, 1))));
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

herr_t ProbeAttribute(hid_t loc, const char* name, const H5A_info_t*, void* max_bytes) {
  Handle a(H5Aopen(loc, name, H5P_DEFAULT), H5Aclose);
  if (!a) return -1;
  Handle type(H5Aget_type(a.get()), H5Tclose);
  Handle space(H5Aget_space(a.get()), H5Sclose);
  return type && space && ReadAll(a.get(), type.get(), space.get(), true, *static_cast<double*>(max_bytes)) ? 0 : -1;
}

herr_t ProbeObject(hid_t root, const char* name, const H5O_info_t* info, void* max_bytes) {
  if (H5Aiterate_by_name(root, name, H5_INDEX_NAME, H5_ITER_NATIVE, nullptr, ProbeAttribute, max_bytes,
                         H5P_DEFAULT) < 0)
    return -1;
  if (info->type != H5O_TYPE_DATASET) return 0;
  Handle d(H5Dopen2(root, name, H5P_DEFAULT), H5Dclose);
  if (!d) return -1;
  Handle type(H5Dget_type(d.get()), H5Tclose);
  Handle space(H5Dget_space(d.get()), H5Sclose);
  return type && space && ReadAll(d.get(), type.get(), space.get(), false, *static_cast<double*>(max_bytes)) ? 0 : -1;
}

}  // namespace

bool ReadEverything(const std::string& path, double max_bytes, const std::vector<std::string>& only) {
  Silence();
  EnsureHeadroom();
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file) return false;
  if (only.empty())
    return H5Ovisit2(file.get(), H5_INDEX_NAME, H5_ITER_NATIVE, ProbeObject, &max_bytes, H5O_INFO_BASIC) >= 0;
  for (const auto& name : only) {
    // Each link of the path in turn (H5Oget_info_by_name on a path through a missing group fails).
    bool there = true;
    for (size_t slash = name.find('/', 1); there; slash = name.find('/', slash + 1)) {
      there = H5Lexists(file.get(), name.substr(0, slash).c_str(), H5P_DEFAULT) > 0;
      if (slash == std::string::npos) break;
    }
    H5O_info_t info;
    if (!there || H5Oget_info_by_name2(file.get(), name.c_str(), &info, H5O_INFO_BASIC, H5P_DEFAULT) < 0) continue;
    if (ProbeObject(file.get(), name.c_str(), &info, &max_bytes) < 0) return false;
  }
  return true;
}

}  // namespace vibro::h5
