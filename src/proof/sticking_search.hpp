// The sticking orbit a proof starts from (docs/prove.md): the Poincaré solver's sticking orbit,
// then two of its periods followed by the simulator with an observer that records the events the
// proof needs (landings, sticks, releases). One search for the sticking proofs of one contact and of
// sets of contacts.
#pragma once

#include <string>

#include "proof/budget.hpp"
#include "vibro/observer.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/prove.hpp"
#include "vibro/scene.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace vibro::proof {

struct StickingSearch {
  std::string failure;   // why there is no sticking orbit to prove (empty: found)
  bool stopped = false;  // the budget ran out (or a stop was requested) during the search
  OrbitResult orbit;
  RunResult run;
};

// Solves for the sticking orbit of `request` (its period, transient and start), then follows it over
// 2q + 1 periods from its section with `recorder` watching.
StickingSearch FollowStickingOrbit(const System& sys, const Scene& scene, const ProofRequest& request,
                                   const Budget& budget, Observer& recorder);

}  // namespace vibro::proof
