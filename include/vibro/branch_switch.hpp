// Branch switching (docs/orbits.md, "Branch switching"): at a branch point or a flip of a branch of
// periodic orbits, the first points of the other branch through it.
//
// Let G(z, λ) = F^p(z; λ) − z on the stroboscopic section ωt0 = φ0 (poincare.hpp), p forcing
// periods. Along the old branch the null space of [D_zG ∂_λG] is its tangent t. At a simple branch
// point it is two-dimensional (D_zG has a kernel φ: a real multiplier of DF^p equals +1 and ∂_λG
// lies in the range of D_zG); the second branch leaves in the plane of t and (φ, 0). At a flip of
// the q-periodic branch, DF^q has the multiplier −1 with eigenvector φ, and the old branch, seen as
// orbits of period p = 2q, has a branch point: DF^{2q} − I = (DF^q − I)(DF^q + I) has the kernel φ,
// and the period-2q orbits born there leave along (φ, 0) (a pitchfork of F^{2q} whose two halves
// are one orbit, shifted by q periods).
//
// The switch: two points of the old branch at λ* ∓ δ (corrected with λ held fixed, δ small), their
// midpoint y* and chord t; φ = the right singular vector of the smallest singular value of D_zG at
// y*; d = (φ, 0) made orthogonal to t. From the predictor y_p = y* ± c (φ, 0), c = h/(dᵀ(φ, 0)) (the
// new branch's tangent at a pitchfork and at a flip), Newton solves {G(y) = 0, dᵀ(y − y_p) = 0}:
// this hyperplane cuts the new branch at distance ~h and the old one only at distance ~√h (its
// curvature), so the corrector lands on the new branch (at a transcritical point, whose new
// tangent mixes t and (φ, 0), it moves O(h) within the hyperplane to get there). A corrected
// point is accepted when it stays within 0.3 h of its predictor and lies at least h/4 from the old
// orbit at the same λ (and, at a flip, is no fixed point of F^q); h is tried from 1e-4 of the
// orbit's scale up and down.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "vibro/scene.hpp"

namespace vibro {

struct SwitchRequest {
  std::function<Scene(double)> scene_at;  // the scene with the continued key at λ
  std::string kind;        // "branch-point" or "flip": the bifurcation to switch at
  double value = 0;        // its λ* (e.g. Bifurcation::value of the old branch)
  // A point of the old branch near λ* (a BranchPoint): its λ, section time, modal state and the
  // period q of the old branch, in forcing periods.
  double from_value = 0, section_time = 0;
  Eigen::VectorXd X, V;  // (n)
  int period = 1;
  const std::atomic<bool>* stop_requested = nullptr;
};

// One half of the new branch, just off the bifurcation: a periodic orbit of `period` forcing
// periods (2q at a flip) at λ = value, free state (X, V) at section_time.
struct SwitchStart {
  double value = 0, section_time = 0;
  Eigen::VectorXd X, V;
  int period = 1;
  // +1 or −1: the sign of λ − λ* along the new branch leaving the bifurcation through this half
  // (where `vibro continue` must head to move away from it).
  int direction = 0;
  // The new orbit's contact displacement at the section minus the old orbit's there (which side
  // of the old branch this half lies on).
  double x_B_offset = 0;
  double distance = 0;  // |z_new − z_old|∞ at the same λ
};

struct SwitchResult {
  bool ok = false;
  std::string message;  // why no new branch was found (ok = false), or what was found
  double located = 0;   // λ* used (the midpoint of the two old points)
  // Both halves at a branch point; one at a flip (its two halves are one orbit, shifted by q
  // periods). Each half's section is at the old branch's section phase.
  std::vector<SwitchStart> starts;
};

SwitchResult SwitchBranch(const SwitchRequest& request);

}  // namespace vibro
