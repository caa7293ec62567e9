// Address space held back for the HDF5 library (docs/output.md, "Memory"). HDF5 1.10 does not
// survive every failed allocation: H5B_create, which makes a node of a chunk index (its first one,
// and one more each time a node splits, i.e. every few dozen chunks written), leaves a pointer
// unset when an allocation fails and its clean-up frees it (SIGSEGV in H5FL_blk_free from
// H5B__node_dest, seen under `ulimit -v`); other failures end the process with exit(-1).
//
// So the store never lets the library meet a failed allocation: while a file is open it holds a
// mapping of kBytes of address space, and releases it just before a stretch of HDF5 calls, which
// only the store's thread makes while no other thread of the store runs (the writer thread only
// encodes rows, and waits). The stretch's allocations (what a flush of 4 MiB of rows and of the
// metadata takes: far below kBytes, measured in docs/output.md "Memory") then come out of that
// room. The reserve is taken back before the next stretch, and before the run goes on after a
// flush; when it cannot be, the library or the run has used memory the process does not have to
// spare, and the store stops there (std::bad_alloc: exit 3, the file as its last flush left it)
// without calling the library again (h5::Abandon). A limit under which the simulation itself runs
// out meets its own std::bad_alloc with the reserve still held, which the store's clean-up then
// releases for the closing of its file.
//
// The mapping is PROT_NONE and never touched: under an address-space limit (RLIMIT_AS, `ulimit
// -v`), the one vibro reports as out of memory, it counts in full while costing no RAM.
#pragma once

#include <cstddef>
#include <new>

namespace vibro::h5 {

class MemoryReserve {
 public:
  static constexpr size_t kBytes = size_t{16} << 20;
  // Maps the reserve; std::bad_alloc when the system refuses it.
  MemoryReserve();
  ~MemoryReserve() { Release(); }
  MemoryReserve(const MemoryReserve&) = delete;
  MemoryReserve& operator=(const MemoryReserve&) = delete;

  // Maps the reserve again if it was released; false when the system refuses it.
  bool Take();
  // Unmaps the reserve: the room is the HDF5 calls' that follow.
  void Release();
  bool held() const { return at_ != nullptr; }

 private:
  void* at_ = nullptr;
};

}  // namespace vibro::h5
