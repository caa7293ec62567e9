// vibro::ProveOrbit and vibro::ProveOrbitOverInterval (prove.hpp) in libvibro: they load the prover
// plugin libvibro_prove.so (proof/prove_api.hpp) on their first call and forward to it, so that
// no process maps Arb, FLINT and their libraries before it proves something (docs/performance.md,
// "Start-up").
#include <mutex>
#include <stdexcept>

#include "dynamics/plugin_loader.hpp"
#include "proof/prove_api.hpp"

namespace vibro {
namespace {

const VibroProveApi* LoadProver() {
  const detail::LoadedPlugin plugin =
      detail::LoadPlugin({VIBRO_PROVE_PLUGIN, "vibro_prove_api", false, "vibro prove: ", "the prover ", ""});
  const VibroProveApi* api = reinterpret_cast<const VibroProveApi* (*)()>(plugin.entry)();
  if (api->result_size != sizeof(ProofResult) || api->request_size != sizeof(ProofRequest))
    throw std::runtime_error("vibro prove: " + plugin.path + " was built from other headers than this libvibro");
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
