// libvibro gives Eigen the caches' sizes the C library read (src/model/eigen_caches.cpp) instead of
// letting Eigen ask the processor with `cpuid`: the blocks of Eigen's large products, and so their
// rounding, stay what they were only if the two agree. This program is built without
// EIGEN_NO_CPUID and without libvibro, so Eigen::internal::queryCacheSizes is Eigen's own `cpuid`
// query; it must find the sizes sysconf gives (a size either does not know: Eigen's default).
// Exit 0 when they agree, 1 otherwise.
#include <unistd.h>

#include <cstdio>

#include <Eigen/Core>

#ifdef EIGEN_NO_CPUID
#error "eigen_cache_sizes_test needs Eigen's own cpuid query"
#endif

namespace {

std::ptrdiff_t Known(long bytes, std::ptrdiff_t fallback) { return bytes > 0 ? bytes : fallback; }

}  // namespace

int main() {
  using namespace Eigen::internal;
  int q1 = -1, q2 = -1, q3 = -1;
  queryCacheSizes(q1, q2, q3);
  const std::ptrdiff_t eigen[3] = {manage_caching_sizes_helper(q1, defaultL1CacheSize),
                                   manage_caching_sizes_helper(q2, defaultL2CacheSize),
                                   manage_caching_sizes_helper(q3, defaultL3CacheSize)};
  const std::ptrdiff_t libc[3] = {Known(sysconf(_SC_LEVEL1_DCACHE_SIZE), defaultL1CacheSize),
                                  Known(sysconf(_SC_LEVEL2_CACHE_SIZE), defaultL2CacheSize),
                                  Known(sysconf(_SC_LEVEL3_CACHE_SIZE), defaultL3CacheSize)};
  int failed = 0;
  for (int i = 0; i < 3; ++i) {
    const bool same = eigen[i] == libc[i];
    std::printf("L%d: Eigen's cpuid query %td bytes, sysconf %td bytes: %s\n", i + 1, eigen[i], libc[i],
                same ? "same" : "DIFFERENT");
    failed += same ? 0 : 1;
  }
  return failed == 0 ? 0 : 1;
}
