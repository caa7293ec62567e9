// The prover as a plugin (docs/performance.md, "Start-up"). Arb and FLINT, and with them NTL,
// gf2x, MPFR and GMP, cost a process about 4 ms of CPU to map and relocate even when it never
// proves anything; so src/proof/*.cpp (the only code that uses them) is built into the plugin
// libvibro_prove.so beside libvibro, and libvibro reaches it through this table, loaded
// (src/proof/prove_loader.cpp) on the first call of ProveOrbit or ProveOrbitOverInterval.
// `vibro --version`, `vibro simulate` and every other command never map Arb.
#pragma once

#include <vector>

#include "vibro/prove.hpp"

namespace vibro::proof {

// The definitions behind vibro::ProveOrbit and vibro::ProveOrbitOverInterval (prove.hpp), in the
// plugin (src/proof/prove.cpp).
ProofResult ProveOrbit(const System& system, const Scene& scene, const ProofRequest& request);
std::vector<ProofResult> ProveOrbitOverInterval(const System& system_lo, const Scene& scene_lo, const ProofRequest& lo,
                                                const System& system_hi, const Scene& scene_hi, const ProofRequest& hi);
ProofResult ProveBifurcation(const System& system, const Scene& scene, const BifurcationRequest& request);

}  // namespace vibro::proof

extern "C" {

struct VibroProveApi {
  // sizeof(vibro::ProofResult) and sizeof(vibro::ProofRequest) as the plugin was built: the loader
  // refuses a plugin of another build of the headers.
  unsigned long result_size, request_size;
  vibro::ProofResult (*prove_orbit)(const vibro::System&, const vibro::Scene&, const vibro::ProofRequest&);
  std::vector<vibro::ProofResult> (*prove_over_interval)(const vibro::System&, const vibro::Scene&,
                                                         const vibro::ProofRequest&, const vibro::System&,
                                                         const vibro::Scene&, const vibro::ProofRequest&);
  vibro::ProofResult (*prove_bifurcation)(const vibro::System&, const vibro::Scene&, const vibro::BifurcationRequest&);
};

// The plugin's one exported symbol.
const VibroProveApi* vibro_prove_api();
}

// The plugin's file name; prove_loader.cpp looks for it beside the object libvibro is in.
#define VIBRO_PROVE_PLUGIN "libvibro_prove.so"
