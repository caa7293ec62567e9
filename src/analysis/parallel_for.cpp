// vibro::detail::ParallelFor (parallel_for.hpp) in libvibro: it loads the plugin
// libvibro_parallel.so (oneTBB) on its first call and forwards to it, so that no process maps TBB
// before it runs a parallel loop (docs/performance.md, "Start-up"), as the prover
// (src/proof/prove_loader.cpp) and the CVODE engine (src/dynamics/cvode_loader.cpp) are loaded.
#include "analysis/parallel_for.hpp"

#include <mutex>

#include "dynamics/plugin_loader.hpp"

namespace vibro::detail {
namespace {

const VibroParallelApi* LoadParallel() {
  const LoadedPlugin plugin =
      LoadPlugin({VIBRO_PARALLEL_PLUGIN, "vibro_parallel_api", false, "", "the thread pool ", ""});
  return reinterpret_cast<const VibroParallelApi* (*)()>(plugin.entry)();
}

const VibroParallelApi& Parallel() {
  static std::once_flag once;
  static const VibroParallelApi* api = nullptr;
  std::call_once(once, [] { api = LoadParallel(); });  // a failed load throws and is tried again
  return *api;
}

}  // namespace

void ParallelFor(std::size_t n, int threads, const std::function<void(std::size_t, std::size_t)>& body) {
  if (n == 0) return;
  Parallel().parallel_for(n, threads, body);
}

}  // namespace vibro::detail
