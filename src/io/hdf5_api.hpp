// The HDF5 C API as h5_file.cpp calls it, through a table of entry points filled at first use
// by dlopen(3) of the HDF5 library found at configure time. Included by src/io/h5_file.cpp alone.
//
// Why: libhdf5 links libcurl (its read-only S3 driver), and libcurl GnuTLS, Kerberos and LDAP,
// about 30 shared libraries that cost a process about 4 ms of CPU to map and relocate
// (docs/performance.md, "Start-up"). Loaded at first use, they cost nothing to the commands and
// runs that open no HDF5 file (`vibro --version`, `vibro simulate SCENE` without --out).
//
// The declarations come from <hdf5.h> as usual (decltype of each function and variable); the
// macros at the end send every name h5_file.cpp uses, including those behind HDF5's own macros
// (H5T_NATIVE_DOUBLE → H5T_NATIVE_DOUBLE_g, H5Dopen → H5Dopen2), to the table. A name missing
// here is a link error of libvibro (it links no HDF5), never a silent direct call.
#pragma once

#include <dlfcn.h>

#include <stdexcept>
#include <string>

#include <hdf5.h>

// Every function and variable of the HDF5 library that h5_file.cpp uses (`nm -u` of its object).
#define VIBRO_HDF5_FUNCTIONS(X) \
    X(H5Aclose) X(H5Acreate2) X(H5Adelete) X(H5Aexists) X(H5Aget_space) X(H5Aget_type) \
    X(H5Aiterate2) X(H5Aiterate_by_name) X(H5Aopen) X(H5Aread) X(H5Awrite) X(H5Dclose) \
    X(H5Dcreate2) X(H5Dget_space) X(H5Dget_type) X(H5Dopen2) X(H5Dread) X(H5Dset_extent) \
    X(H5Dvlen_reclaim) X(H5Dwrite) X(H5Eset_auto2) X(H5Ewalk2) X(H5Fclose) X(H5Fcreate) \
    X(H5Fflush) X(H5Fget_mdc_size) X(H5Fget_name) X(H5Fget_vfd_handle) X(H5Fis_hdf5) X(H5Fopen) \
    X(H5Gclose) X(H5Gcreate2) X(H5Gget_info) X(H5Gopen2) X(H5Idec_ref) X(H5Iget_file_id) \
    X(H5Iget_type) X(H5Ldelete) X(H5Lexists) X(H5Lget_name_by_idx) X(H5Literate) \
    X(H5Oget_info_by_name2) X(H5Ovisit2) X(H5Pclose) X(H5Pcreate) X(H5Pget_mdc_config) \
    X(H5Pset_chunk) X(H5Pset_chunk_cache) X(H5Pset_deflate) X(H5Pset_file_locking) \
    X(H5Pset_file_space_strategy) X(H5Pset_mdc_config) X(H5Pset_shuffle) X(H5Sclose) X(H5Scopy) \
    X(H5Screate) X(H5Screate_simple) X(H5Sget_simple_extent_dims) X(H5Sget_simple_extent_ndims) \
    X(H5Sget_simple_extent_npoints) X(H5Sselect_hyperslab) X(H5Tclose) X(H5Tcopy) \
    X(H5Tdetect_class) X(H5Tenum_create) X(H5Tenum_insert) X(H5Tget_class) X(H5Tget_native_type) \
    X(H5Tget_size) X(H5Tis_variable_str) X(H5Tset_cset) X(H5Tset_size) X(H5check_version) \
    X(H5free_memory) X(H5open)

#define VIBRO_HDF5_VARIABLES(X) \
    X(H5P_CLS_DATASET_ACCESS_ID_g) X(H5P_CLS_DATASET_CREATE_ID_g) X(H5P_CLS_FILE_ACCESS_ID_g) \
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
  // RTLD_NODELETE: HDF5's atexit handlers stay valid however the handle is treated.
  void* lib = dlopen(VIBRO_HDF5_LIBRARY, RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (lib == nullptr)
    throw std::runtime_error(std::string("cannot load the HDF5 library " VIBRO_HDF5_LIBRARY ": ") +
                             dlerror());
  Hdf5Api api{};
  auto entry = [&](const char* name) {
    void* p = dlsym(lib, name);
    if (p == nullptr)
      throw std::runtime_error(std::string("the HDF5 library " VIBRO_HDF5_LIBRARY " lacks ") + name);
    return p;
  };
#define VIBRO_HDF5_ENTRY(name) api.name = reinterpret_cast<decltype(api.name)>(entry(#name));
  VIBRO_HDF5_FUNCTIONS(VIBRO_HDF5_ENTRY)
  VIBRO_HDF5_VARIABLES(VIBRO_HDF5_ENTRY)
#undef VIBRO_HDF5_ENTRY
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
#define H5T_NATIVE_INT32_g (*::vibro::h5::Hdf5().H5T_NATIVE_INT32_g)
#define H5T_NATIVE_INT64_g (*::vibro::h5::Hdf5().H5T_NATIVE_INT64_g)
#define H5T_NATIVE_INT8_g (*::vibro::h5::Hdf5().H5T_NATIVE_INT8_g)
#define H5T_NATIVE_UINT8_g (*::vibro::h5::Hdf5().H5T_NATIVE_UINT8_g)
#define H5T_STD_I32LE_g (*::vibro::h5::Hdf5().H5T_STD_I32LE_g)
#define H5T_STD_I64LE_g (*::vibro::h5::Hdf5().H5T_STD_I64LE_g)
#define H5T_STD_I8LE_g (*::vibro::h5::Hdf5().H5T_STD_I8LE_g)
#define H5T_STD_U8LE_g (*::vibro::h5::Hdf5().H5T_STD_U8LE_g)
