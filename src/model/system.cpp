// Structural model: modal data in the paper's scaling (docs/model.md §1.3) and the constrained modes
// (docs/model.md §4.2).
#include "vibro/system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace vibro {
namespace {

// A mode whose B component is below this fraction of its largest component has a node at B.
constexpr double kNodeTolerance = 1e-10;

}  // namespace

std::vector<int> System::KeptModes(const Eigen::VectorXd& omega, int keep) {
  std::vector<int> order(static_cast<size_t>(omega.size()));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return omega[a] < omega[b]; });
  if (keep > 0 && keep < static_cast<int>(order.size())) order.resize(static_cast<size_t>(keep));
  return order;
}

System::System(const Scene& scene) {
  x0_ = scene.stop_position;
  r_ = scene.restitution;
  // [[contact]] tables: contact 0 takes the place of the [stop] (e_0 = σ_0 d_0).
  const ContactSpec* first = scene.contacts.empty() ? nullptr : &scene.contacts.front();
  const double sigma0 = first && first->side == Side::kAbove ? -1.0 : 1.0;
  if (first) {
    x0_ = sigma0 * first->position;
    r_ = first->restitution;
  }
  f_ = scene.amplitude;
  w_ = scene.frequency;
  period_ = 2.0 * M_PI / w_;

  Eigen::VectorXd zeta_all;
  if (scene.modal) {
    const auto& m = *scene.modal;
    const auto keep = KeptModes(m.frequencies, scene.modes);
    kept_ = keep;
    const auto n = static_cast<Eigen::Index>(keep.size());
    omega_.resize(n);
    forcing_.resize(n);
    contact_.resize(n);
    zeta_ = Eigen::VectorXd::Zero(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      omega_[i] = m.frequencies[keep[static_cast<size_t>(i)]];
      forcing_[i] = m.forcing[keep[static_cast<size_t>(i)]];
      contact_[i] = m.contact[keep[static_cast<size_t>(i)]];
      if (scene.damping_ratios.size() > 0) zeta_[i] = scene.damping_ratios[keep[static_cast<size_t>(i)]];
    }
    shape_ = Eigen::VectorXd::Ones(n);
  } else if (scene.physical) {
    physical_ = true;
    const auto& p = *scene.physical;
    mass_ = p.mass;
    // docs/model.md §1.3 step 1: K φ = λ M φ (φᵀMφ = 1).
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(p.stiffness, p.mass);
    if (eig.info() != Eigen::Success) throw std::invalid_argument("eigenproblem K φ = λ M φ failed");
    const Eigen::VectorXd lambda = eig.eigenvalues();
    const Eigen::VectorXd all_omega = lambda.cwiseMax(0.0).cwiseSqrt();
    const auto keep = KeptModes(all_omega, scene.modes);
    const auto n = static_cast<Eigen::Index>(keep.size());
    const auto N = p.mass.rows();
    omega_.resize(n);
    forcing_.resize(n);
    contact_.resize(n);
    shape_.resize(n);
    zeta_ = Eigen::VectorXd::Zero(n);
    mode_shapes_.resize(N, n);
    modal_masses_.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const int k = keep[static_cast<size_t>(i)];
      Eigen::VectorXd phi = eig.eigenvectors().col(k);
      omega_[i] = all_omega[k];
      if (scene.damping_ratios.size() > 0) zeta_[i] = scene.damping_ratios[k];
      // The component the first contact sees, σ_0 w_0ᵀφ (w_0 = e_B for a [stop]).
      double phiB = 0;
      if (!first) {
        phiB = phi[p.contact_dof];
      } else {
        phiB = phi[first->dof];
        if (first->partner >= 0) phiB -= phi[first->partner];
        phiB *= sigma0;
      }
      if (std::abs(phiB) > kNodeTolerance * phi.cwiseAbs().maxCoeff()) {
        // Step 2-3: unit component at B, T_A = ψ(A)/m, T_B = 1/m.
        const Eigen::VectorXd psi = phi / phiB;
        const double m_i = psi.dot(p.mass * psi);
        mode_shapes_.col(i) = psi;
        modal_masses_[i] = m_i;
        forcing_[i] = psi[p.forcing_dof] / m_i;
        contact_[i] = 1.0 / m_i;
        shape_[i] = 1.0;
      } else {
        // Step 4: node at B; mass-normalised, invisible to the contact.
        mode_shapes_.col(i) = phi;
        modal_masses_[i] = 1.0;
        forcing_[i] = phi[p.forcing_dof];
        contact_[i] = 0.0;
        shape_[i] = 0.0;
      }
    }
  } else {
    throw std::invalid_argument("scene has no structure");
  }
  damped_ = zeta_.size() > 0 && zeta_.maxCoeff() > 0.0;
  s_A_ = shape_.dot(forcing_);
  s_B_ = shape_.dot(contact_);
  if (!(s_B_ > 0.0)) throw std::invalid_argument("no mode is seen by the contact (s_B = 0)");
  flexibility_ = shape_.dot(contact_.cwiseQuotient(omega_.cwiseAbs2()));
  const Eigen::VectorXd v0 = contact_.cwiseQuotient(omega_.cwiseAbs2());
  static_shape_ = v0 / flexibility_;
  BuildConstrained();
  BuildContacts(scene);
  BuildHarmonics(scene);
}

namespace {

// docs/model.md §4.2 for the contact (c, T) in mass-weighted form: the constrained modes solve
// (μΩ − λμ) v = c R̂, cᵀv = 0, μ_i the modal masses of the scaling. With N an orthonormal basis of
// {cᵀX = 0}, v = N y and (NᵀμΩN) y = λ (NᵀμN) y is a symmetric-definite problem.
ConstrainedModes Constrained(const Eigen::VectorXd& omega_, const Eigen::VectorXd& zeta_,
                             const Eigen::VectorXd& forcing_, const Eigen::VectorXd& mu,
                             const Eigen::VectorXd& shape_, const Eigen::VectorXd& contact_,
                             double s_A_, double s_B_, const Eigen::VectorXd& static_shape_) {
  const auto n = omega_.size();
  ConstrainedModes cm;
  if (n < 2) {
    cm.frequencies.resize(0);
    cm.vectors.resize(n, 0);
    cm.left.resize(0, n);
    cm.modal_forcing.resize(0);
    cm.reaction.resize(0);
    cm.damping.resize(0, 0);
    return cm;
  }
  // Orthonormal basis of the null space of cᵀ.
  const Eigen::MatrixXd ct = shape_.transpose();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(ct, Eigen::ComputeFullV);
  const Eigen::MatrixXd N = svd.matrixV().rightCols(n - 1);
  const Eigen::MatrixXd Kc = N.transpose() * mu.cwiseProduct(omega_.cwiseAbs2()).asDiagonal() * N;
  const Eigen::MatrixXd Mc = N.transpose() * mu.asDiagonal() * N;
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Kc, Mc);
  cm.frequencies = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  cm.vectors = N * eig.eigenvectors();
  // Left eigenvectors: rows of E⁻¹ with E = [v0, v_1..v_{n−1}].
  Eigen::MatrixXd E(n, n);
  E.col(0) = static_shape_;
  E.rightCols(n - 1) = cm.vectors;
  const Eigen::MatrixXd Einv = E.inverse();
  cm.left = Einv.bottomRows(n - 1);
  const Eigen::VectorXd Fc = forcing_ - (s_A_ / s_B_) * contact_;
  cm.modal_forcing = cm.left * Fc;
  const Eigen::VectorXd cw2 = shape_.cwiseProduct(omega_.cwiseAbs2());
  cm.reaction = (cm.vectors.transpose() * cw2) / s_B_;
  // §7: Ẍ + Π D Ẋ + A X = F_c f sin ωt; in ξ coordinates (X = x0 v0/(cᵀv0) + V ξ, ξ = L X) the
  // damping is L Π D V. (L Π ≠ L: l_kᵀ T_B ≠ 0 in general.)
  const Eigen::VectorXd D = 2.0 * zeta_.cwiseProduct(omega_);
  const Eigen::MatrixXd Pi =
      Eigen::MatrixXd::Identity(n, n) - contact_ * shape_.transpose() / s_B_;
  cm.damping = cm.left * Pi * D.asDiagonal() * cm.vectors;
  return cm;
}

}  // namespace

// Modal masses of the scaling: 1/T_B,i for a mode the contact sees (unit component at B), 1 for a
// mass-normalised mode with a node at B.
Eigen::VectorXd System::ModalMassesOfScaling() const {
  const auto n = omega_.size();
  Eigen::VectorXd mu(n);
  for (Eigen::Index i = 0; i < n; ++i) mu[i] = shape_[i] > 0 ? 1.0 / contact_[i] : 1.0;
  return mu;
}

void System::BuildConstrained() {
  constrained_ = Constrained(omega_, zeta_, forcing_, ModalMassesOfScaling(), shape_, contact_,
                             s_A_, s_B_, static_shape_);
}

void System::BuildContacts(const Scene& scene) {
  // Contact 0 is the contact of the scaling: the accessors' data.
  ContactModel c0;
  const auto specs = Contacts(scene);
  if (!specs.empty()) c0.spec = specs.front();
  else c0.spec = ContactSpec{-1, -1, Side::kBelow, x0_, r_, {}, scene.stop_compliance};
  c0.shape = shape_;
  c0.contact = contact_;
  c0.stop = x0_;
  c0.restitution = r_;
  c0.s_A = s_A_;
  c0.s_B = s_B_;
  c0.flexibility = flexibility_;
  c0.static_shape = static_shape_;
  c0.constrained = constrained_;
  contacts_.push_back(std::move(c0));
  const Eigen::VectorXd mu = ModalMassesOfScaling();
  for (size_t j = 1; j < specs.size(); ++j) {
    const ContactSpec& sp = specs[j];
    const double sigma = sp.side == Side::kBelow ? 1.0 : -1.0;
    ContactModel c;
    c.spec = sp;
    Eigen::VectorXd w(dof());  // a_j,i = w_jᵀψ_i
    if (physical_) {
      w = mode_shapes_.row(sp.dof).transpose();
      if (sp.partner >= 0) w -= mode_shapes_.row(sp.partner).transpose();
    } else {
      // Modal form: the components as given, for the kept modes (docs/contacts.md).
      if (sp.modal.size() != scene.modal->frequencies.size())
        throw std::invalid_argument("contact " + std::to_string(j) + " needs one modal component per mode");
      for (int i = 0; i < dof(); ++i) w[i] = sp.modal[kept_[static_cast<size_t>(i)]];
    }
    c.shape = sigma * w;  // c_j,i = σ_j w_jᵀψ_i
    c.contact = c.shape.cwiseQuotient(mu);
    c.stop = sigma * sp.position;
    c.restitution = sp.restitution;
    c.s_A = c.shape.dot(forcing_);
    c.s_B = c.shape.dot(c.contact);
    if (!(c.s_B > 0.0))
      throw std::invalid_argument("contact " + std::to_string(j) + " sees no kept mode (W_jj = 0)");
    const Eigen::VectorXd v0 = c.contact.cwiseQuotient(omega_.cwiseAbs2());
    c.flexibility = c.shape.dot(v0);
    c.static_shape = v0 / c.flexibility;
    c.constrained = Constrained(omega_, zeta_, forcing_, mu, c.shape, c.contact, c.s_A, c.s_B,
                                c.static_shape);
    contacts_.push_back(std::move(c));
  }
  const auto m = static_cast<Eigen::Index>(contacts_.size());
  delassus_.resize(m, m);
  for (Eigen::Index j = 0; j < m; ++j)
    for (Eigen::Index k = 0; k < m; ++k)
      delassus_(j, k) = contacts_[static_cast<size_t>(j)].shape.dot(contacts_[static_cast<size_t>(k)].contact);
}

std::optional<double> System::static_reaction() const {
  if (x0_ < 0) return std::nullopt;
  return x0_ / flexibility_;
}

double System::Reaction(const Eigen::VectorXd& X, const Eigen::VectorXd& V, double phase) const {
  double elastic = 0.0;
  for (Eigen::Index i = 0; i < X.size(); ++i) {
    if (shape_[i] == 0.0) continue;
    elastic += omega_[i] * omega_[i] * X[i] + 2.0 * zeta_[i] * omega_[i] * V[i];
  }
  if (harmonic_sum_) return (elastic - HarmonicContactForce(0, phase, 0)) / s_B_;
  return (elastic - s_A_ * f_ * std::sin(phase)) / s_B_;
}

double System::ContactReaction(int j, const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                               double phase) const {
  if (j == 0) return Reaction(X, V, phase);
  const ContactModel& c = contacts_[static_cast<size_t>(j)];
  double elastic = 0.0;
  for (Eigen::Index i = 0; i < X.size(); ++i)
    elastic += c.shape[i] * (omega_[i] * omega_[i] * X[i] + 2.0 * zeta_[i] * omega_[i] * V[i]);
  if (harmonic_sum_) return (elastic - HarmonicContactForce(j, phase, 0)) / c.s_B;
  return (elastic - c.s_A * f_ * std::sin(phase)) / c.s_B;
}

double System::ReactionRate(const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                            double phase) const {
  const Eigen::VectorXd w2 = omega_.cwiseAbs2();
  double rate = shape_.dot(w2.cwiseProduct(V)) -
                (harmonic_sum_ ? HarmonicContactForce(0, phase, 1) : s_A_ * f_ * w_ * std::cos(phase));
  if (damped_) {
    // Ẍ = −A X − Π D Ẋ + F_c f sin φ on the stop.
    const Eigen::VectorXd DV = 2.0 * zeta_.cwiseProduct(omega_).cwiseProduct(V);
    const Eigen::VectorXd free_acc =
        -w2.cwiseProduct(X) - DV +
        (harmonic_sum_ ? HarmonicForce(phase, 0) : Eigen::VectorXd(forcing_ * (f_ * std::sin(phase))));
    const Eigen::VectorXd acc = free_acc - contact_ * (shape_.dot(free_acc) / s_B_);
    rate += shape_.dot(2.0 * zeta_.cwiseProduct(omega_).cwiseProduct(acc));
  }
  return rate / s_B_;
}

void System::ApplyImpact(Eigen::VectorXd& V, double restitution) const {
  const double p = -(1.0 + restitution) * ContactVelocity(V) / s_B_;
  V += p * contact_;
}

void System::ProjectOntoStop(Eigen::VectorXd& X, Eigen::VectorXd& V) const {
  V -= contact_ * (ContactVelocity(V) / s_B_);
  X -= contact_ * ((ContactDisplacement(X) - x0_) / s_B_);
}

Eigen::VectorXd System::ModalFromPhysical(const Eigen::VectorXd& q) const {
  const Eigen::VectorXd Mq = mass_ * q;
  Eigen::VectorXd X(dof());
  for (int i = 0; i < dof(); ++i) X[i] = mode_shapes_.col(i).dot(Mq) / modal_masses_[i];
  return X;
}

double System::StopTolerance(const Eigen::VectorXd& X) const {
  return kStopUlps * std::numeric_limits<double>::epsilon() *
         (std::abs(x0_) + shape_.cwiseProduct(X).cwiseAbs().sum());
}

double System::BelowStopTolerance() const { return 1e-12 * std::max(1.0, std::abs(x0_)); }

double System::RestTolerance(const Eigen::VectorXd& V) const {
  return kStopUlps * std::numeric_limits<double>::epsilon() * shape_.cwiseProduct(V).cwiseAbs().sum();
}

namespace {

// Moves X along T_B (which changes x_B only) until x_B ≤ x0 in double: the projection
// X − T_B(x_B − x0)/s_B rounds to within an ulp or two of x0, on either side; the engines take a
// state above the stop, however little, as a free flight (docs/scenes.md).
void OntoStop(const Eigen::VectorXd& shape, const Eigen::VectorXd& contact, double s_B, double x0,
              Eigen::VectorXd& X) {
  double step = 0;
  for (int k = 0; k < 64 && shape.dot(X) > x0; ++k) {
    const double gap = shape.dot(X) - x0;
    X -= contact * ((gap + step) / s_B);
    step = step == 0 ? std::numeric_limits<double>::epsilon() * (std::abs(x0) + gap) : 2 * step;
  }
}

// The same for ẋ_B: until ẋ_B ≤ 0.
void ToRest(const Eigen::VectorXd& shape, const Eigen::VectorXd& contact, double s_B, Eigen::VectorXd& V) {
  double step = 0;
  for (int k = 0; k < 64 && shape.dot(V) != 0.0; ++k) {
    const double v = shape.dot(V);
    if (v < 0 && step > 0) break;  // at rest to rounding, not moving off the stop
    V -= contact * ((v + step) / s_B);
    step = step == 0 ? std::numeric_limits<double>::epsilon() * (std::abs(v) + 1e-300) : 2 * step;
  }
}

}  // namespace

System::InitialState System::Initial(const Scene& scene) const {
  InitialState s{scene.initial_time, Eigen::VectorXd::Zero(dof()), Eigen::VectorXd::Zero(dof()),
                 false};
  if (scene.initial_displacement.size() == 0 && scene.initial_velocity.size() == 0) {
    if (x0_ > 0) {
      // Static pressed equilibrium (docs/model.md §4.2, constant term): at rest on the stop.
      s.X = x0_ * static_shape_;
      OntoStop(shape_, contact_, s_B_, x0_, s.X);  // x0·T_B/s_B may round above the stop
      s.sticking = true;
    }
    return s;
  }
  // Modal form: the scene lists every mode; keep those of the model.
  const auto select = [&](const Eigen::VectorXd& given) {
    if (physical_) return ModalFromPhysical(given);
    Eigen::VectorXd out(dof());
    for (int i = 0; i < dof(); ++i) out[i] = given[kept_[static_cast<size_t>(i)]];
    return out;
  };
  if (scene.initial_displacement.size() > 0) s.X = select(scene.initial_displacement);
  if (scene.initial_velocity.size() > 0) s.V = select(scene.initial_velocity);
  // Within rounding of the stop: on it, and at rest there (the tolerances of StopTolerance and
  // RestTolerance). States farther off keep their values.
  const double gap = ContactDisplacement(s.X) - x0_;
  if (gap > 0 && gap <= StopTolerance(s.X)) OntoStop(shape_, contact_, s_B_, x0_, s.X);
  const double at = ContactDisplacement(s.X) - x0_;
  const bool on_stop = at <= StopTolerance(s.X) && at >= -BelowStopTolerance();
  const double v = ContactVelocity(s.V);
  if (on_stop && v != 0.0 && std::abs(v) <= RestTolerance(s.V)) ToRest(shape_, contact_, s_B_, s.V);
  return s;
}

}  // namespace vibro

namespace vibro {

// MODEL (S1)–(S2) (docs/contacts_reference.md) in the modal coordinates of the scaling: with
// C (rows c_jᵀ, j ∈ S) and N an orthonormal basis of ker C, the held flow moves in X = X_p + V y,
// V = N Y from the symmetric-definite problem (NᵀμΩN) Y = (NᵀμN) Y diag(ν²), so VᵀμV = I and
// VᵀμΩV = diag(ν²). X_p = Ω⁻¹T_S α with C X_p = e_S is the static state on every stop of S
// (VᵀμΩX_p = VᵀCᵀα = 0: no constant force on the modes), and α is its contact force. Projecting
// μ(Ẍ + DẊ + ΩX) = μT_A f sin ωt + Cᵀλ onto V removes λ; C Ẍ = 0 gives
// W_SS λ = C(DẊ + ΩX − T_A f sin ωt).
HeldSetModes System::HeldOn(const std::vector<int>& set) const {
  const auto n = omega_.size();
  const auto s = static_cast<Eigen::Index>(set.size());
  if (s < 2 || s > n)
    throw std::invalid_argument("a held set needs two to n contacts");
  HeldSetModes h;
  h.set = set;
  Eigen::MatrixXd C(s, n), T(n, s);
  Eigen::VectorXd e(s);
  for (Eigen::Index a = 0; a < s; ++a) {
    const ContactModel& c = contacts_.at(static_cast<size_t>(set[static_cast<size_t>(a)]));
    C.row(a) = c.shape.transpose();
    T.col(a) = c.contact;
    e[a] = c.stop;
  }
  const Eigen::MatrixXd W = C * T;
  Eigen::FullPivLU<Eigen::MatrixXd> wlu(W);
  if (wlu.rank() < s) throw std::invalid_argument("dependent contacts cannot be held together");
  const Eigen::VectorXd mu = ModalMassesOfScaling();
  const Eigen::VectorXd w2 = omega_.cwiseAbs2();
  const Eigen::MatrixXd OinvT = w2.cwiseInverse().asDiagonal() * T;
  const Eigen::VectorXd alpha = (C * OinvT).fullPivLu().solve(e);
  h.base = OinvT * alpha;
  h.reaction_static = alpha;
  h.reaction_forcing = wlu.solve(C * forcing_);
  const Eigen::Index k = n - s;
  h.frequencies.resize(k);
  h.vectors.resize(n, k);
  if (k > 0) {
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(C, Eigen::ComputeFullV);
    const Eigen::MatrixXd N = svd.matrixV().rightCols(k);
    const Eigen::MatrixXd Kc = N.transpose() * mu.cwiseProduct(w2).asDiagonal() * N;
    const Eigen::MatrixXd Mc = N.transpose() * mu.asDiagonal() * N;
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Kc, Mc);
    h.frequencies = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    h.vectors = N * eig.eigenvectors();
  }
  h.left = h.vectors.transpose() * mu.asDiagonal();
  h.modal_forcing = h.left * forcing_;
  h.reaction = wlu.solve(C * w2.asDiagonal() * h.vectors);
  const Eigen::VectorXd D = 2.0 * zeta_.cwiseProduct(omega_);
  h.damping = h.left * D.asDiagonal() * h.vectors;
  h.reaction_velocity = wlu.solve(C * D.asDiagonal() * h.vectors);
  return h;
}

}  // namespace vibro
