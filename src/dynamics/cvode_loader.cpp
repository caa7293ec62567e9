// MakeCvodeEngine (cvode_api.hpp) and MakeCvodeCompliant (cvode_engine.hpp) in libvibro: they load
// the CVODE plugin libvibro_cvode.so on their first call and forward to it, so that no process maps
// SUNDIALS before it integrates with CVODE (docs/performance.md, "Start-up"), as the prover
// (src/proof/prove_loader.cpp) and HDF5 (src/io/h5_file.cpp) are loaded.
#include <dlfcn.h>

#include <mutex>
#include <new>
#include <stdexcept>
#include <string>

#include "dynamics/cvode_api.hpp"
#include "dynamics/cvode_engine.hpp"

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
const VibroCvodeApi* LoadCvode() {
  Dl_info self{};
  std::string dir;
  if (dladdr(reinterpret_cast<void*>(&LoadCvode), &self) != 0 && self.dli_fname != nullptr) {
    const std::string object = self.dli_fname;
    const auto slash = object.rfind('/');
    if (slash != std::string::npos) dir = object.substr(0, slash + 1);
  }
  std::string path = dir + VIBRO_CVODE_PLUGIN, tried = path;
  void* plugin = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (plugin == nullptr) RefuseOutOfMemory(dlerror());
  if (plugin == nullptr && !dir.empty()) {
    path = dir + "../" VIBRO_LIBDIR "/" VIBRO_CVODE_PLUGIN;
    tried += " or " + path;
    plugin = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  }
  const std::string error = plugin == nullptr ? RefuseOutOfMemory(dlerror()) : std::string();
  if (plugin == nullptr)
    throw std::runtime_error("run.engine = \"cvode\": cannot load the CVODE engine " + tried + ": " + error);
  auto* entry = reinterpret_cast<const VibroCvodeApi* (*)()>(dlsym(plugin, "vibro_cvode_api"));
  if (entry == nullptr) throw std::runtime_error("run.engine = \"cvode\": " + path + " lacks vibro_cvode_api");
  const VibroCvodeApi* api = entry();
  if (api->run_size != sizeof(RunSpec) || api->model_size != sizeof(ModelT<double>))
    throw std::runtime_error("run.engine = \"cvode\": " + path + " was built from other headers than this libvibro");
  return api;
}

const VibroCvodeApi& Cvode() {
  static std::once_flag once;
  static const VibroCvodeApi* api = nullptr;
  std::call_once(once, [] { api = LoadCvode(); });  // a failed load throws and is tried again
  return *api;
}

}  // namespace

std::unique_ptr<Propagator> MakeCvodeEngine(const System& system, const RunSpec& run) {
  return Cvode().make_engine(system, run);
}

std::unique_ptr<CompliantPhase> MakeCvodeCompliant(const RunSpec& run, const std::vector<const ModelT<double>*>& models,
                                                   int contact) {
  return Cvode().make_compliant(run, models, contact);
}

}  // namespace vibro::detail
