// Damped sticking flow in closed form, quad precision (docs/model.md §7).
#include "dynamics/damped_sticking_quad.hpp"

#include <algorithm>

#include <Eigen/Eigenvalues>

namespace vibro::detail {
namespace {

using R = Real<Quad>;
using C = DampedStickingT<Quad>::C;
using CMat = DampedStickingT<Quad>::CMat;

Quad Abs(const C& z) { return R::hypot(z.real(), z.imag()); }

// e^{z} and e^{z} − 1 (without cancellation at small |z|).
C Exp(const C& z) {
  Quad s, c;
  R::sincos(z.imag(), s, c);
  const Quad e = R::exp(z.real());
  return {e * c, e * s};
}
C Expm1(const C& z) {
  Quad s, c;
  R::sincos(z.imag(), s, c);
  const Quad h = R::sin(Quad(0.5) * z.imag());
  return {R::expm1(z.real()) * c - Quad(2) * h * h, R::exp(z.real()) * s};
}

Quad MaxAbs(const CMat& A) {
  Quad m(0);
  for (Eigen::Index j = 0; j < A.cols(); ++j)
    for (Eigen::Index i = 0; i < A.rows(); ++i) m = std::max(m, Abs(A(i, j)));
  return m;
}

}  // namespace

DampedStickingT<Quad>::DampedStickingT(const System& sys, int contact) {
  const ContactModel& km = sys.contacts()[static_cast<size_t>(contact)];
  const auto& cm = km.constrained;
  k_ = cm.frequencies.size();
  // Undamped sticking needs none of this (the engine's own closed form, dynamics/oscillator.hpp).
  if (k_ == 0 || cm.damping.size() == 0 || cm.damping.cwiseAbs().maxCoeff() == 0) return;
  // The same data as the quad model (dynamics/model_t.hpp): the double structure converted exactly.
  omega_ = Quad(sys.frequency());
  const Quad f(sys.amplitude()), s_B(km.s_B);
  kappa_f_ = Quad(km.s_A) / s_B * f;
  R_static_ = Quad(km.stop) / Quad(km.flexibility);
  damping_ = cm.damping.cast<Quad>();
  const Vec nu = cm.frequencies.cast<Quad>();
  w2_ = nu.cwiseProduct(nu);
  F_ = cm.modal_forcing.cast<Quad>() * f;
  rho_ = cm.reaction.cast<Quad>();
  const Vec zeta = sys.damping().cast<Quad>(), om = sys.omega().cast<Quad>();
  const Vec D = Quad(2) * zeta.cwiseProduct(om);
  rho_v_ = cm.vectors.cast<Quad>().transpose() * km.shape.cast<Quad>().cwiseProduct(D) /
           s_B;
  Decompose(cm.frequencies, cm.damping);
}

DampedStickingT<Quad>::DampedStickingT(const DampedFlowData& d) {
  k_ = d.frequencies.size();
  if (k_ == 0 || d.damping.size() == 0 || d.damping.cwiseAbs().maxCoeff() == 0) return;
  omega_ = Quad(d.omega);
  kappa_f_ = Quad(d.kappa_f);
  R_static_ = Quad(d.R_static);
  damping_ = d.damping.cast<Quad>();
  const Vec nu = d.frequencies.cast<Quad>();
  w2_ = nu.cwiseProduct(nu);
  F_ = d.modal_forcing.cast<Quad>() * Quad(d.f);
  rho_ = d.rho.cast<Quad>();
  rho_v_ = d.rho_v.cast<Quad>();
  Decompose(d.frequencies, d.damping);
}

// The eigen-decomposition of G (refined from the double one) and what the probes need, from the
// fields a constructor set; `frequencies` and `damping` are the double data the start is made of.
void DampedStickingT<Quad>::Decompose(const Eigen::VectorXd& frequencies, const Eigen::MatrixXd& damping) {
  const Eigen::Index m = 2 * k_;
  Mat G = Mat::Zero(m, m);
  G.topRightCorner(k_, k_).setIdentity();
  G.bottomLeftCorner(k_, k_) = -Mat(w2_.asDiagonal());
  G.bottomRightCorner(k_, k_) = -damping_;
  const CMat Gc = G.cast<C>();

  // Start: the double eigen-decomposition (as DampedStickingT<double>), refused where that one is.
  Eigen::MatrixXd Gd = Eigen::MatrixXd::Zero(m, m);
  Gd.topRightCorner(k_, k_).setIdentity();
  Gd.bottomLeftCorner(k_, k_) = -Eigen::MatrixXd(frequencies.cwiseAbs2().asDiagonal());
  Gd.bottomRightCorner(k_, k_) = -damping;
  Eigen::ComplexEigenSolver<Eigen::MatrixXcd> es(Gd.cast<std::complex<double>>());
  if (es.info() != Eigen::Success) return;
  {
    Eigen::FullPivLU<Eigen::MatrixXcd> lu(es.eigenvectors());
    if (!lu.isInvertible() || lu.rcond() < 1e-10) return;  // defective (critical damping)
  }
  W_.resize(m, m);
  lambda_.resize(m);
  for (Eigen::Index j = 0; j < m; ++j) {
    lambda_[j] = C(Quad(es.eigenvalues()[j].real()), Quad(es.eigenvalues()[j].imag()));
    for (Eigen::Index i = 0; i < m; ++i)
      W_(i, j) = C(Quad(es.eigenvectors()(i, j).real()), Quad(es.eigenvectors()(i, j).imag()));
  }

  // Refinement: with E = W⁻¹ G W = Λ + Δ (Δ small off the diagonal), the eigenvalues are E_jj to
  // second order and W (I + X), X_ij = E_ij / (E_jj − E_ii) (i ≠ j), is the first-order correction
  // of the eigenvectors: quadratic convergence, from the double's 1e-16 to quad rounding in two
  // steps for separated eigenvalues.
  const Quad scale = MaxAbs(Gc);
  const Quad tiny = Quad(64) * Eps<Quad>() * scale;
  for (refinements_ = 0; refinements_ < 8; ++refinements_) {
    const CMat E = W_.partialPivLu().inverse() * (Gc * W_);
    CMat X = CMat::Zero(m, m);
    Quad off(0);
    for (Eigen::Index j = 0; j < m; ++j) {
      lambda_[j] = E(j, j);
      for (Eigen::Index i = 0; i < m; ++i) {
        if (i == j) continue;
        off = std::max(off, Abs(E(i, j)));
        const C gap = E(j, j) - E(i, i);
        if (Abs(gap) > tiny) X(i, j) = E(i, j) / gap;
      }
    }
    if (off <= tiny) break;
    W_ += W_ * X;
    // Keep the columns at unit size (their scale is free; c0 absorbs it).
    for (Eigen::Index j = 0; j < m; ++j) W_.col(j) /= C(MaxAbs(CMat(W_.col(j))));
  }
  Winv_ = W_.fullPivLu().inverse();
  residual_ = MaxAbs(CMat(Gc * W_ - W_ * lambda_.asDiagonal())) / (scale * MaxAbs(W_));
  if (!(residual_ <= Quad(1e-28))) return;  // did not refine to quad rounding

  CVec h = CVec::Zero(m);
  for (Eigen::Index k = 0; k < k_; ++k) h[k_ + k] = C(F_[k]);
  const CMat A = C(Quad(0), omega_) * CMat::Identity(m, m) - Gc;
  q_ = A.fullPivLu().solve(h);
  rq_ = C(0);
  rw_ = CVec::Zero(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const Quad r = i < k_ ? rho_[i] : rho_v_[i - k_];
    rq_ += r * q_[i];
    for (Eigen::Index j = 0; j < m; ++j) rw_[j] += r * W_(i, j);
  }
  ok_ = true;
}


void DampedStickingT<Quad>::Begin(const Vec& xi, const Vec& dxi, const Quad& phase) {
  phase_ = phase;
  z0_.resize(2 * k_);
  z0_ << xi, dxi;
  Quad sp, cp;
  R::sincos(phase, sp, cp);
  CVec d(2 * k_);
  for (Eigen::Index i = 0; i < 2 * k_; ++i)
    d[i] = C(z0_[i] - (q_[i].real() * sp + q_[i].imag() * cp));
  c0_ = Winv_ * d;
}

void DampedStickingT<Quad>::Evaluate(const Quad& sigma, Vec& xi, Vec& dxi) const {
  const Vec dz = Increment(sigma);
  xi = z0_.head(k_) + dz.head(k_);
  dxi = z0_.tail(k_) + dz.tail(k_);
}

DampedStickingT<Quad>::Vec DampedStickingT<Quad>::Increment(const Quad& sigma) const {
  Quad sp, cp;
  R::sincos(phase_, sp, cp);
  const Quad sw = R::sin(omega_ * sigma), hw = R::sin(Quad(0.5) * omega_ * sigma);
  const Quad cwm1 = Quad(-2) * hw * hw;
  const Quad dsin = sp * cwm1 + cp * sw, dcos = cp * cwm1 - sp * sw;
  CVec e(2 * k_);
  for (Eigen::Index j = 0; j < 2 * k_; ++j) e[j] = Expm1(lambda_[j] * sigma) * c0_[j];
  const CVec we = W_ * e;
  Vec dz(2 * k_);
  for (Eigen::Index i = 0; i < 2 * k_; ++i) dz[i] = q_[i].real() * dsin + q_[i].imag() * dcos + we[i].real();
  return dz;
}

ProbeT<Quad> DampedStickingT<Quad>::ReactionProbe(const Quad& sigma) const {
  Vec xi, eta;
  Evaluate(sigma, xi, eta);
  Quad s, c;
  R::sincos(phase_ + omega_ * sigma, s, c);
  const Vec acc = -w2_.cwiseProduct(xi) - damping_ * eta + F_ * s;
  const Vec jerk = -w2_.cwiseProduct(eta) - damping_ * acc + F_ * (omega_ * c);
  ProbeT<Quad> p{{Quad(0), Quad(0), Quad(0)}, Quad(0)};
  p.jet.g = R_static_ + rho_.dot(xi) + rho_v_.dot(eta) - kappa_f_ * s;
  p.jet.g1 = rho_.dot(eta) + rho_v_.dot(acc) - kappa_f_ * omega_ * c;
  p.jet.g2 = rho_.dot(acc) + rho_v_.dot(jerk) + kappa_f_ * omega_ * omega_ * s;
  // |R'''| ≤ Σ_j |ρ̃ᵀw_j| |c_j e^{λ_j σ}| |λ_j|³ + (|ρ̃ᵀq| + |κ f|) ω³, and the homogeneous
  // amplitudes only decay after σ (Re λ_j ≤ 0).
  Quad M = (Abs(rq_) + R::abs(kappa_f_)) * omega_ * omega_ * omega_;
  for (Eigen::Index j = 0; j < 2 * k_; ++j) {
    const Quad l = Abs(lambda_[j]);
    M += Abs(rw_[j]) * Abs(c0_[j] * Exp(lambda_[j] * sigma)) * l * l * l;
  }
  p.M = M * (Quad(1) + Quad(1e-9));
  return p;
}

ProbeT<Quad> DampedStickingT<Quad>::LinearProbe(const Vec& w, const Quad& base, const Quad& sigma) const {
  const Vec dz = Increment(sigma);
  const Vec xi = z0_.head(k_) + dz.head(k_), eta = z0_.tail(k_) + dz.tail(k_);
  Quad s, c;
  R::sincos(phase_ + omega_ * sigma, s, c);
  const Vec acc = -w2_.cwiseProduct(xi) - damping_ * eta + F_ * s;
  ProbeT<Quad> p{{base + w.dot(Vec(dz.head(k_))), w.dot(eta), w.dot(acc)}, Quad(0)};
  // |d³g/dσ³| ≤ Σ_j |wᵀW_j| |c_j e^{λ_j σ}| |λ_j|³ + |wᵀq| ω³ (the ξ rows of W and q).
  C wq(0);
  for (Eigen::Index i = 0; i < k_; ++i) wq += w[i] * q_[i];
  Quad M = Abs(wq) * omega_ * omega_ * omega_;
  for (Eigen::Index j = 0; j < 2 * k_; ++j) {
    C wj(0);
    for (Eigen::Index i = 0; i < k_; ++i) wj += w[i] * W_(i, j);
    const Quad l = Abs(lambda_[j]);
    M += Abs(wj) * Abs(c0_[j] * Exp(lambda_[j] * sigma)) * l * l * l;
  }
  p.M = M * (Quad(1) + Quad(1e-9));
  return p;
}

FlightJetT<Quad> DampedStickingT<Quad>::StartJet(const Vec& w) const {
  const Vec xi = z0_.head(k_), eta = z0_.tail(k_);
  Quad s, c;
  R::sincos(phase_, s, c);
  const Vec acc = -w2_.cwiseProduct(xi) - damping_ * eta + F_ * s;
  const Vec jerk = -w2_.cwiseProduct(eta) - damping_ * acc + F_ * (omega_ * c);
  FlightJetT<Quad> j{w.dot(eta), w.dot(acc), w.dot(jerk), Quad(0), Quad(0)};
  // |g^(p)| ≤ Σ_j |wᵀW_j| |c_j| |λ_j|^p + |wᵀq| ω^p for every σ ≥ 0 (Re λ_j ≤ 0).
  C wq(0);
  for (Eigen::Index i = 0; i < k_; ++i) wq += w[i] * q_[i];
  const Quad o3 = omega_ * omega_ * omega_;
  j.M3 = Abs(wq) * o3;
  j.M4 = Abs(wq) * o3 * omega_;
  for (Eigen::Index jj = 0; jj < 2 * k_; ++jj) {
    C wj(0);
    for (Eigen::Index i = 0; i < k_; ++i) wj += w[i] * W_(i, jj);
    const Quad l = Abs(lambda_[jj]), a = Abs(wj) * Abs(c0_[jj]);
    j.M3 += a * l * l * l;
    j.M4 += a * l * l * l * l;
  }
  j.M3 *= Quad(1) + Quad(1e-9);
  j.M4 *= Quad(1) + Quad(1e-9);
  return j;
}

ProbeT<Quad> DampedStickingT<Quad>::FunctionalProbe(const Vec& rho, const Vec& rho_v, const Quad& base,
                                                    const Quad& kappa_f, const Quad& sigma) const {
  Vec xi, eta;
  Evaluate(sigma, xi, eta);
  Quad s, c;
  R::sincos(phase_ + omega_ * sigma, s, c);
  const Vec acc = -w2_.cwiseProduct(xi) - damping_ * eta + F_ * s;
  const Vec jerk = -w2_.cwiseProduct(eta) - damping_ * acc + F_ * (omega_ * c);
  ProbeT<Quad> p{{base + rho.dot(xi) + rho_v.dot(eta) - kappa_f * s,
                  rho.dot(eta) + rho_v.dot(acc) - kappa_f * omega_ * c,
                  rho.dot(acc) + rho_v.dot(jerk) + kappa_f * omega_ * omega_ * s},
                 Quad(0)};
  C rq(0);
  CVec rw = CVec::Zero(2 * k_);
  for (Eigen::Index i = 0; i < 2 * k_; ++i) {
    const Quad r = i < k_ ? rho[i] : rho_v[i - k_];
    rq += r * q_[i];
    for (Eigen::Index j = 0; j < 2 * k_; ++j) rw[j] += r * W_(i, j);
  }
  Quad M = (Abs(rq) + R::abs(kappa_f)) * omega_ * omega_ * omega_;
  for (Eigen::Index j = 0; j < 2 * k_; ++j) {
    const Quad l = Abs(lambda_[j]);
    M += Abs(rw[j]) * Abs(c0_[j] * Exp(lambda_[j] * sigma)) * l * l * l;
  }
  p.M = M * (Quad(1) + Quad(1e-9));
  return p;
}

}  // namespace vibro::detail
