// The symmetry-breaking pitchfork of the symmetric orbit of a mirrored model, any number of modes,
// damped or not (docs/prove.md "Bifurcation points"): the parameter enclosed in an interval at most
// 1e-10 wide, exactly one point in it, the crossing transversal.
#pragma once

#include <string>

#include "proof/proof_common.hpp"

namespace vibro::proof {

// `guess`: the symmetric orbit (two impacts, on contact 0 and contact 1 half a period apart, the
// second state the first mirrored) found at `located`; `mirrored` as ProveGrazing's.
Outcome ProveOrbitPitchfork(const IntervalModel& model, bool mirrored, const ImpactGuess& guess, bool frequency,
                            double located, double bracket, const Budget& budget, std::string& interval_text);

}  // namespace vibro::proof
