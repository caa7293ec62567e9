// Address space held back for the HDF5 library: see memory_reserve.hpp.
#include "io/memory_reserve.hpp"

#include <sys/mman.h>

namespace vibro::h5 {

MemoryReserve::MemoryReserve() {
  if (!Take()) throw std::bad_alloc();
}

bool MemoryReserve::Take() {
  if (at_ != nullptr) return true;
  void* p = mmap(nullptr, kBytes, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) return false;
  at_ = p;
  return true;
}

void MemoryReserve::Release() {
  if (at_ == nullptr) return;
  munmap(at_, kBytes);
  at_ = nullptr;
}

}  // namespace vibro::h5
