// vibro::detail::ParallelFor (parallel_for.hpp) in libvibro: it loads the plugin
// libvibro_parallel.so (oneTBB) on its first call and forwards to it, so that no process maps TBB
// before it runs a parallel loop (docs/performance.md, "Start-up"), as the prover
// (src/proof/prove_loader.cpp) and the CVODE engine (src/dynamics/cvode_loader.cpp) are loaded.
#include "analysis/parallel_for.hpp"

#include <dlfcn.h>

#include <mutex>
#include <new>
#include <stdexcept>
#include <string>

namespace vibro::detail {
namespace {

// A plugin that could not be mapped because the address space or memory ran out (ulimit -v, the
// process's RLIMIT_AS) is memory exhausted like any refused allocation: std::bad_alloc (exit 3 from
// the command line, MemoryError in Python), not a missing file. `error`: dlerror()'s text.
std::string RefuseOutOfMemory(const char* error) {
  std::string e = error != nullptr ? error : "no error reported";
  if (e.find("failed to map segment") != std::string::npos || e.find("cannot map zero-fill") != std::string::npos ||
      e.find("Cannot allocate memory") != std::string::npos || e.find("out of memory") != std::string::npos)
    throw std::bad_alloc();
  return e;
}

// The plugin beside the object this code is in (libvibro.so: build/ in the build tree, lib/ once
// installed), or in ../lib of it (a program linked with a static libvibro, installed in bin/).
// RTLD_NODELETE: loaded once for the life of the process.
const VibroParallelApi* LoadParallel() {
  Dl_info self{};
  std::string dir;
  if (dladdr(reinterpret_cast<void*>(&LoadParallel), &self) != 0 && self.dli_fname != nullptr) {
    const std::string object = self.dli_fname;
    const auto slash = object.rfind('/');
    if (slash != std::string::npos) dir = object.substr(0, slash + 1);
  }
  std::string path = dir + VIBRO_PARALLEL_PLUGIN, tried = path;
  void* plugin = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (plugin == nullptr) RefuseOutOfMemory(dlerror());
  if (plugin == nullptr && !dir.empty()) {
    path = dir + "../" VIBRO_LIBDIR "/" VIBRO_PARALLEL_PLUGIN;
    tried += " or " + path;
    plugin = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  }
  const std::string error = plugin == nullptr ? RefuseOutOfMemory(dlerror()) : std::string();
  if (plugin == nullptr) throw std::runtime_error("cannot load the thread pool " + tried + ": " + error);
  auto* entry = reinterpret_cast<const VibroParallelApi* (*)()>(dlsym(plugin, "vibro_parallel_api"));
  if (entry == nullptr) throw std::runtime_error(path + " lacks vibro_parallel_api");
  return entry();
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
