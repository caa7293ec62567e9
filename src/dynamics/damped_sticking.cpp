// Damped sticking flow in closed form (docs/model.md §7).
#include "dynamics/damped_sticking.hpp"

#include <cmath>

namespace vibro::detail {
namespace {

// e^{λσ} − 1 without cancellation at small σ.
std::complex<double> Expm1(std::complex<double> z) {
  const double a = z.real(), b = z.imag();
  const double h = std::sin(0.5 * b);
  return {std::expm1(a) * std::cos(b) - 2.0 * h * h, std::exp(a) * std::sin(b)};
}

}  // namespace

DampedStickingT<double>::DampedStickingT(const System& sys, int contact) {
  const ContactModel& km = sys.contacts()[static_cast<size_t>(contact)];
  const auto& cm = km.constrained;
  k_ = cm.frequencies.size();
  if (k_ == 0) return;
  omega_ = sys.frequency();
  kappa_f_ = km.s_A / km.s_B * sys.amplitude();
  R_static_ = km.stop / km.flexibility;
  damping_ = cm.damping;
  rho_ = cm.reaction;
  const Eigen::VectorXd D = 2.0 * sys.damping().cwiseProduct(sys.omega());
  rho_v_ = cm.vectors.transpose() * km.shape.cwiseProduct(D) / km.s_B;
  Decompose(cm.frequencies, cm.modal_forcing, sys.amplitude());
}

DampedStickingT<double>::DampedStickingT(const DampedFlowData& d) {
  k_ = d.frequencies.size();
  if (k_ == 0) return;
  omega_ = d.omega;
  kappa_f_ = d.kappa_f;
  R_static_ = d.R_static;
  damping_ = d.damping;
  rho_ = d.rho;
  rho_v_ = d.rho_v;
  Decompose(d.frequencies, d.modal_forcing, d.f);
}

void DampedSticking::Decompose(const Eigen::VectorXd& frequencies, const Eigen::VectorXd& modal_forcing,
                               double f) {
  w2_ = frequencies.cwiseAbs2();
  G_ = Eigen::MatrixXd::Zero(2 * k_, 2 * k_);
  G_.topRightCorner(k_, k_).setIdentity();
  G_.bottomLeftCorner(k_, k_) = -Eigen::MatrixXd(w2_.asDiagonal());
  G_.bottomRightCorner(k_, k_) = -damping_;
  Eigen::ComplexEigenSolver<Eigen::MatrixXcd> es(G_.cast<std::complex<double>>());
  if (es.info() != Eigen::Success) return;
  W_ = es.eigenvectors();
  lambda_ = es.eigenvalues();
  Eigen::FullPivLU<Eigen::MatrixXcd> lu(W_);
  if (!lu.isInvertible() || lu.rcond() < 1e-10) return;  // defective (critical damping)
  Winv_ = lu.inverse();
  h_ = Eigen::VectorXd::Zero(2 * k_);
  h_.tail(k_) = modal_forcing * f;
  const std::complex<double> iw(0.0, omega_);
  const Eigen::MatrixXcd A =
      iw * Eigen::MatrixXcd::Identity(2 * k_, 2 * k_) - G_.cast<std::complex<double>>();
  q_ = A.fullPivLu().solve(h_.cast<std::complex<double>>());
  e_.resize(2 * k_);
  Eigen::VectorXd rt(2 * k_);
  rt << rho_, rho_v_;
  rq_ = rt.cast<std::complex<double>>().dot(q_);  // dot conjugates its first argument: rt is real
  rw_ = (rt.transpose().cast<std::complex<double>>() * W_).transpose();
  ok_ = true;
}

void DampedSticking::Begin(const Eigen::VectorXd& xi, const Eigen::VectorXd& dxi, double phase) {
  phase_ = phase;
  sin_phase_ = std::sin(phase);
  cos_phase_ = std::cos(phase);
  z0_.resize(2 * k_);
  z0_ << xi, dxi;
  const Eigen::VectorXd zp0 = q_.real() * sin_phase_ + q_.imag() * cos_phase_;
  c0_ = Winv_ * (z0_ - zp0).cast<std::complex<double>>();
}

void DampedSticking::Evaluate(double sigma, Eigen::VectorXd& xi, Eigen::VectorXd& dxi) const {
  const Eigen::VectorXd& dz = Increment(sigma);
  xi = z0_.head(k_) + dz.head(k_);
  dxi = z0_.tail(k_) + dz.tail(k_);
}

const Eigen::VectorXd& DampedSticking::Increment(double sigma) const {
  const double sp = sin_phase_, cp = cos_phase_;
  const double sw = std::sin(omega_ * sigma), hw = std::sin(0.5 * omega_ * sigma);
  const double cwm1 = -2.0 * hw * hw;
  const double dsin = sp * cwm1 + cp * sw, dcos = cp * cwm1 - sp * sw;
  for (Eigen::Index j = 0; j < 2 * k_; ++j) e_[j] = Expm1(lambda_[j] * sigma) * c0_[j];
  we_.noalias() = W_ * e_;
  dz_ = q_.real() * dsin + q_.imag() * dcos + we_.real();
  return dz_;
}

Probe DampedSticking::ReactionProbe(double sigma) const {
  Eigen::VectorXd &xi = xi_, &eta = eta_, &acc = acc_, &jerk = jerk_;
  Evaluate(sigma, xi, eta);
  const double psi = phase_ + omega_ * sigma;
  const double s = std::sin(psi), c = std::cos(psi);
  const auto F = h_.tail(k_);  // views, not copies: the same values, two allocations fewer per probe
  // a = −ν²ξ − D'ξ̇ + F s and j = −ν²ξ̇ − D'a + F ω c, each product D'v formed in the vector that
  // then takes the sum (Eigen would form it in a temporary of its own: the same values).
  acc.noalias() = damping_ * eta;
  acc = -w2_.cwiseProduct(xi) - acc + F * s;
  jerk.noalias() = damping_ * acc;
  jerk = -w2_.cwiseProduct(eta) - jerk + F * (omega_ * c);
  Probe p{};
  p.jet.g = R_static_ + rho_.dot(xi) + rho_v_.dot(eta) - kappa_f_ * s;
  p.jet.g1 = rho_.dot(eta) + rho_v_.dot(acc) - kappa_f_ * omega_ * c;
  p.jet.g2 = rho_.dot(acc) + rho_v_.dot(jerk) + kappa_f_ * omega_ * omega_ * s;
  // |R'''| ≤ Σ_j |ρ̃ᵀw_j| |c_j e^{λ_j σ}| |λ_j|³ + (|ρ̃ᵀq| + |κ f|) ω³, and the homogeneous
  // amplitudes only decay after σ.
  double M = (std::abs(rq_) + std::abs(kappa_f_)) * omega_ * omega_ * omega_;
  for (Eigen::Index j = 0; j < 2 * k_; ++j) {
    const double l = std::abs(lambda_[j]);
    M += std::abs(rw_[j]) * std::abs(c0_[j] * std::exp(lambda_[j] * sigma)) * l * l * l;
  }
  p.M = M * (1.0 + 1e-9);
  return p;
}

Probe DampedSticking::LinearProbe(const Eigen::VectorXd& w, double base, double sigma) const {
  const Eigen::VectorXd& dz = Increment(sigma);
  Eigen::VectorXd &xi = xi_, &eta = eta_, &acc = acc_;  // as in ReactionProbe
  xi = z0_.head(k_) + dz.head(k_);
  eta = z0_.tail(k_) + dz.tail(k_);
  const double s = std::sin(phase_ + omega_ * sigma);
  const auto F = h_.tail(k_);
  acc.noalias() = damping_ * eta;
  acc = -w2_.cwiseProduct(xi) - acc + F * s;
  Probe p{};
  p.jet.g = base + w.dot(dz.head(k_));
  p.jet.g1 = w.dot(eta);
  p.jet.g2 = w.dot(acc);
  // |d³g/dσ³| ≤ Σ_j |wᵀW_j| |c_j e^{λ_j σ}| |λ_j|³ + |wᵀq| ω³ (the ξ rows of W and q).
  const Eigen::VectorXcd ww = (w.transpose().cast<std::complex<double>>() * W_.topRows(k_)).transpose();
  const std::complex<double> wq = w.cast<std::complex<double>>().dot(q_.head(k_));
  double M = std::abs(wq) * omega_ * omega_ * omega_;
  for (Eigen::Index j = 0; j < 2 * k_; ++j) {
    const double l = std::abs(lambda_[j]);
    M += std::abs(ww[j]) * std::abs(c0_[j] * std::exp(lambda_[j] * sigma)) * l * l * l;
  }
  p.M = M * (1.0 + 1e-9);
  return p;
}

FlightJet DampedSticking::StartJet(const Eigen::VectorXd& w) const {
  const Eigen::VectorXd xi = z0_.head(k_), eta = z0_.tail(k_);
  const auto F = h_.tail(k_);
  Eigen::VectorXd acc = damping_ * eta;  // as in ReactionProbe
  acc = -w2_.cwiseProduct(xi) - acc + F * std::sin(phase_);
  Eigen::VectorXd jerk = damping_ * acc;
  jerk = -w2_.cwiseProduct(eta) - jerk + F * (omega_ * std::cos(phase_));
  FlightJet j{w.dot(eta), w.dot(acc), w.dot(jerk), 0.0, 0.0};
  // |g^(p)| ≤ Σ_j |wᵀW_j| |c_j| |λ_j|^p + |wᵀq| ω^p for every σ ≥ 0 (Re λ_j ≤ 0).
  const Eigen::VectorXcd ww = (w.transpose().cast<std::complex<double>>() * W_.topRows(k_)).transpose();
  const double wq = std::abs(w.cast<std::complex<double>>().dot(q_.head(k_)));
  j.M3 = wq * std::pow(omega_, 3);
  j.M4 = wq * std::pow(omega_, 4);
  for (Eigen::Index i = 0; i < 2 * k_; ++i) {
    const double l = std::abs(lambda_[i]), a = std::abs(ww[i]) * std::abs(c0_[i]);
    j.M3 += a * l * l * l;
    j.M4 += a * l * l * l * l;
  }
  j.M3 *= 1.0 + 1e-9;
  j.M4 *= 1.0 + 1e-9;
  return j;
}

Probe DampedSticking::FunctionalProbe(const Eigen::VectorXd& rho, const Eigen::VectorXd& rho_v,
                                      double base, double kappa_f, double sigma) const {
  Eigen::VectorXd &xi = xi_, &eta = eta_, &acc = acc_, &jerk = jerk_;  // as in ReactionProbe
  Evaluate(sigma, xi, eta);
  const double psi = phase_ + omega_ * sigma;
  const double s = std::sin(psi), c = std::cos(psi);
  const auto F = h_.tail(k_);
  // a = −ν²ξ − D'ξ̇ + F s and j = −ν²ξ̇ − D'a + F ω c, each product D'v formed in the vector that
  // then takes the sum (Eigen would form it in a temporary of its own: the same values).
  acc.noalias() = damping_ * eta;
  acc = -w2_.cwiseProduct(xi) - acc + F * s;
  jerk.noalias() = damping_ * acc;
  jerk = -w2_.cwiseProduct(eta) - jerk + F * (omega_ * c);
  Probe p{};
  p.jet.g = base + rho.dot(xi) + rho_v.dot(eta) - kappa_f * s;
  p.jet.g1 = rho.dot(eta) + rho_v.dot(acc) - kappa_f * omega_ * c;
  p.jet.g2 = rho.dot(acc) + rho_v.dot(jerk) + kappa_f * omega_ * omega_ * s;
  Eigen::VectorXd rt(2 * k_);
  rt << rho, rho_v;
  const Eigen::VectorXcd rw = (rt.transpose().cast<std::complex<double>>() * W_).transpose();
  double M = (std::abs(rt.cast<std::complex<double>>().dot(q_)) + std::abs(kappa_f)) * std::pow(omega_, 3);
  for (Eigen::Index j = 0; j < 2 * k_; ++j) {
    const double l = std::abs(lambda_[j]);
    M += std::abs(rw[j]) * std::abs(c0_[j] * std::exp(lambda_[j] * sigma)) * l * l * l;
  }
  p.M = M * (1.0 + 1e-9);
  return p;
}

}  // namespace vibro::detail
