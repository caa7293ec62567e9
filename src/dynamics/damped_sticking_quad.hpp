// The damped sticking flow of docs/model.md §7 in 113-bit quad precision, for the quad engine
// (run.precision = "quad"): the same closed form as DampedStickingT<double> (dynamics/
// damped_sticking.hpp),
//   z(σ) = z_p(σ) + Re[W e^{Λσ} W⁻¹ (z(0) − z_p(0))],   z_p = Im[(iωI − G)⁻¹ h e^{i(φ+ωσ)}],
// with the complex eigenpairs of G = [[0, I], [−Ω', −D']] taken from the double eigensolver and
// refined in quad until G W = W Λ holds to quad rounding (see Refine in the .cpp). Only the
// translation units that instantiate the quad engine include this header.
#pragma once

#include <complex>

#include <Eigen/Dense>

#include "dynamics/damped_sticking.hpp"
#include "dynamics/quad.hpp"
#include "dynamics/root_finder.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

template <>
class DampedStickingT<Quad> {
 public:
  using Vec = Eigen::Matrix<Quad, Eigen::Dynamic, 1>;
  using Mat = Eigen::Matrix<Quad, Eigen::Dynamic, Eigen::Dynamic>;
  using C = std::complex<Quad>;
  using CVec = Eigen::Matrix<C, Eigen::Dynamic, 1>;
  using CMat = Eigen::Matrix<C, Eigen::Dynamic, Eigen::Dynamic>;

  explicit DampedStickingT(const System& system, int contact = 0);
  explicit DampedStickingT(const DampedFlowData& data);

  // Whether G could be diagonalised to quad rounding (false for a defective G, e.g. exactly
  // critical damping, or eigenpairs that would not refine).
  bool ok() const { return ok_; }

  void Begin(const Vec& xi, const Vec& dxi, const Quad& phase);
  // ξ(σ), ξ̇(σ).
  void Evaluate(const Quad& sigma, Vec& xi, Vec& dxi) const;
  // R and its two derivatives at σ, with a bound on |R'''| valid for every σ' ≥ σ.
  ProbeT<Quad> ReactionProbe(const Quad& sigma) const;
  // g = base + wᵀξ and its two derivatives, with a bound on |d³g/dσ³| (as the double twin's).
  ProbeT<Quad> LinearProbe(const Vec& w, const Quad& base, const Quad& sigma) const;
  // Its derivatives g', g'', g''' at σ = 0 and bounds of |g'''|, |g''''| for every σ ≥ 0.
  FlightJetT<Quad> StartJet(const Vec& w) const;
  // F = base + ρᵀξ + ρ_vᵀξ̇ − kappa_f sin, as the double twin's.
  ProbeT<Quad> FunctionalProbe(const Vec& rho, const Vec& rho_v, const Quad& base, const Quad& kappa_f,
                               const Quad& sigma) const;

  // The refined decomposition, for tests: eigenvalues λ_j, and the residual
  // max |G W − W Λ| / (max|G| · max|W|) after refinement (of the order of the quad rounding unit).
  const CVec& eigenvalues() const { return lambda_; }
  Quad residual() const { return residual_; }
  int refinements() const { return refinements_; }

 private:
  void Decompose(const Eigen::VectorXd& frequencies, const Eigen::MatrixXd& damping);
  Vec Increment(const Quad& sigma) const;  // z(σ) − z(0)

  bool ok_ = false;
  Eigen::Index k_ = 0;
  Quad omega_{0}, kappa_f_{0}, R_static_{0};
  Mat damping_;   // D'
  Vec w2_, F_;    // ω'², modal forcing amplitude
  CMat W_, Winv_;
  CVec lambda_, q_;  // eigenvalues; forced amplitude (iωI − G)⁻¹ h
  Vec rho_, rho_v_;  // R = R_st + ρᵀξ + ρ_vᵀξ̇ − κ f sin
  C rq_;             // (ρ, ρ_v)ᵀ q
  CVec rw_;          // (ρ, ρ_v)ᵀ W, per mode
  Quad residual_{0};
  int refinements_ = 0;

  // Segment.
  Quad phase_{0};
  Vec z0_;
  CVec c0_;  // W⁻¹ (z(0) − z_p(0))
};

}  // namespace vibro::detail
