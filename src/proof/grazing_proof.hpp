// A grazing proven (docs/prove.md "Bifurcation points"): the parameter at which an impacting
// orbit's free flight touches a contact with zero velocity, enclosed in an interval at most 1e-10
// wide, exactly one such parameter in it, the crossing transversal.
#pragma once

#include <string>

#include "proof/proof_common.hpp"

namespace vibro::proof {

// The grazing of the impacting orbit `guess` (found at the located parameter `located`; any
// model: damped, several contacts, any number of modes), in the amplitude (frequency = false) or
// the forcing frequency. `bracket`: the location's uncertainty; the point is refined by Newton
// within it (0: the interval is centred on `located`). Proven: `interval_text` is "[lo, hi]".
// `mirrored`: the scene's structure says contact 1 is contact 0 mirrored (two stops on one DOF,
// opposite sides); a symmetric orbit of such a model is proven as its half.
Outcome ProveGrazing(const IntervalModel& model, bool mirrored, const ImpactGuess& guess, bool frequency,
                     double located, double bracket, const Budget& budget, std::string& interval_text);

}  // namespace vibro::proof
