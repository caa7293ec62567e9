// The compliant stop's law (docs/compliant.md): a linear spring–dashpot of stiffness k and damping
// c on the gap g = c_jᵀX − e_j of contact j. While the body is in contact the contact carries
//   λ = −k g − c ġ,
// so the structure gains k T_j c_jᵀ and c T_j c_jᵀ (in the physical coordinates k w wᵀ, c w wᵀ):
//   Ẍ + (D + c T_j c_jᵀ) Ẋ + (Ω + k T_j c_jᵀ) X = T_A f sin φ + k e_j T_j,
// a linear flow with a closed form, like every phase of the model. It is written in the
// first-order form z' = A z + b(t) with A's eigenvectors (complex; a flow whose damping stays
// proportional gives the same modes, real and decoupled), so that the state, the gap, its rate and
// the force are sums of complex exponentials (dynamics/exp_sum.hpp) and their roots certified.
//
// Events of a contact phase (the automaton's mode `sticking` on a compliant contact):
//   exit, rule "gap":   g returns to 0 (the dashpot may pull: λ < 0 just before is allowed);
//   exit, rule "force": λ returns to 0 (no pulling). The surface, massless, then relaxes back,
//                       y = y₀ e^(−kσ/c) (y₀ = g at the exit), while the body flies: the flight that
//                       follows sees the gap g − y (a relaxing flight), and re-contact with the
//                       surface is an entry. Once the surface is back within the rounding of the
//                       gap the flight is an ordinary one.
//   another contact's gap reaching 0 during a contact phase or a relaxing flight: its own event.
// The loads of a phase (docs/loads.md): duration, ∫λ dt, peak force and its instant (a certified
// root of λ̇), largest penetration, energy dissipated (∫c ġ² dt, and ½k g² at a force-rule exit,
// lost as the surface relaxes).
#pragma once

#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "dynamics/exp_sum.hpp"
#include "dynamics/model_t.hpp"
#include "dynamics/propagator.hpp"

namespace vibro::detail {

// The closed form of  Ẍ + C Ẋ + K X = T_A f sin φ + b0  in the first-order form, built once.
class LinearFlow {
 public:
  using Vec = Eigen::VectorXd;
  using Mat = Eigen::MatrixXd;
  using CVec = Eigen::VectorXcd;
  using CMat = Eigen::MatrixXcd;

  // One harmonic of the forcing: T_A^(h) f_h sin(n_h φ + ψ_h), pulsation ω_h = n_h ω_b
  // (docs/harmonics.md); today's single forcing is T_A f sin φ: n = 1, ψ = 0, ω_h = ω.
  struct Term {
    Vec forcing;  // T_A^(h) f_h
    double omega = 1, psi = 0;
    int n = 1;
  };

  // Returns an empty string when built, else why not (a defective or ill-conditioned A, a
  // forcing at a resonance of the undamped flow).
  std::string Build(const Mat& K, const Mat& C, const std::vector<Term>& terms, const Vec& b0) {
    const Eigen::Index n = K.rows();
    n_ = n;
    Mat A = Mat::Zero(2 * n, 2 * n);
    A.topRightCorner(n, n) = Mat::Identity(n, n);
    A.bottomLeftCorner(n, n) = -K;
    A.bottomRightCorner(n, n) = -C;
    Eigen::EigenSolver<Mat> es(A);
    if (es.info() != Eigen::Success) return "the eigenvalues of the contact phase's flow did not converge";
    lambda_ = es.eigenvalues();
    P_ = es.eigenvectors();
    Eigen::PartialPivLU<CMat> lu(P_);
    Pinv_ = lu.inverse();
    const double cond = P_.cwiseAbs().rowwise().sum().maxCoeff() * Pinv_.cwiseAbs().rowwise().sum().maxCoeff();
    if (!(cond < 1e8))
      return fmt::format(
          "the contact phase's flow is (nearly) defective (eigenvector condition {:.3g}: a contact "
          "damping at or near the critical value); move the stiffness or the damping",
          cond);
    // Static part: K X_s = b0.
    Xs_ = K.fullPivLu().solve(b0);
    // Harmonic part, one per harmonic: (K − ω_h² I + iω_h C) H_h = T_A^(h) f_h.
    harmonics_.clear();
    for (const Term& t : terms) {
      if (t.forcing.norm() == 0) continue;
      const double w = t.omega;
      CMat Z = K.cast<std::complex<double>>() - (w * w) * CMat::Identity(n, n) +
               std::complex<double>(0, w) * C.cast<std::complex<double>>();
      Eigen::FullPivLU<CMat> zlu(Z);
      if (zlu.rank() < n)
        return terms.size() > 1 ? fmt::format("the harmonic at ω = {} is a resonance of the undamped contact phase", w)
                                : std::string("the forcing frequency is a resonance of the undamped contact phase");
      harmonics_.push_back({zlu.solve(t.forcing.cast<std::complex<double>>()), w, t.psi, t.n});
    }
    return "";
  }

  // The flow from (X0, V0) at forcing phase φ0: coefficients of each mode.
  // φ_h = n_h φ + ψ_h at σ = 0 (exactly φ for today's single harmonic).
  void Begin(double phase, const Vec& X0, const Vec& V0) {
    phase_.clear();
    for (const Harmonic& h : harmonics_) phase_.push_back(h.n == 1 && h.psi == 0 ? phase : h.n * phase + h.psi);
    // X_p(0) = X_s + Σ_h Im(H_h e^{iφ_h}); V_p(0) = Σ_h Im(iω_h H_h e^{iφ_h}).
    CVec z(2 * n_);
    for (Eigen::Index i = 0; i < n_; ++i) {
      z[i] = X0[i] - Xs_[i];
      z[n_ + i] = V0[i];
    }
    for (size_t k = 0; k < harmonics_.size(); ++k) {
      const Harmonic& hk = harmonics_[k];
      const std::complex<double> e(std::cos(phase_[k]), std::sin(phase_[k]));
      for (Eigen::Index i = 0; i < n_; ++i) {
        const std::complex<double> h = hk.H[i] * e;
        z[i] -= h.imag();
        z[n_ + i] -= (std::complex<double>(0, hk.omega) * h).imag();
      }
    }
    a_ = Pinv_ * z;
  }
  // The state at σ.
  void Evaluate(double s, Vec& X, Vec& V) const {
    CVec c(2 * n_);
    for (Eigen::Index k = 0; k < 2 * n_; ++k) c[k] = a_[k] * std::exp(lambda_[k] * s);
    const CVec z = P_ * c;
    X = Xs_;
    V = Vec::Zero(n_);
    for (size_t k = 0; k < harmonics_.size(); ++k) {
      const Harmonic& hk = harmonics_[k];
      const std::complex<double> e(std::cos(phase_[k] + hk.omega * s), std::sin(phase_[k] + hk.omega * s));
      for (Eigen::Index i = 0; i < n_; ++i) {
        const std::complex<double> h = hk.H[i] * e;
        X[i] += h.imag();
        V[i] += (std::complex<double>(0, hk.omega) * h).imag();
      }
    }
    for (Eigen::Index i = 0; i < n_; ++i) {
      X[i] += z[i].real();
      V[i] += z[n_ + i].real();
    }
  }
  // uᵀX(σ) − offset as a sum of exponentials (a gap: u = c_j, offset = e_j).
  ExpSum Linear(const Vec& u, double offset) const {
    ExpSum F;
    for (Eigen::Index k = 0; k < 2 * n_; ++k) {
      std::complex<double> b(0, 0);
      for (Eigen::Index i = 0; i < n_; ++i) b += u[i] * P_(i, k);
      if (std::abs(b * a_[k]) > 0) F.Add(b * a_[k], lambda_[k]);
    }
    F.Add(u.dot(Xs_) - offset, 0.0);
    // Im(h e^{i(φ_h+ω_hσ)}) = Re(−i h e^{iφ_h} e^{iω_hσ}): one term per harmonic, its real part is the sum.
    for (size_t k = 0; k < harmonics_.size(); ++k) {
      std::complex<double> h(0, 0);
      for (Eigen::Index i = 0; i < n_; ++i) h += u[i] * harmonics_[k].H[i];
      if (std::abs(h) > 0) {
        const std::complex<double> e(std::cos(phase_[k]), std::sin(phase_[k]));
        F.Add(std::complex<double>(0, -1) * h * e, std::complex<double>(0, harmonics_[k].omega));
      }
    }
    return F;
  }
  // The derivative of a sum made by Linear (each term times its exponent).
  static ExpSum Rate(const ExpSum& F) {
    ExpSum D;
    for (size_t i = 0; i < F.B.size(); ++i)
      if (F.mu[i] != 0.0) D.Add(F.B[i] * F.mu[i], F.mu[i]);
    return D;
  }
  const Eigen::VectorXcd& eigenvalues() const { return lambda_; }

 private:
  struct Harmonic {
    CVec H;  // (K − ω_h² I + iω_h C)⁻¹ T_A^(h) f_h
    double omega, psi;
    int n;
  };
  Eigen::Index n_ = 0;
  std::vector<Harmonic> harmonics_;
  std::vector<double> phase_;  // φ_h at σ = 0
  CVec lambda_;
  CMat P_, Pinv_;
  Vec Xs_;
  CVec a_;
};

// What the automaton asks of a compliant contact's propagator (dynamics/compliant_transitions.hpp),
// whichever engine runs it: the closed form below (the exact engine), or CVODE's integration of the
// same spring–dashpot law (dynamics/cvode_engine.hpp, `vibro check`'s second opinion). It runs the
// contact phase (mode sticking) and the relaxing flight after a force-rule exit (mode free), over
// every contact's gap, and gives the phase's loads.
class CompliantPhase : public PropagatorT<double> {
 public:
  // The contact phase's loads over [0, σ] of the last segment (docs/loads.md): ∫λ dt, the
  // dashpot's ∫c ġ² dt, and the largest force and penetration with their instants.
  struct PhaseLoads {
    double integral = 0, dissipated = 0;
    double peak = -std::numeric_limits<double>::infinity(), peak_at = 0;
    double penetration = 0, penetration_at = 0;
  };

  // Empty when the propagator is ready, else why not (the run fails with it).
  const std::string& error() const { return error_; }
  // The relaxing surface of a force-rule exit: its offset y₀ (≤ 0) at the start of the next segment.
  // at_exit: the flight starts at the exit itself (the gap to the surface has a double zero there).
  void SetSurface(double y0, bool at_exit = false) {
    y0_ = y0;
    at_exit_ = at_exit;
  }
  double SurfaceAt(double s) const { return y0_ == 0 ? 0.0 : y0_ * std::exp(-stiffness_ / damping_ * s); }
  // A relaxing flight's last segment ended because the surface is back (within the gap's rounding).
  bool relaxed() const { return relaxed_; }
  virtual PhaseLoads Loads(double sigma) const = 0;

 protected:
  CompliantPhase(double stiffness, double damping) : stiffness_(stiffness), damping_(damping) {}
  // The local time after which the relaxing surface is back within the rounding of a gap of
  // `scale` (the end of a relaxing flight).
  double RelaxedAfter(double scale) const {
    const double tol = 8 * std::numeric_limits<double>::epsilon() * (scale + 1.0);
    return damping_ / stiffness_ * std::log(std::abs(y0_) / tol);
  }

  double stiffness_, damping_;
  std::string error_;
  double y0_ = 0;
  bool relaxed_ = false, at_exit_ = false;
};

// The propagator of a compliant contact (docs/compliant.md): the contact phase (mode sticking)
// and the relaxing flight after a force-rule exit (mode free), over every contact's gap.
class CompliantPropagator final : public CompliantPhase {
 public:
  using Vec = Eigen::VectorXd;
  using Mat = Eigen::MatrixXd;

  // `contact`: the compliant contact j; `models`: every contact's model (their gaps are watched).
  CompliantPropagator(const std::vector<const ModelT<double>*>& models, int contact)
      : CompliantPhase(models[static_cast<size_t>(contact)]->stiffness, models[static_cast<size_t>(contact)]->damping),
        models_(models),
        j_(contact),
        m_(*models[static_cast<size_t>(contact)]) {
    const Eigen::Index n = m_.dof();
    Mat K = m_.omega.cwiseAbs2().asDiagonal();
    Mat D = (2.0 * m_.zeta.cwiseProduct(m_.omega)).asDiagonal();
    const Vec zero = Vec::Zero(n);
    // The forcing: today's T_A f sin φ, or a sum of harmonics (ModelT's f is then 0).
    std::vector<LinearFlow::Term> terms;
    if (m_.harmonics.empty()) {
      terms.push_back({m_.forcing * m_.f, m_.w, 0.0, 1});
    } else {
      for (const auto& h : m_.harmonics.h) terms.push_back({h.forcing, h.omega, h.psi, h.n});
    }
    error_ = free_.Build(K, D, terms, zero);
    const double k = m_.stiffness, c = m_.damping;
    Mat Kc = K + k * m_.contact * m_.shape.transpose();
    Mat Cc = D + c * m_.contact * m_.shape.transpose();
    if (error_.empty()) error_ = contact_.Build(Kc, Cc, terms, k * m_.x0 * m_.contact);
  }
  void Begin(const SegmentStartT<double>& s) override {
    mode_ = s.mode;
    phase_ = s.phase;
    relaxed_ = false;
    LinearFlow& flow = mode_ == Mode::kFree ? free_ : contact_;
    flow.Begin(s.phase, s.X, s.V);
    gaps_.clear();
    for (const ModelT<double>* m : models_) gaps_.push_back(flow.Linear(m->shape, m->x0));
    ExpSum& g = gaps_[static_cast<size_t>(j_)];
    if (mode_ == Mode::kFree && y0_ != 0) g.Add(-y0_, -m_.stiffness / m_.damping);  // the gap to the surface
    rate_ = LinearFlow::Rate(g);
    // λ = −k g − c ġ (contact phase).
    force_ = ExpSum{};
    force_.Append(g, -m_.stiffness);
    force_.Append(rate_, -m_.damping);
    scale_ = std::abs(m_.x0) + m_.shape.cwiseProduct(s.X).cwiseAbs().sum();
  }

  SegmentResultT<double> Advance(double sigma_max, bool detect, const StretchCallbackT<double>& cb) override {
    double end = sigma_max;
    SegmentEnd why = SegmentEnd::kLimit;
    int who = j_;
    if (mode_ == Mode::kFree && y0_ != 0) {
      // The surface is back within the rounding of the gap after this time: an ordinary flight.
      const double back = RelaxedAfter(scale_);
      if (back < end) {
        end = std::max(back, 0.0);
        relaxed_ = true;
      }
    }
    if (detect) {
      // The exit of the phase (or the re-contact of a relaxing flight): the compliant contact's root.
      ExpSum exit;
      if (mode_ == Mode::kFree) exit = gaps_[static_cast<size_t>(j_)];
      else if (m_.separation == Separation::kGap || m_.damping == 0) exit.Append(gaps_[static_cast<size_t>(j_)], -1.0);
      else exit = force_;
      const bool watch_own = mode_ == Mode::kSticking || y0_ != 0;
      if (watch_own) {
        const ExpRoot r = FirstExpRoot(exit, end, ForceScale(exit), mode_ == Mode::kFree && at_exit_);
        if (r.found && r.sigma <= end) {
          end = r.sigma;
          why = mode_ == Mode::kFree ? SegmentEnd::kContact : SegmentEnd::kRelease;
          relaxed_ = false;
        }
      }
      for (size_t k = 0; k < gaps_.size(); ++k) {
        if (static_cast<int>(k) == j_) continue;
        const ExpRoot r = FirstExpRoot(gaps_[k], end, scale_);
        if (r.found && r.sigma < end) {
          end = r.sigma;
          why = SegmentEnd::kContact;
          who = static_cast<int>(k);
          relaxed_ = false;
        }
      }
    }
    last_ = end;
    at_exit_ = false;
    if (cb) cb(0.0, end);
    SegmentResultT<double> res{why, end, {}};
    res.contact = who;
    return res;
  }

  void Evaluate(double s, Vec& X, Vec& V) const override {
    (mode_ == Mode::kFree ? free_ : contact_).Evaluate(s, X, V);
  }
  double Gap(double s) const override { return gaps_[static_cast<size_t>(j_)].Value(s); }
  double GapOf(int j, double s) const override { return gaps_[static_cast<size_t>(j)].Value(s); }

  // Certified: the roots of λ̇ and ġ where they fall, by the same stepping, then the ends.
  PhaseLoads Loads(double sigma) const override {
    PhaseLoads L;
    L.integral = force_.Integral(sigma);
    L.dissipated = m_.damping * ExpSum::IntegralOfProduct(rate_, rate_, sigma);
    const ExpSum& g = gaps_[static_cast<size_t>(j_)];
    Maximum(force_, sigma, L.peak, L.peak_at);
    ExpSum pen;
    pen.Append(g, -1.0);
    Maximum(pen, sigma, L.penetration, L.penetration_at);
    return L;
  }
  double ForceAt(double s) const { return force_.Value(s); }
  double GapRateAt(double s) const { return rate_.Value(s); }

 private:
  // max of F over [0, σ]: its ends and every interior root of F' where F' goes from + to −.
  void Maximum(const ExpSum& F, double sigma, double& best, double& at) const {
    best = F.Value(0.0);
    at = 0;
    const double e = F.Value(sigma);
    if (e > best) {
      best = e;
      at = sigma;
    }
    ExpSum D = LinearFlow::Rate(F);
    double u = 0;
    const double scale = ForceScale(D);
    for (int guard = 0; guard < 10000 && u < sigma; ++guard) {
      const double d = D.Value(u);
      ExpSum S;
      S.Append(D, d >= 0 ? 1.0 : -1.0);
      // Shifted to start at u: B e^{μ(u+t)}.
      for (size_t i = 0; i < S.B.size(); ++i) S.B[i] *= std::exp(S.mu[i] * u);
      const ExpRoot r = FirstExpRoot(S, sigma - u, scale);
      if (!r.found) break;
      double t = u + r.sigma;
      if (d >= 0) {
        // A maximum near t: Newton on F' from the certified point below the root.
        for (int it = 0; it < 4; ++it) {
          const JetT<double> jj = F.Jet(t, 1);
          if (!(jj.g1 < 0)) break;
          const double nt = t - jj.g / jj.g1;
          if (!(nt >= u && nt <= sigma)) break;
          t = nt;
        }
        const double v = F.Value(t);
        if (v > best) {
          best = v;
          at = t;
        }
      }
      const double step = std::max(t - u, 16 * std::numeric_limits<double>::epsilon() * std::max(t, 1e-300));
      u = std::max(u + step, t + 16 * std::numeric_limits<double>::epsilon() * std::max(t, 1e-300));
    }
  }
  static double ForceScale(const ExpSum& F) {
    double s = 0;
    for (const auto& b : F.B) s += std::abs(b);
    return s;
  }

  std::vector<const ModelT<double>*> models_;
  int j_;
  const ModelT<double>& m_;
  LinearFlow free_, contact_;
  Mode mode_ = Mode::kSticking;
  double phase_ = 0, last_ = 0, scale_ = 1;
  std::vector<ExpSum> gaps_;
  ExpSum rate_, force_;
};

}  // namespace vibro::detail
