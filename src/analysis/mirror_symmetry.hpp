// The mirror symmetry of a model (docs/orbits.md, "Closed loops"): x ↦ −x with t ↦ t + T/2. The
// structure is linear, so the flow commutes with it when every harmonic of the forcing is an odd
// multiple of the base pulsation (f sin(n(ωt + π)) = −f sin nωt for odd n) and the contacts come in
// mirror pairs: contact k is contact j mirrored when its gap c_kᵀX − e_k is c_jᵀ(−X) − e_j, i.e.
// c_k = −c_j and e_k = e_j (two stops on one DOF on opposite sides at ±d), with equal restitutions
// and compliances. The tube in its loose support (data/scenes/tube_loose_support.toml) and the
// symmetric two-sided oscillator are mirrored models; a stop with no mirror partner, a preload
// (e_0 ≠ e_1) or an even harmonic breaks the symmetry.
#pragma once

#include <optional>
#include <vector>

#include "vibro/system.hpp"

namespace vibro {

// The contact permutation of the mirror symmetry: image[j] = the contact that is contact j
// mirrored (an involution without fixed points), or nothing when the model is not mirrored.
// Shapes and stops are compared within 1e-12 relative.
std::optional<std::vector<int>> MirrorImage(const System& sys);

}  // namespace vibro
