// Bifurcation points proven (docs/prove.md "Bifurcation points"): the parameter of the point
// enclosed in an interval at most 1e-10 wide, exactly one point in it, the crossing transversal:
// the pitchfork and the fold of the symmetric two-sided one-DOF oscillator.
#pragma once

#include <string>

#include "proof/proof_common.hpp"

namespace vibro::proof {

// The model is the symmetric two-sided one-DOF oscillator: one undamped mode, contact 1 contact 0
// mirrored (c_1 = −c_0, e_1 = e_0 < 0, r_1 = r_0). `mirrored`: the scene's structure says
// c_1 = −c_0 exactly (two stops on one DOF, opposite sides), when the model's c are enclosures.
// Otherwise false, with the reason in `why`.
bool SymmetricTwoSided(const IntervalModel& model, bool mirrored, std::string& why);

// The symmetry-breaking pitchfork of the symmetric orbit (bifurcation_proof.cpp), near `located`,
// the amplitude (frequency = false) or the forcing frequency: proven, `interval_text` is
// "[lo, hi]" (exact decimals) holding exactly one pitchfork, crossed transversally.
// `bracket`: the location's uncertainty; the value is refined by Newton within it (0: not refined).
Outcome ProvePitchfork(const IntervalModel& model, bool mirrored, bool frequency, double located, double bracket,
                       const Budget& budget, std::string& interval_text);

// The fold of the symmetric orbit (the two symmetric orbits merge), likewise.
Outcome ProveSymmetricFold(const IntervalModel& model, bool mirrored, bool frequency, double located,
                           double bracket, const Budget& budget, std::string& interval_text);

}  // namespace vibro::proof
