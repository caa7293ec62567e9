// The scene as written (docs/prove.md, "The scene as written"): for a scene in the physical form
// (mass and stiffness matrices), the modal data of the proof are enclosures of the eigenpairs of
// K φ = ω² M φ, not the floating-point eigen-decomposition the simulator uses.
//
// Every eigenpair (λ_k = ω_k², φ_k) of the pencil is enclosed (interval.hpp, PencilEigenpairs) for
// the scene's matrices as exact decimals, all eigenvalues certified simple and ordered; each
// eigenvector is scaled to the paper's normalisation, a unit component at contact 0
// (ψ = φ/(σ_0 w_0ᵀφ), docs/model.md §1.3), and its box widened to a relative 1e-15. From those boxes
// the modal data of the kept modes are enclosed as docs/model.md §1.3 builds them:
//   ω_i = √λ_i,  m_i = ψ_iᵀMψ_i,  T_A,i = ψ_i(A)/m_i,  T_B,i = 1/m_i,  c_i = 1,
//   contact j ≥ 1:  c_j,i = σ_j w_jᵀψ_i,  T_j,i = c_j,i/m_i,
// and these intervals (not points) are the model the orbit is proven for: the theorem holds for
// the scene's matrices. The certificate's "structure" carries the matrices, the contacts and the
// eigenpair boxes; scripts/vibro_check_proof.py re-proves each box holds exactly one eigenpair and
// recomputes the modal data from them.
#pragma once

#include <string>
#include <vector>

#include "proof/proof_common.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro::proof {

struct ModalEnclosure {
  // "" when enclosed; else why not (a repeated natural frequency, a mode with a node at contact 0).
  std::string failure;
  // Interval texts "[lo, hi]" of the kept modes: ω_i, T_A,i, T_B,i, c_i (contact 0).
  std::vector<std::string> omega, forcing, contact, shape;
  // Contacts 1, 2, ...: c_j,i and T_j,i.
  std::vector<std::vector<std::string>> more_shape, more_contact;
  Json structure;  // the certificate's "structure" (docs/prove.md)
};

// `sys` is System(scene), scene.physical is set. The floating-point modal data of `sys` (the orbit
// search's) are checked to lie within 1e-10 of the enclosures (else `failure` says which do not).
ModalEnclosure EncloseModalData(const System& sys, const Scene& scene);

}  // namespace vibro::proof
