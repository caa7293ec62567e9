// The plugin libvibro_parallel.so (parallel_for.hpp): ParallelFor on oneTBB, the one file of vibro
// that includes TBB. libvibro loads it on the first parallel loop of a process (parallel_for.cpp).
#include <cstddef>
#include <functional>
#include <optional>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/parallel_for.h>

#include "analysis/parallel_for.hpp"

namespace {

void TbbParallelFor(std::size_t n, int threads, const std::function<void(std::size_t, std::size_t)>& body) {
  std::optional<tbb::global_control> limit;
  if (threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n),
                    [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

}  // namespace

extern "C" __attribute__((visibility("default"))) const VibroParallelApi* vibro_parallel_api() {
  static const VibroParallelApi api{&TbbParallelFor};
  return &api;
}
