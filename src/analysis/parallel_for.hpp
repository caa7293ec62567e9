// Parallel loops over independent items (the cells of a study, the columns of a partition, the
// classes of a study's orbits), run on oneTBB's thread pool. oneTBB itself is a plugin,
// libvibro_parallel.so beside libvibro (parallel_plugin.cpp, the one file that includes TBB),
// loaded by parallel_for.cpp on the first parallel loop of a process: libtbb is bound at load, not
// lazily, and every `vibro simulate`, `vibro --version` and Python import paid for mapping it
// although only a study runs in parallel (docs/performance.md, "Start-up").
#pragma once

#include <cstddef>
#include <functional>

namespace vibro::detail {

// body(begin, end) over blocks that together cover [0, n) once, on up to `threads` threads at a
// time (0: oneTBB's default, every processor the process may use), as tbb::parallel_for over a
// tbb::blocked_range<size_t>(0, n) under a tbb::global_control of max_allowed_parallelism =
// threads. An exception thrown by a body is rethrown here, in the calling thread.
void ParallelFor(std::size_t n, int threads, const std::function<void(std::size_t, std::size_t)>& body);

}  // namespace vibro::detail

extern "C" {

struct VibroParallelApi {
  void (*parallel_for)(std::size_t n, int threads, const std::function<void(std::size_t, std::size_t)>& body);
};

// The plugin's one exported symbol.
const VibroParallelApi* vibro_parallel_api();
}

// The plugin's file name; parallel_for.cpp looks for it beside the object libvibro is in.
#define VIBRO_PARALLEL_PLUGIN "libvibro_parallel.so"
