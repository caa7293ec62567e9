// vibro::ProveOrbit and vibro::ProveOrbitOverInterval (prove.hpp) in libvibro: they load the prover
// plugin libvibro_prove.so (proof/prove_api.hpp) on their first call and forward to it, so that
// no process maps Arb, FLINT and their libraries before it proves something (docs/performance.md,
// "Start-up").
#include <dlfcn.h>

#include <mutex>
#include <stdexcept>
#include <string>

#include "proof/prove_api.hpp"

namespace vibro {
namespace {

// The plugin beside the object this code is in (libvibro.so: build/ in the build tree, lib/ once
// installed), or in ../lib of it (a program linked with a static libvibro, installed in bin/).
// RTLD_NODELETE: loaded once for the life of the process.
const VibroProveApi* LoadProver() {
  Dl_info self{};
  std::string dir;
  if (dladdr(reinterpret_cast<void*>(&LoadProver), &self) != 0 && self.dli_fname != nullptr) {
    const std::string object = self.dli_fname;
    const auto slash = object.rfind('/');
    if (slash != std::string::npos) dir = object.substr(0, slash + 1);
  }
  std::string path = dir + VIBRO_PROVE_PLUGIN, tried = path;
  void* plugin = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (plugin == nullptr && !dir.empty()) {
    path = dir + "../" VIBRO_LIBDIR "/" VIBRO_PROVE_PLUGIN;
    tried += " or " + path;
    plugin = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  }
  if (plugin == nullptr)
    throw std::runtime_error("vibro prove: cannot load the prover " + tried + ": " + dlerror());
  auto* entry = reinterpret_cast<const VibroProveApi* (*)()>(dlsym(plugin, "vibro_prove_api"));
  if (entry == nullptr) throw std::runtime_error("vibro prove: " + path + " lacks vibro_prove_api");
  const VibroProveApi* api = entry();
  if (api->result_size != sizeof(ProofResult) || api->request_size != sizeof(ProofRequest))
    throw std::runtime_error("vibro prove: " + path + " was built from other headers than this libvibro");
  return api;
}

const VibroProveApi& Prover() {
  static std::once_flag once;
  static const VibroProveApi* api = nullptr;
  std::call_once(once, [] { api = LoadProver(); });  // a failed load throws and is tried again
  return *api;
}

}  // namespace

ProofResult ProveOrbit(const System& system, const Scene& scene, const ProofRequest& request) {
  return Prover().prove_orbit(system, scene, request);
}

std::vector<ProofResult> ProveOrbitOverInterval(const System& system_lo, const Scene& scene_lo, const ProofRequest& lo,
                                                const System& system_hi, const Scene& scene_hi, const ProofRequest& hi) {
  return Prover().prove_over_interval(system_lo, scene_lo, lo, system_hi, scene_hi, hi);
}

ProofResult ProveBifurcation(const System& system, const Scene& scene, const BifurcationRequest& request) {
  return Prover().prove_bifurcation(system, scene, request);
}

}  // namespace vibro
