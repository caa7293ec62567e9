// The caches' sizes Eigen's blocked products are cut to (docs/performance.md, "Start-up").
//
// A product or triangular solve with a dimension of 48 or more (a 50-mode beam's model) is cut
// into blocks sized from the L1, L2 and L3 caches, and the blocks set the order of its sums: its
// rounding depends on those sizes. Eigen asks the processor for them with `cpuid` at the first
// such product of a process, which traps to the hypervisor on a virtual machine (1.7 % of the CPU
// of a short `vibro simulate`). libvibro is built with EIGEN_NO_CPUID (CMakeLists.txt), so Eigen
// asks nothing and would take its fixed defaults (32 KiB, 256 KiB, 2 MiB on x86), which round the
// beam's events differently from before. The C library already knows the sizes: glibc reads them
// with `cpuid` once in every process's start-up, and sysconf returns what it read. They are given
// to Eigen here, when libvibro is loaded, before any product; a size the C library does not know
// (0 or -1) takes Eigen's default, as Eigen's own query does (test eigen.cache_sizes: the same
// sizes as Eigen's query).
#include <unistd.h>

#include <Eigen/Core>

namespace vibro::detail {
namespace {

std::ptrdiff_t Known(long bytes, std::ptrdiff_t fallback) { return bytes > 0 ? bytes : fallback; }

[[maybe_unused]] const bool kEigenCacheSizes = [] {
  using namespace Eigen::internal;
  Eigen::setCpuCacheSizes(Known(sysconf(_SC_LEVEL1_DCACHE_SIZE), defaultL1CacheSize),
                          Known(sysconf(_SC_LEVEL2_CACHE_SIZE), defaultL2CacheSize),
                          Known(sysconf(_SC_LEVEL3_CACHE_SIZE), defaultL3CacheSize));
  return true;
}();

}  // namespace
}  // namespace vibro::detail
