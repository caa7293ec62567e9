// Closed-form sticking flow with modal damping (docs/model.md §7): in the constrained modes of §4.2,
//   ξ̈ + D'ξ̇ + Ω'ξ = F sin(φ + ωσ)      (D' = L D V couples the modes: non-proportional damping)
// written first order, ż = G z + h sin(φ + ωσ), z = (ξ, ξ̇), G = [[0, I], [−Ω', −D']], and solved with
// the eigen-decomposition G = W Λ W⁻¹ (complex) and the forced response
// z_p = Im[(iωI − G)⁻¹ h e^{i(φ+ωσ)}]:
//   z(σ) = z_p(σ) + Re[W e^{Λσ} W⁻¹ (z(0) − z_p(0))].
// Increments from σ = 0 are formed with expm1 so that they keep relative accuracy at small σ.
// DampedStickingT<double> is the double engine's (Eigen's complex eigensolver);
// DampedStickingT<Quad> (dynamics/damped_sticking_quad.hpp) the quad engine's, its eigenpairs
// refined to 113 bits from the double ones.
#pragma once

#include <complex>

#include <Eigen/Dense>

#include "dynamics/flight_window.hpp"
#include "dynamics/root_finder.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

template <class S>
class DampedStickingT;

// A damped held flow given by its data (docs/model.md §7; several held contacts, docs/contacts.md):
// ξ̈ + damping ξ̇ + diag(ν²) ξ = modal_forcing f sin ωt, and one force
// R = R_static + ρᵀξ + ρ_vᵀξ̇ − kappa_f sin ωt.
struct DampedFlowData {
  double omega = 0, f = 0;
  Eigen::VectorXd frequencies, modal_forcing;
  Eigen::MatrixXd damping;
  double R_static = 0, kappa_f = 0;
  Eigen::VectorXd rho, rho_v;
};

template <>
class DampedStickingT<double> {
 public:
  // Sticking on contact `contact` alone (docs/contacts.md).
  explicit DampedStickingT(const System& system, int contact = 0);
  explicit DampedStickingT(const DampedFlowData& data);

  // Whether G could be diagonalised (false for a defective G, e.g. exactly critical damping).
  bool ok() const { return ok_; }

  // Start from the constrained coordinates ξ, ξ̇ at forcing phase φ.
  void Begin(const Eigen::VectorXd& xi, const Eigen::VectorXd& dxi, double phase);
  // ξ(σ), ξ̇(σ).
  void Evaluate(double sigma, Eigen::VectorXd& xi, Eigen::VectorXd& dxi) const;
  // Reaction R = R_st + ρᵀξ + ρ_vᵀξ̇ − κ f sin and its two derivatives at σ, with a bound on
  // |R'''| valid for every σ' ≥ σ (the homogeneous modes decay, Re λ ≤ 0).
  Probe ReactionProbe(double sigma) const;
  // g = base + wᵀ(ξ(σ) − ξ(0)) (another contact's gap while this one is held, base its value at
  // the start, docs/contacts.md: increments keep a gap that starts at 0 there exactly) and its two
  // derivatives at σ, with a bound on |d³g/dσ³| valid for every σ' ≥ σ, as ReactionProbe.
  Probe LinearProbe(const Eigen::VectorXd& w, double base, double sigma) const;
  // Its derivatives g', g'', g''' at σ = 0 and bounds of |g'''|, |g''''| for every σ ≥ 0 (a gap
  // that starts at zero under the held flow, docs/model.md §2.1).
  FlightJet StartJet(const Eigen::VectorXd& w) const;
  // F = base + ρᵀξ + ρ_vᵀξ̇ − kappa_f sin and its two derivatives at σ, with a bound on |F'''| for
  // every σ' ≥ σ (any functional of the same form as R: a chattering tail's deceleration).
  Probe FunctionalProbe(const Eigen::VectorXd& rho, const Eigen::VectorXd& rho_v, double base,
                        double kappa_f, double sigma) const;

 private:
  // The eigen-decomposition of G and what the probes need, from the fields set by a constructor.
  void Decompose(const Eigen::VectorXd& frequencies, const Eigen::VectorXd& modal_forcing, double f);
  // z(σ) − z(0), written with expm1 so that it keeps relative accuracy at small σ (in dz_).
  const Eigen::VectorXd& Increment(double sigma) const;

  Eigen::VectorXd w2_;        // ν²
  Eigen::MatrixXd damping_;   // D'
  bool ok_ = false;
  Eigen::Index k_ = 0;
  double omega_ = 0, kappa_f_ = 0, R_static_ = 0;
  Eigen::MatrixXd G_;
  Eigen::MatrixXcd W_, Winv_;
  Eigen::VectorXcd lambda_, q_;  // eigenvalues; forced amplitude (iωI − G)⁻¹ h
  Eigen::VectorXd rho_, rho_v_;  // R = R_st + rhoᵀξ + rho_vᵀξ̇ − κ f sin
  std::complex<double> rq_;      // (ρ, ρ_v)ᵀ q
  Eigen::VectorXcd rw_;          // (ρ, ρ_v)ᵀ W, per mode
  Eigen::VectorXd h_;            // (0, F)

  // Segment.
  double phase_ = 0, sin_phase_ = 0, cos_phase_ = 1;
  Eigen::VectorXd z0_;
  Eigen::VectorXcd c0_;  // W⁻¹ (z(0) − z_p(0))

  // The probes' vectors, kept from one probe to the next: a run makes hundreds of probes, and each
  // of these was an allocation of its own in every probe (docs/performance.md, "Start-up"). The
  // same operations in the same order. A flow serves one engine, which one thread runs at a time.
  mutable Eigen::VectorXcd e_, we_;                  // (e^{Λσ} − 1) c0, W e
  mutable Eigen::VectorXd dz_, xi_, eta_, acc_, jerk_;  // z(σ) − z(0), ξ, ξ̇, ξ̈, ξ⃛
};

using DampedSticking = DampedStickingT<double>;

}  // namespace vibro::detail
