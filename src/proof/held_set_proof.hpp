// Sticking orbits of a model with several contacts, held on one contact or on a set of contacts at
// once, with plastic landings (docs/prove.md "Sticking orbits held on sets of contacts").
//
// The period is cut at its events into segments. While the contacts of a set H are held
// (c_hᵀX = e_h, c_hᵀẊ = 0, λ_h ≥ 0, h ∈ H; H empty: a free flight), the modes obey
//   Ẍ = a(Z) + T_H λ,  λ = −W_HH⁻¹ C_H a(Z),  a(Z) = −Ω²X − DẊ + T_A f sin ωt,
// (docs/contacts.md "Sticking on several contacts at once", W_hk = c_hᵀT_k), a linear system Ż = A_H Z
// in Z = (X, Ẋ, sin ωt, cos ωt) whose exponential is enclosed as for one held contact (held_flow.hpp).
// A segment ends at the plastic landing of a contact j (c_jᵀX = e_j; Ẋ ← P_Z Ẋ,
// P_Z = I − T_Z W_ZZ⁻¹ C_Z, Z = H ∪ {j}; j then sticks, H ∪ {j} held, or departs at once, H held) or at
// the release of a held contact h (λ_h = 0).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Dense>

#include "proof/budget.hpp"
#include "proof/held_flow.hpp"
#include "proof/proof_common.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro::proof {

// The event that ends a segment.
struct HeldSetTransition {
  bool landing = false;  // a plastic landing of `contact`; else its release
  int contact = 0;
  bool sticks = false;   // a landing: the contact stays held (else it departs at once)
};

// A sticking orbit held on sets, as the simulator found it: segment k starts at times[k] in the
// state (X[k], V[k]) just after the event that ends segment k − 1 (cyclically; segment 0 starts
// at a release), holds `held[k]` and ends with `ends[k]`; the last ends at times[0] + period·T.
struct HeldSetGuess {
  int period = 0;
  std::vector<double> times;
  std::vector<Eigen::VectorXd> X, V;
  std::vector<std::vector<int>> held;
  std::vector<HeldSetTransition> ends;
  // W_jk = c_jᵀT_k between the contacts, for the signs of the impulses at a landing beside held
  // contacts: exactly from the mass matrix (w_jᵀM⁻¹w_k) for a physical scene with every mode kept
  // ("structure"), else from the modal data ("modal").
  IntervalMatrix coupling;
  std::string coupling_source = "modal";
};

// The orbit of the scene as the simulator finds it (empty failure), or why none can be proven.
struct FoundHeldSet {
  std::string failure;
  bool stopped = false;
  HeldSetGuess guess;
};
FoundHeldSet FindHeldSetOrbit(const System& sys, const Scene& scene, const IntervalModel& model,
                              const ProofRequest& request, const Budget& budget);

Outcome ProveHeldSet(const IntervalModel& model, const HeldSetGuess& guess, const ProofRequest& request,
                     const Budget& budget);

// The held flow on the set `held` (sorted contacts): A in h.A, and per held contact its force
// λ_h = force[k]ᵀZ and rate λ̇_h = rate[k]ᵀZ. False (with `why`) when W_HH is not invertible.
struct SetFlow {
  HeldFlow h;
  std::vector<int> held;
  std::vector<std::vector<Interval>> force, rate;
};
bool MakeSetFlow(const IntervalModel& m, const std::vector<int>& held, SetFlow& out, std::string& why);

// The inverse of a small interval matrix (Gauss–Jordan on the diagonal pivots); false when a pivot
// may vanish. Exact zeros stay exact (a diagonal matrix has an exactly diagonal inverse).
bool InvertSmall(const IntervalMatrix& a, IntervalMatrix& inv);

}  // namespace vibro::proof
