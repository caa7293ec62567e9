// Periodic orbits by Newton on the stroboscopic map with the analytic Jacobian (docs/model.md §5).
#include "vibro/poincare.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include <fmt/format.h>
#include <unsupported/Eigen/MatrixFunctions>

#include <fmt/format.h>

#include "vibro/contact_sequence.hpp"

namespace vibro {
namespace {

Eigen::VectorXd Stack(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  Eigen::VectorXd z(a.size() + b.size());
  z << a, b;
  return z;
}

// Observer keeping what the orbit search needs from a transient.
struct TransientLog final : Observer {
  long long keep_from = 0;
  std::vector<Event> events;
  void OnEvent(const Event& e) override {
    if (e.clock.period >= keep_from) events.push_back(e);
  }
};

// Observer catching the dense sample with a given index.
struct SampleCatcher final : Observer {
  long long target = 0, seen = 0;
  // When finite: the sample nearest to this time (within half a spacing) instead of the index
  // (a long run's samples need not all be emitted: none inside a chattering tail's jump).
  double target_time = std::numeric_limits<double>::quiet_NaN(), half_spacing = 0;
  bool caught = false;
  double t = 0;
  Eigen::VectorXd X, V;
  Mode mode = Mode::kFree;
  void OnSample(const Sample& s) override {
    const bool hit = std::isfinite(target_time) ? !caught && std::abs(s.t - target_time) <= half_spacing
                                                : seen == target;
    ++seen;
    if (hit) {
      caught = true;
      t = s.t;
      X = s.X;
      V = s.V;
      mode = s.mode;
    }
  }
};

// The contacts a section state is held on (several contacts, docs/contacts.md "Periodic orbits"):
// gap and gap velocity zero within the rounding of the state.
std::vector<int> HeldAtSection(const System& sys, const Eigen::VectorXd& z) {
  std::vector<int> S;
  if (sys.contact_count() < 2) return S;
  const auto n = sys.dof();
  for (int j = 0; j < sys.contact_count(); ++j) {
    const ContactModel& c = sys.contacts()[static_cast<size_t>(j)];
    const double gap = c.shape.dot(z.head(n)) - c.stop;
    const double scale = std::abs(c.stop) + c.shape.cwiseProduct(z.head(n)).cwiseAbs().sum();
    const double vscale = c.shape.cwiseProduct(z.tail(n)).cwiseAbs().sum() + 1e-300;
    if (std::abs(gap) <= 1e-9 * (1.0 + scale) && std::abs(c.shape.dot(z.tail(n))) <= 1e-9 * (1.0 + vscale))
      S.push_back(j);
  }
  return S;
}

// The events of the first q periods of a run from the section (the orbit's contact sequence,
// OrbitResult::sequence), and how many directions its sticking phases collapse: 2 per independent
// held contact shape c_j (rank of their span).
struct SequenceRecorder final : Observer {
  explicit SequenceRecorder(long long q, double t0 = 0, std::vector<int> held = {})
      : periods(q), start(t0), held_at_start(std::move(held)) {}
  long long periods;
  double start;                   // the section time
  std::vector<int> held_at_start;  // contacts held at the section: their stick there is no event of the orbit
  std::vector<Event> events;
  std::vector<int> stuck;  // contacts with a sticking phase, in order of first entry
  void OnEvent(const Event& e) override {
    if (e.clock.period >= periods) return;
    if (e.kind == EventKind::kStick && std::find(stuck.begin(), stuck.end(), e.contact) == stuck.end())
      stuck.push_back(e.contact);
    if (e.kind == EventKind::kStick && std::abs(e.t - start) <= 1e-12 * (1.0 + std::abs(start)) &&
        std::find(held_at_start.begin(), held_at_start.end(), e.contact) != held_at_start.end())
      return;
    events.push_back(e);
  }
  int Collapsed(const System& sys) const {
    // A compliant stop's contact phase collapses nothing (docs/compliant.md, "Periodic orbits").
    std::vector<int> held;
    for (int j : stuck)
      if (!sys.contacts()[static_cast<size_t>(j)].spec.compliance.compliant()) held.push_back(j);
    if (held.empty()) return 0;
    Eigen::MatrixXd C(sys.dof(), static_cast<Eigen::Index>(held.size()));
    for (size_t k = 0; k < held.size(); ++k)
      C.col(static_cast<Eigen::Index>(k)) = sys.contacts()[static_cast<size_t>(held[k])].shape;
    Eigen::FullPivLU<Eigen::MatrixXd> lu(C);
    lu.setThreshold(1e-10);
    return 2 * static_cast<int>(lu.rank());
  }
};

}  // namespace

TangentTracker::TangentTracker(const System& sys) : sys_(sys) {
  const auto n = sys.dof();
  const Eigen::VectorXd w2 = sys.omega().cwiseAbs2();
  const Eigen::VectorXd D = 2.0 * sys.damping().cwiseProduct(sys.omega());
  const Eigen::MatrixXd Omega = w2.asDiagonal();
  Eigen::MatrixXd G_free = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  G_free.topRightCorner(n, n).setIdentity();
  G_free.bottomLeftCorner(n, n) = -Omega;
  G_free.bottomRightCorner(n, n) = -Eigen::MatrixXd(D.asDiagonal());
  // Per contact j: Π_j = I − T_j c_jᵀ/W_jj and the flow with j held, G = [[0, I], [−A_j, −Π_j D]],
  // A_j = Ω − T_j (c_j∘ω²)ᵀ/W_jj (docs/model.md §4.2 with c → c_j; contact 0 is the [stop]).
  for (const ContactModel& k : sys.contacts()) {
    ContactTangent t;
    t.c = k.shape;
    t.T = k.contact;
    t.e = k.stop;
    t.s = k.s_B;
    t.r = k.restitution;
    t.Pi = Eigen::MatrixXd::Identity(n, n) - t.T * t.c.transpose() / t.s;
    const Eigen::MatrixXd A = Omega - t.T * t.c.cwiseProduct(w2).transpose() / t.s;
    t.G_stick = G_free;
    t.G_stick.bottomLeftCorner(n, n) = -A;
    t.G_stick.bottomRightCorner(n, n) = -t.Pi * D.asDiagonal();
    // Undamped: exp(G s) from the constrained modes (HeldFlight), E = [v_0, V] with E⁻¹ = [cᵀ; L]
    // (cᵀv_0 = 1, cᵀV = 0).
    const ConstrainedModes& cm = k.constrained;
    t.closed_form = !sys.damped() && cm.vectors.rows() == n && cm.vectors.cols() == n - 1 &&
                    cm.left.rows() == n - 1 && cm.frequencies.size() == n - 1 &&
                    std::abs(t.c.dot(k.static_shape) - 1.0) <= 1e-12;
    if (t.closed_form) {
      t.v0 = k.static_shape;
      t.nu = cm.frequencies;
      t.V = cm.vectors;
      t.L = cm.left;
    }
    // A compliant stop's contact phase (docs/compliant.md (C2)): the structure gains k T cᵀ and c T cᵀ.
    const Compliance& cc = k.spec.compliance;
    if (cc.compliant()) {
      t.compliant = true;
      t.stiffness = cc.stiffness;
      t.damping = cc.damping;
      t.gap_exit = cc.separation == Separation::kGap || cc.damping == 0;
      t.G_contact = G_free;
      t.G_contact.bottomLeftCorner(n, n) -= t.stiffness * t.T * t.c.transpose();
      t.G_contact.bottomRightCorner(n, n) -= t.damping * t.T * t.c.transpose();
      const double norm = t.G_contact.bottomLeftCorner(n, n).cwiseAbs().rowwise().sum().maxCoeff();
      t.balance = norm > 0 ? std::sqrt(norm) : 1.0;
      t.G_contact.topRightCorner(n, n) *= t.balance;
      t.G_contact.bottomLeftCorner(n, n) /= t.balance;
    }
    contacts_.push_back(std::move(t));
  }
  phi_ = Eigen::MatrixXd::Identity(2 * n, 2 * n);
  w2_ = w2;
  D_ = D;
  du_.resize(n);
  dv_.resize(n);
  xi_.resize(n - 1);
  eta_.resize(n - 1);
  held_c_.resize(n - 1);
  held_s_.resize(n - 1);
  salt_u_.resize(2 * n);
  salt_v_.resize(n);
  dy_ = Eigen::RowVectorXd::Zero(2 * n);
}

void TangentTracker::Restart(const Eigen::MatrixXd& start) {
  phi_ = start;
  singular_ = false;
  // Several contacts, restarted while held (a Lyapunov frame at a period boundary): the frame's
  // directions off the held manifold are collapsed, as at the start of a run held on contacts.
  if (contacts_.size() > 1 && (held_ >= 0 || held_ == kSet)) CollapseOffHeld();
}

void TangentTracker::CollapseOffHeld() {
  const auto n = sys_.dof();
  const Eigen::MatrixXd P = held_ == kSet ? SetProjection(held_set_) : contacts_[static_cast<size_t>(held_)].Pi;
  phi_.topRows(n) = (P * phi_.topRows(n)).eval();
  phi_.bottomRows(n) = (P * phi_.bottomRows(n)).eval();
}

void TangentTracker::Undefined(std::string why) {
  if (undefined_.empty()) undefined_ = std::move(why);
}

double TangentTracker::Coupling(int j, int k) const {
  // As the automaton: a coupling within the rounding of the mode shapes is none (docs/contacts.md).
  const double w = sys_.delassus()(j, k);
  const double scale = std::sqrt(contacts_[static_cast<size_t>(j)].s * contacts_[static_cast<size_t>(k)].s);
  return std::abs(w) <= 64 * std::numeric_limits<double>::epsilon() * scale ? 0.0 : w;
}

Eigen::VectorXd TangentTracker::Field(Mode mode, const Eigen::VectorXd& X,
                                      const Eigen::VectorXd& V, double phase, int contact) const {
  const auto n = sys_.dof();
  Eigen::VectorXd z(2 * n);
  z.head(n) = V;
  z.tail(n) = -w2_.cwiseProduct(X) - D_.cwiseProduct(V) +
              (sys_.harmonic_sum() ? sys_.HarmonicForce(phase, 0)  // docs/harmonics.md
                                   : Eigen::VectorXd(sys_.forcing() * (sys_.amplitude() * std::sin(phase))));
  // Ẍ = free acceleration + T_j λ_j with c_jᵀẌ = 0.
  if (mode == Mode::kSticking) z.tail(n) = contacts_[static_cast<size_t>(contact)].Pi * z.tail(n);
  return z;
}

Eigen::MatrixXd TangentTracker::SetProjection(const std::vector<int>& set) const {
  const auto n = sys_.dof();
  const auto m = static_cast<Eigen::Index>(set.size());
  Eigen::MatrixXd T(n, m), C(m, n);
  for (Eigen::Index a = 0; a < m; ++a) {
    T.col(a) = contacts_[static_cast<size_t>(set[static_cast<size_t>(a)])].T;
    C.row(a) = contacts_[static_cast<size_t>(set[static_cast<size_t>(a)])].c.transpose();
  }
  const Eigen::MatrixXd W = C * T;  // W_SS, positive definite for independent contacts
  return Eigen::MatrixXd::Identity(n, n) - T * W.fullPivLu().solve(C);
}

const Eigen::MatrixXd& TangentTracker::SetFlow(const std::vector<int>& set) {
  for (const auto& [key, G] : set_flows_)
    if (key == set) return G;
  // Ẍ = P_S (−ΩX − DẊ + T_A f sin φ) on the set (MODEL (S1) in docs/contacts.md's notation):
  // the reactions λ_S = −W_SS⁻¹ C_S a_free keep C_S Ẍ = 0.
  const auto n = sys_.dof();
  const Eigen::MatrixXd P = SetProjection(set);
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  G.topRightCorner(n, n).setIdentity();
  G.bottomLeftCorner(n, n) = -P * w2_.asDiagonal();
  G.bottomRightCorner(n, n) = -P * D_.asDiagonal();
  set_flows_.emplace_back(set, std::move(G));
  return set_flows_.back().second;
}

// The field of the flow the tracker follows now (free, held on one contact, or on a set).
Eigen::VectorXd TangentTracker::HeldField(const Eigen::VectorXd& X, const Eigen::VectorXd& V, double phase) {
  if (held_ == kSet) {
    Eigen::VectorXd z = Field(Mode::kFree, X, V, phase);
    const auto n = sys_.dof();
    z.tail(n) = SetProjection(held_set_) * z.tail(n);
    return z;
  }
  return held_ >= 0 ? Field(Mode::kSticking, X, V, phase, held_) : Field(Mode::kFree, X, V, phase);
}

void TangentTracker::Defer(const Eigen::MatrixXd& dV, const Eigen::VectorXd& f_minus, const Eigen::VectorXd& c,
                           double denom, const Eigen::VectorXd& X, const Eigen::VectorXd& V, double phase) {
  pending_.active = true;
  pending_.dV = dV;
  pending_.f_minus = f_minus;
  pending_.c = c;
  pending_.denom = denom;
  pending_.X = X;
  pending_.V = V;
  pending_.phase = phase;
  pending_.held_before = held_;
  pending_.set_before = held_set_;
  held_ = -2;  // the acceleration LCP decides the flow after: the next stretch names it
}

Eigen::VectorXd TangentTracker::SetField(const std::vector<int>& set, const Eigen::VectorXd& X,
                                         const Eigen::VectorXd& V, double phase) const {
  if (set.size() == 1) return Field(Mode::kSticking, X, V, phase, set.front());
  Eigen::VectorXd z = Field(Mode::kFree, X, V, phase);
  if (set.empty()) return z;
  const auto n = sys_.dof();
  z.tail(n) = SetProjection(set) * z.tail(n);
  return z;
}

void TangentTracker::HeldSetFlight(const std::vector<int>& set, double duration) {
  if (set.size() == 1) {
    const ContactTangent& ct = contacts_[static_cast<size_t>(set.front())];
    if (ct.closed_form)
      HeldFlight(ct, duration);
    else
      phi_ = (ct.G_stick * duration).exp() * phi_;
    return;
  }
  phi_ = (SetFlow(set) * duration).exp() * phi_;
}

// A chattering sequence at contact k = r.contact beside the held set S, jumped to its accumulation
// point (dynamics/contact_laws.hpp, TryHeldAccumulation; docs/contacts.md "Periodic orbits"): the
// jump L takes the post-impact state z_k over Δ∞(z_k) on the flow held on S (k free), then projects
// onto Z = S ∪ {k} (g = ġ = 0 on Z: ∂ = P_Z on positions and velocities). As for one contact
// (docs/model.md §5.4),
//   D L = diag(P_Z, P_Z) (Φ_S(Δ∞) + f_S(t∞⁻) ∇Δ∞ᵀ) − f⁺(t∞) ∇Δ∞ᵀ,
// with ∇Δ∞ the gradient of the prediction the automaton took (HeldTailGradient) and f⁺ the flow
// after, which the acceleration LCP chooses (held on Z, on part of it, or free): that term is
// applied when the next stretch names it. The last impact's saltation, deferred when it was an
// impact while a set was held, takes the S-flow as its flow after: the tail flight starts on it.
void TangentTracker::HeldAccumulation(const Reset& r) {
  const auto n = sys_.dof();
  std::vector<int> S;
  const auto from = [&](int held, const std::vector<int>& set) {
    if (held == kSet) return set;
    return held >= 0 ? std::vector<int>{held} : std::vector<int>{};
  };
  if (pending_.active) {
    S = from(pending_.held_before, pending_.set_before);
    if (S.empty()) {
      pending_.active = false;
      Undefined("a chattering accumulation beside held contacts after an impact that left none held");
      held_ = -2;
      return;
    }
    Resolve(Mode::kSticking, S.front(), &S);
  } else {
    S = from(held_, held_set_);
  }
  held_ = -2;
  held_set_.clear();
  if (S.empty()) {
    Undefined("a chattering accumulation beside held contacts without a held flow the tangent map knows");
    return;
  }
  if (!r.delta_gradient || !r.X_end || !r.V_end) {
    singular_ = true;
    return;
  }
  const Eigen::RowVectorXd grad_phi = r.delta_gradient->transpose() * phi_;  // ∇Δ∞ᵀ Φ
  HeldSetFlight(S, r.delta);                                                   // Φ_S(Δ∞) Φ
  std::vector<int> Z = S;
  if (std::find(Z.begin(), Z.end(), r.contact) == Z.end()) Z.push_back(r.contact);
  std::sort(Z.begin(), Z.end());
  const Eigen::MatrixXd P = SetProjection(Z);
  const double phase_inf = r.phase + sys_.frequency() * r.delta;
  const Eigen::VectorXd f_end = SetField(S, *r.X_end, *r.V_end, phase_inf);
  phi_.topRows(n) = (P * phi_.topRows(n)).eval();
  phi_.bottomRows(n) = (P * phi_.bottomRows(n)).eval();
  Eigen::VectorXd jump(2 * n);
  jump << P * f_end.head(n), P * f_end.tail(n);
  phi_ += jump * grad_phi;
  pending_jump_.active = true;
  pending_jump_.grad_phi = grad_phi;
  pending_jump_.X = r.X_after;
  pending_jump_.V = r.V_after;
  pending_jump_.phase = phase_inf;
}

void TangentTracker::Resolve(Mode mode, int contact, const std::vector<int>* set) {
  pending_.active = false;
  Eigen::VectorXd f_plus = Field(Mode::kFree, pending_.X, pending_.V, pending_.phase);
  const auto n = sys_.dof();
  if (mode == Mode::kSticking && set && set->size() > 1)
    f_plus.tail(n) = SetProjection(*set) * f_plus.tail(n);
  else if (mode == Mode::kSticking)
    f_plus.tail(n) = contacts_[static_cast<size_t>(contact)].Pi * f_plus.tail(n);
  Saltation(pending_.dV, pending_.f_minus, f_plus, pending_.c, pending_.denom);
}

void TangentTracker::OnStretch(const Stretch& s) {
  const bool multi = contacts_.size() > 1;
  // A compliant stop (docs/compliant.md, "Periodic orbits"): its contact phase is a linear flow,
  // Φ ← exp(G_c s) Φ (C2); a free flight while its surface relaxes carries δy = e^(−ks/c) δy (C7).
  const int sj = multi ? s.contact : 0;
  if (s.mode == Mode::kSticking && (s.held == nullptr || s.held->size() <= 1) &&
      contacts_[static_cast<size_t>(sj)].compliant) {
    if (compliant_ != sj) Undefined("a contact phase of a compliant stop began without an entry the tangent map knows");
    held_ = -1;
    const ContactTangent& ct = contacts_[static_cast<size_t>(sj)];
    Eigen::MatrixXd E = (ct.G_contact * s.duration).exp();  // of the balanced G_c
    const auto n = sys_.dof();
    E.topRightCorner(n, n) /= ct.balance;  // D⁻¹ E D
    E.bottomLeftCorner(n, n) *= ct.balance;
    phi_ = E * phi_;
    return;
  }
  if (s.mode == Mode::kFree && relax_contact_ >= 0) {
    const ContactTangent& ct = contacts_[static_cast<size_t>(relax_contact_)];
    const double decay = std::exp(-ct.stiffness / ct.damping * s.duration);
    dy_ *= decay;
    relax_y_ *= decay;
  }
  const bool on_set = multi && s.mode == Mode::kSticking && s.held && s.held->size() > 1;
  if (pending_sim_.active)  // the flow after a simultaneous impact: free, held on one contact, or on a set
    ResolveSimultaneous(s.mode == Mode::kFree ? std::vector<int>{}
                        : on_set              ? *s.held
                                              : std::vector<int>{s.contact});
  if (pending_.active) Resolve(s.mode, s.contact, on_set ? s.held : nullptr);
  if (pending_jump_.active) {  // − f⁺(t∞) ∇Δ∞ᵀ of a held accumulation, f⁺ the flow this stretch follows
    pending_jump_.active = false;
    const std::vector<int> set = s.mode == Mode::kFree ? std::vector<int>{}
                                 : on_set              ? *s.held
                                                       : std::vector<int>{multi ? s.contact : 0};
    phi_ -= SetField(set, pending_jump_.X, pending_jump_.V, pending_jump_.phase) * pending_jump_.grad_phi;
  }
  // A run that starts held (a section on a held set, or a Lyapunov frame): directions off the
  // held manifold are collapsed as a landing collapses them (a perturbation off a held contact
  // returns onto it): diag(P_S, P_S), a no-op on directions along the manifold.
  const bool collapse = multi && held_ == -2 && s.mode == Mode::kSticking;
  if (s.mode == Mode::kFree) {
    // Several contacts: every way out of sticking is a reset the tracker has seen.
    if (multi && (held_ >= 0 || held_ == kSet))
      Undefined("a sticking phase ended without a release the tangent map knows");
    held_ = -1;
    held_set_.clear();
    FreeFlight(s.duration, phi_);
  } else if (on_set) {
    // Held on a set S (docs/contacts.md, "Periodic orbits"): exp(G_S s).
    if (held_ != -2 && !(held_ == kSet && held_set_ == *s.held))
      Undefined("a phase held on several contacts began without an entry the tangent map knows");
    held_ = kSet;
    held_set_ = *s.held;
    if (collapse) CollapseOffHeld();
    phi_ = (SetFlow(held_set_) * s.duration).exp() * phi_;
  } else {
    const auto j = static_cast<size_t>(multi ? s.contact : 0);
    if (multi && held_ != s.contact && held_ != -2)
      Undefined("a sticking phase began without an entry the tangent map knows (several contacts held, "
                "or a simultaneous plastic impact)");
    held_ = s.contact;
    held_set_.clear();
    if (collapse) CollapseOffHeld();
    if (contacts_[j].closed_form)
      HeldFlight(contacts_[j], s.duration);
    else
      phi_ = (contacts_[j].G_stick * s.duration).exp() * phi_;
  }
}

// exp(G_free s) is block diagonal over the modes: for Ẍ_i = −ω_i² X_i − 2ζ_iω_i Ẋ_i (ζ_i < 1),
// with a = ζ_iω_i and ω_d = ω_i √(1 − ζ_i²), the block acting on (X_i, Ẋ_i) is
// e^{−a s} [[cos + (a/ω_d) sin, sin/ω_d], [−(ω_i²/ω_d) sin, cos − (a/ω_d) sin]] at ω_d s.
// Applied in place to the rows of `m`.
void TangentTracker::FreeFlight(double s, Eigen::MatrixXd& m) const {
  const auto n = sys_.dof();
  for (int i = 0; i < n; ++i) {
    const double a = 0.5 * D_[i], wd = std::sqrt(w2_[i] - a * a);
    double sn, c;
    ::sincos(wd * s, &sn, &c);
    const double e = a == 0.0 ? 1.0 : std::exp(-a * s);
    const double b00 = e * (c + a / wd * sn), b01 = e * sn / wd, b10 = -e * w2_[i] / wd * sn,
                 b11 = e * (c - a / wd * sn);
    for (Eigen::Index j = 0; j < m.cols(); ++j) {
      const double x = m(i, j), v = m(n + i, j);
      m(i, j) = b00 * x + b01 * v;
      m(n + i, j) = b10 * x + b11 * v;
    }
  }
}

// exp(G s) of the flow held on contact j, undamped (docs/model.md §4.2): in the coordinates of
// E = [v_0, V], X = v_0 a + V ξ, Ẋ = v_0 b + V η with a = cᵀX, ξ = LX (b, η likewise from Ẋ), the
// held flow is ä = 0 (A v_0 = 0) and ξ̈_k = −ω'_k² ξ_k, so that
//   X(s) = v_0 (a + b s) + V (cos ω's ξ + sin ω's/ω' η),  Ẋ(s) = v_0 b + V (−ω' sin ω's ξ + cos ω's η).
// Applied in place to the columns of phi_ (no temporaries; loops rather than Eigen's products,
// whose dispatch costs more than the arithmetic at these sizes).
void TangentTracker::HeldFlight(const ContactTangent& ct, double s) {
  const auto n = sys_.dof();
  const Eigen::Index k = ct.nu.size();
  for (Eigen::Index i = 0; i < k; ++i) ::sincos(ct.nu[i] * s, &held_s_[i], &held_c_[i]);
  for (Eigen::Index j = 0; j < phi_.cols(); ++j) {
    double* x = phi_.col(j).data();
    double* v = x + n;
    double a = 0, b = 0;
    for (Eigen::Index r = 0; r < n; ++r) {
      a += ct.c[r] * x[r];
      b += ct.c[r] * v[r];
    }
    for (Eigen::Index i = 0; i < k; ++i) {
      double q = 0, p = 0;
      for (Eigen::Index r = 0; r < n; ++r) {
        q += ct.L(i, r) * x[r];
        p += ct.L(i, r) * v[r];
      }
      const double nu = ct.nu[i], sn = held_s_[i], cs = held_c_[i];
      xi_[i] = cs * q + (nu > 0 ? sn / nu : s) * p;
      eta_[i] = -nu * sn * q + cs * p;
    }
    const double a_s = a + b * s;
    for (Eigen::Index r = 0; r < n; ++r) {
      double xr = a_s * ct.v0[r], vr = b * ct.v0[r];
      for (Eigen::Index i = 0; i < k; ++i) {
        xr += ct.V(r, i) * xi_[i];
        vr += ct.V(r, i) * eta_[i];
      }
      x[r] = xr;
      v[r] = vr;
    }
  }
}

// The restitution law's saltation S = ∂g + (f⁺ − ∂g f⁻) ∇hᵀ / (∇h·f⁻) (docs/model.md §5.6) with
// ∂g = diag(I, I − (1+r_j) T_j c_jᵀ/W_jj) and ∇h = (c_j, 0) (contact j; the [stop]: c, T_B, s_B),
// applied as rank-one updates column by column (a run has millions of impacts: no temporaries):
// the phase does not change across the impact, so f⁺ − ∂g f⁻ = (Ẋ⁺ − Ẋ⁻, a⁺ − ∂g_V a⁻) with
// a = −ω²X − DẊ + T_A f sin φ on either side (X⁺ is X⁻ snapped onto the stop: equal to rounding).
void TangentTracker::Impact(const Reset& r, int contact) {
  const auto n = sys_.dof();
  const ContactTangent& ct = contacts_[static_cast<size_t>(contact)];
  const Eigen::VectorXd& c = ct.c;
  const Eigen::VectorXd& T_B = ct.T;
  const Eigen::VectorXd& T_A = sys_.forcing();
  const double denom = std::isnan(r.contact_velocity_before) ? c.dot(r.V_before) : r.contact_velocity_before;
  if (!(std::abs(denom) > 1e-300)) {
    singular_ = true;
    return;
  }
  const double k = (1.0 + ct.r) / ct.s;
  const double forcing = sys_.amplitude() * std::sin(r.phase);
  // a⁺ − ∂g_V a⁻ = a⁺ − a⁻ + k T_B (cᵀa⁻), a⁺ − a⁻ = −ω²(X⁺ − X⁻) − D(Ẋ⁺ − Ẋ⁻).
  double c_a_minus = 0;
  for (int i = 0; i < n; ++i)
    c_a_minus += c[i] * (-w2_[i] * r.X_before[i] - D_[i] * r.V_before[i] + T_A[i] * forcing);
  if (sys_.harmonic_sum()) {  // a sum of harmonics (docs/harmonics.md): the forcing summed
    const Eigen::VectorXd F = sys_.HarmonicForce(r.phase, 0);
    c_a_minus = 0;
    for (int i = 0; i < n; ++i) c_a_minus += c[i] * (-w2_[i] * r.X_before[i] - D_[i] * r.V_before[i] + F[i]);
  }
  for (int i = 0; i < n; ++i) {
    du_[i] = r.V_after[i] - r.V_before[i];
    dv_[i] = -w2_[i] * (r.X_after[i] - r.X_before[i]) - D_[i] * du_[i] + k * c_a_minus * T_B[i];
  }
  for (Eigen::Index j = 0; j < phi_.cols(); ++j) {
    double* col = phi_.col(j).data();
    double cx = 0, cv = 0;
    for (int i = 0; i < n; ++i) {
      cx += c[i] * col[i];
      cv += c[i] * col[n + i];
    }
    cx /= denom;
    cv *= k;
    for (int i = 0; i < n; ++i) {
      col[i] += du_[i] * cx;
      col[n + i] += dv_[i] * cx - T_B[i] * cv;
    }
  }
}

void TangentTracker::Saltation(const Eigen::MatrixXd& dV, const Eigen::VectorXd& f_minus,
                               const Eigen::VectorXd& f_plus, const Eigen::VectorXd& c, double denom) {
  const auto n = sys_.dof();
  if (!(std::abs(denom) > 1e-300)) {
    singular_ = true;
    return;
  }
  // S = [[I + u_X cᵀ/denom, 0], [u_V cᵀ/denom, dV]] with u = f⁺ − ∂g f⁻, applied column by column.
  salt_u_.head(n) = f_plus.head(n) - f_minus.head(n);
  salt_u_.tail(n) = f_plus.tail(n);
  salt_u_.tail(n).noalias() -= dV * f_minus.tail(n);
  for (Eigen::Index j = 0; j < phi_.cols(); ++j) {
    auto x = phi_.col(j).head(n);
    auto v = phi_.col(j).tail(n);
    const double cx = c.dot(x) / denom;
    salt_v_.noalias() = dV * v;
    v = salt_v_ + salt_u_.tail(n) * cx;
    x += salt_u_.head(n) * cx;
  }
}

// Contact k = r.contact closes while contact h = held_ sticks (docs/contacts.md, "Periodic
// orbits"), with the automaton's pattern: h pushed off (W_hk P_k > 0 for k's impulse alone:
// P_h = 0, ∂g_V = Π_k) or h stays (the 2 × 2 law W P = −diag(1, 1 + r_k) C_Z Ẋ⁻ on Z = {h, k}:
// ∂g_V = I − T_Z W_ZZ⁻¹ diag(1, 1 + r_k) C_Z, linear while the pattern holds). The guard is g_k,
// the flow before is the one held on h, the flow after the one the run follows: held on h while
// its reaction stays positive, free otherwise.
void TangentTracker::ImpactWhileHeld(const Reset& r) {
  const auto n = sys_.dof();
  const int h = held_, k = r.contact;
  const ContactTangent& H = contacts_[static_cast<size_t>(h)];
  const ContactTangent& K = contacts_[static_cast<size_t>(k)];
  const double vk = std::isnan(r.contact_velocity_before) ? K.c.dot(r.V_before) : r.contact_velocity_before;
  const double Whk = Coupling(h, k);
  const double Pk = -(1.0 + K.r) * vk / K.s;
  const Eigen::VectorXd f_minus = Field(Mode::kSticking, r.X_before, r.V_before, r.phase, h);
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  if (Whk * Pk > 64 * std::numeric_limits<double>::epsilon() * std::abs(Whk * Pk)) {
    held_ = -1;
    const Eigen::MatrixXd dV = I - (1.0 + K.r) * K.T * K.c.transpose() / K.s;
    // Plastic (r_k = 0): k at rest alone, stuck or leaving as the acceleration LCP decides.
    if (K.r == 0.0)
      Defer(dV, f_minus, K.c, vk, r.X_after, r.V_after, r.phase);
    else
      Saltation(dV, f_minus, Field(Mode::kFree, r.X_after, r.V_after, r.phase), K.c, vk);
    return;
  }
  Eigen::Matrix2d W;
  W << H.s, Whk, Whk, K.s;
  Eigen::MatrixXd T_Z(n, 2), C_Z(2, n);
  T_Z << H.T, K.T;
  C_Z << H.c.transpose(), K.c.transpose();
  const Eigen::Matrix2d law = W.inverse() * Eigen::Vector2d(1.0, 1.0 + K.r).asDiagonal();
  const Eigen::MatrixXd dV = I - T_Z * law * C_Z;
  // Plastic (r_k = 0): both at rest, the acceleration LCP on {h, k} decides which stay held (a
  // set, one of them, or none): the flow after is the one the next stretch follows.
  if (K.r == 0.0) {
    Defer(dV, f_minus, K.c, vk, r.X_after, r.V_after, r.phase);
    return;
  }
  // The reaction of h after the impact: λ_h = −c_hᵀ a_free/W_hh.
  const Eigen::VectorXd free_after = Field(Mode::kFree, r.X_after, r.V_after, r.phase);
  const bool stays = -H.c.dot(free_after.tail(n)) / H.s > 0;
  if (!stays) held_ = -1;
  Saltation(dV, f_minus, stays ? Field(Mode::kSticking, r.X_after, r.V_after, r.phase, h) : free_after,
            K.c, vk);
}

// Contact k = r.contact closes while a set S is held (or one contact with others resting beside
// it): the impact LCP (docs/contacts.md) W_ZZ P = −diag(1 + r) v⁻ on the contacts A that take an
// impulse (P_a > 0), with its pattern fixed; held and resting contacts keep v = 0 (factor 1), k
// bounces (1 + r_k). ∂g_V = I − T_A W_AA⁻¹ diag(1, …, 1 + r_k) C_A; A is read from the jump the
// automaton took, P = W_ZZ⁻¹ C_Z (Ẋ⁺ − Ẋ⁻) over the contacts at zero gap. The guard is g_k, the flow
// before the held one, the flow after the one the acceleration LCP chooses (the next stretch's).
std::vector<int> TangentTracker::HeldNow() const {
  return held_ >= 0 ? std::vector<int>{held_} : held_ == kSet ? held_set_ : std::vector<int>{};
}

// The contacts at zero gap after the reset r, those of H aside (r.contact among them).
std::vector<int> TangentTracker::AtZeroGap(const Reset& r, const std::vector<int>& H) const {
  std::vector<int> Z;
  for (size_t j = 0; j < contacts_.size(); ++j) {
    const ContactTangent& ct = contacts_[j];
    const double gap = ct.c.dot(r.X_after) - ct.e;
    const double tol = 1e-9 * (1.0 + std::abs(ct.e) + ct.c.cwiseProduct(r.X_after).cwiseAbs().sum());
    const bool held = std::find(H.begin(), H.end(), static_cast<int>(j)) != H.end();
    if ((std::abs(gap) <= tol && !held) || static_cast<int>(j) == r.contact) Z.push_back(static_cast<int>(j));
  }
  return Z;
}

void TangentTracker::ImpactWhileSetHeld(const Reset& r) {
  const auto n = sys_.dof();
  const int k = r.contact;
  {
    // Another free contact closing at this instant (its gap within rounding, its gap velocity < 0):
    // a simultaneous impact beside the held contacts, not an impact of k alone.
    const std::vector<int> H = HeldNow();
    std::vector<int> closing{k};
    for (const int j : AtZeroGap(r, H)) {
      const ContactTangent& ct = contacts_[static_cast<size_t>(j)];
      if (j != k && ct.c.dot(r.V_before) < -1e-9 * (ct.c.cwiseProduct(r.V_before).cwiseAbs().sum() + 1e-300))
        closing.push_back(j);
    }
    if (closing.size() > 1 && !H.empty()) {
      SimultaneousImpact(r, closing, H);
      return;
    }
  }
  std::vector<int> Z;
  for (size_t j = 0; j < contacts_.size(); ++j) {
    const ContactTangent& ct = contacts_[j];
    const double gap = ct.c.dot(r.X_after) - ct.e;
    const double tol = 1e-9 * (1.0 + std::abs(ct.e) + ct.c.cwiseProduct(r.X_after).cwiseAbs().sum());
    if (std::abs(gap) <= tol || static_cast<int>(j) == k) Z.push_back(static_cast<int>(j));
  }
  const auto z = static_cast<Eigen::Index>(Z.size());
  Eigen::MatrixXd T_Z(n, z), C_Z(z, n);
  for (Eigen::Index a = 0; a < z; ++a) {
    T_Z.col(a) = contacts_[static_cast<size_t>(Z[static_cast<size_t>(a)])].T;
    C_Z.row(a) = contacts_[static_cast<size_t>(Z[static_cast<size_t>(a)])].c.transpose();
  }
  const Eigen::VectorXd P = (C_Z * T_Z).fullPivLu().solve(C_Z * (r.V_after - r.V_before));
  const double scale = P.cwiseAbs().maxCoeff();
  std::vector<int> A;
  for (Eigen::Index a = 0; a < z; ++a)
    if (P[a] > 1e-9 * scale || Z[static_cast<size_t>(a)] == k) A.push_back(Z[static_cast<size_t>(a)]);
  const auto m = static_cast<Eigen::Index>(A.size());
  Eigen::MatrixXd T_A(n, m), C_A(m, n);
  Eigen::VectorXd factor = Eigen::VectorXd::Ones(m);
  for (Eigen::Index a = 0; a < m; ++a) {
    const ContactTangent& ct = contacts_[static_cast<size_t>(A[static_cast<size_t>(a)])];
    T_A.col(a) = ct.T;
    C_A.row(a) = ct.c.transpose();
    if (A[static_cast<size_t>(a)] == k) factor[a] = 1.0 + ct.r;
  }
  const Eigen::MatrixXd dV = Eigen::MatrixXd::Identity(n, n) -
                             T_A * (C_A * T_A).fullPivLu().solve(factor.asDiagonal() * C_A);
  const ContactTangent& K = contacts_[static_cast<size_t>(k)];
  const double vk = std::isnan(r.contact_velocity_before) ? K.c.dot(r.V_before) : r.contact_velocity_before;
  Defer(dV, HeldField(r.X_before, r.V_before, r.phase), K.c, vk, r.X_after, r.V_after, r.phase);
}

// Contacts Z closing at one instant (docs/contacts.md, "Periodic orbits"), in free flight (H empty)
// or while the contacts H are held. With W_jk ≠ 0 between two of them the map is discontinuous there:
// no Jacobian. With W_jk = 0 a perturbation splits the instant into the impacts one after the other,
// in the order their gaps close; the map is piecewise smooth, one piece per order, and continuous. Its
// Jacobian exists where every order gives the same one (the active set locally constant): the
// composite saltation of each order is computed (SequenceSaltation) when the next stretch names the
// flow after, and applied if they agree within rounding; otherwise the orbit is at a corner of the map
// (a genuine non-smooth point) and says so.
void TangentTracker::SimultaneousImpact(const Reset& r, std::vector<int> Z, std::vector<int> H) {
  for (size_t a = 0; a < Z.size(); ++a)
    for (size_t b = a + 1; b < Z.size(); ++b)
      if (Coupling(Z[a], Z[b]) != 0.0) {
        Undefined(kCoupledSimultaneousImpact);
        return;
      }
  std::sort(Z.begin(), Z.end());
  std::sort(H.begin(), H.end());
  pending_sim_.active = true;
  pending_sim_.Z = std::move(Z);
  pending_sim_.H = std::move(H);
  pending_sim_.X = r.X_after;
  pending_sim_.V_before = r.V_before;
  pending_sim_.V_after = r.V_after;
  pending_sim_.phase = r.phase;
  held_ = -2;  // the contact-force LCP after the instant decides the flow: the next stretch names it
  held_set_.clear();
}

// The impacts of `order` one after the other at one instant (flights of zero length between), from
// the flow held on H to the one held on `after`. Each is the impact law on A = H ∪ {j} with its
// pattern fixed (held contacts keep v = 0, factor 1; j bounces, 1 + r_j): ∂g_V = I − T_A W_AA⁻¹ diag(1,
// …, 1 + r_j) C_A, guard g_j, and S_j = ∂g + (f⁺ − ∂g f⁻)∇hᵀ/(∇h·f⁻) (docs/model.md §5.6) with f⁻ the
// flow before it and f⁺ the one after: held on H ∪ {j} when j lands plastically (r_j = 0) and the
// contact-force LCP keeps it, on H otherwise, and `after` for the last. M = S_m ⋯ S_1.
bool TangentTracker::SequenceSaltation(const std::vector<int>& order, const std::vector<int>& after,
                                       Eigen::MatrixXd& M, Eigen::VectorXd& V_end, std::string& why) const {
  const auto n = sys_.dof();
  const Eigen::VectorXd& X = pending_sim_.X;
  const double phase = pending_sim_.phase;
  std::vector<int> H = pending_sim_.H;
  Eigen::VectorXd V = pending_sim_.V_before;
  Eigen::VectorXd f_prev = SetField(H, X, V, phase);
  M = Eigen::MatrixXd::Identity(2 * n, 2 * n);
  const auto gather = [&](const std::vector<int>& set, Eigen::MatrixXd& T, Eigen::MatrixXd& C) {
    const auto m = static_cast<Eigen::Index>(set.size());
    T.resize(n, m);
    C.resize(m, n);
    for (Eigen::Index a = 0; a < m; ++a) {
      T.col(a) = contacts_[static_cast<size_t>(set[static_cast<size_t>(a)])].T;
      C.row(a) = contacts_[static_cast<size_t>(set[static_cast<size_t>(a)])].c.transpose();
    }
  };
  // The contact forces that hold `set` at (X, W): all positive, within the rounding of the forces.
  const auto holds = [&](const std::vector<int>& set, const Eigen::VectorXd& W) {
    if (set.empty()) return true;
    Eigen::MatrixXd T, C;
    gather(set, T, C);
    const Eigen::VectorXd a = Field(Mode::kFree, X, W, phase).tail(n);
    const Eigen::VectorXd Ca = C * a;
    const Eigen::VectorXd lam = (C * T).fullPivLu().solve(-Ca);
    const double tol = 1e-9 * (C.cwiseAbs() * a.cwiseAbs()).maxCoeff();
    return (lam.array() > tol).all();
  };
  for (size_t i = 0; i < order.size(); ++i) {
    const int j = order[i];
    const ContactTangent& K = contacts_[static_cast<size_t>(j)];
    const double d = K.c.dot(V);
    std::vector<int> A = H;
    A.push_back(j);
    Eigen::MatrixXd T_A, C_A;
    gather(A, T_A, C_A);
    Eigen::VectorXd factor = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(A.size()));
    factor[factor.size() - 1] = 1.0 + K.r;
    const Eigen::MatrixXd W = C_A * T_A;
    const Eigen::VectorXd P = W.fullPivLu().solve(-(factor.asDiagonal() * (C_A * V)));
    for (size_t a = 0; a < H.size(); ++a)
      if (P[static_cast<Eigen::Index>(a)] < -1e-9 * std::abs(P[P.size() - 1])) {
        why = fmt::format("contact {}'s impact at the instant of a simultaneous impact pushes held contact {} "
                          "off its stop: that pattern's saltation is not implemented",
                          j, H[a]);
        return false;
      }
    const Eigen::MatrixXd dV = Eigen::MatrixXd::Identity(n, n) - T_A * W.fullPivLu().solve(factor.asDiagonal() * C_A);
    const Eigen::VectorXd V_next = dV * V;
    std::vector<int> H_next;
    if (i + 1 == order.size()) {
      H_next = after;
    } else if (K.r == 0.0) {  // j at rest: held with H if the contact-force LCP keeps it, else it leaves
      std::vector<int> with = A;
      std::sort(with.begin(), with.end());
      if (holds(with, V_next)) {
        H_next = with;
      } else if (holds(H, V_next) && K.c.dot(SetField(H, X, V_next, phase).tail(n)) > 0) {
        H_next = H;
      } else {
        why = fmt::format("contact {} lands plastically at the instant of a simultaneous impact with neither "
                          "held nor leaving decided strictly (the active set changes there): no Jacobian",
                          j);
        return false;
      }
    } else {
      H_next = H;
      if (!holds(H, V_next)) {
        why = fmt::format("contact {}'s impact at the instant of a simultaneous impact ends a held contact's force: "
                          "the active set changes there, no Jacobian",
                          j);
        return false;
      }
    }
    const Eigen::VectorXd f_next = SetField(H_next, X, V_next, phase);
    Eigen::VectorXd u(2 * n);
    u.head(n) = f_next.head(n) - f_prev.head(n);
    u.tail(n) = f_next.tail(n) - dV * f_prev.tail(n);
    Eigen::MatrixXd S = Eigen::MatrixXd::Identity(2 * n, 2 * n);
    S.bottomRightCorner(n, n) = dV;
    S.leftCols(n) += u * (K.c.transpose() / d);
    M = (S * M).eval();
    f_prev = f_next;
    V = V_next;
    H = std::move(H_next);
  }
  V_end = V;
  return true;
}

void TangentTracker::ResolveSimultaneous(const std::vector<int>& after) {
  pending_sim_.active = false;
  std::vector<int> order = pending_sim_.Z;
  const Eigen::VectorXd& V = pending_sim_.V_before;
  for (const int j : order) {  // a contact at zero gap that does not close: a tangential touch
    const ContactTangent& K = contacts_[static_cast<size_t>(j)];
    if (!(K.c.dot(V) < -1e-9 * (K.c.cwiseProduct(V).cwiseAbs().sum() + 1e-300))) {
      singular_ = true;
      return;
    }
  }
  std::string names;
  for (const int j : order) names += (names.empty() ? "" : ", ") + std::to_string(j);
  if (order.size() > 4) {
    Undefined(fmt::format("a simultaneous impact of {} contacts ({}): its saltation is implemented for four at most",
                          order.size(), names));
    return;
  }
  Eigen::MatrixXd M0, M_last;
  double apart = 0;
  bool first = true;
  do {
    Eigen::MatrixXd M;
    Eigen::VectorXd V_end;
    std::string why;
    if (!SequenceSaltation(order, after, M, V_end, why)) {
      Undefined(why);
      return;
    }
    const double vscale = pending_sim_.V_after.cwiseAbs().maxCoeff() + V.cwiseAbs().maxCoeff();
    if ((V_end - pending_sim_.V_after).cwiseAbs().maxCoeff() > 1e-9 * vscale) {
      Undefined(fmt::format("the simultaneous impact of contacts {} left the run with velocities its impact law "
                            "taken one contact after the other does not give (another contact took an impulse): "
                            "its saltation is not implemented",
                            names));
      return;
    }
    if (first) {
      M0 = M;
      first = false;
    } else {
      apart = std::max(apart, (M - M0).cwiseAbs().maxCoeff());
    }
    M_last = std::move(M);
  } while (std::next_permutation(order.begin(), order.end()));
  // Every order's Jacobian the same within rounding (1e-8 relative; at a corner they differ by O(1)
  // in the entries the damping couples: measured 5e-3 to 1e-2): the map is smooth there.
  if (apart > 1e-8 * (1.0 + M0.cwiseAbs().maxCoeff()) && corner_.empty())
    corner_ = fmt::format("a simultaneous impact of contacts {} at a corner of the map (the orders in which a "
                          "perturbation closes their gaps give Jacobians {:.3g} apart: the damping couples the "
                          "impacts)",
                          names, apart);
  phi_ = ((piece_ == 0 ? M0 : M_last) * phi_).eval();
}

// The entry into a compliant stop's contact phase (docs/compliant.md (C3)-(C4)): the guard is the
// gap to the surface d = cᵀX − e − y, crossed with ḋ < 0; no jump, and the flows before and after
// differ by T λ = −c ḋ T in the acceleration and ḋ in ẏ (the surface follows the body in contact),
// so that S = I + (0; −c T; 1)(cᵀ, 0, −1): δẊ ← δẊ − c T δd, δy ← cᵀδX, with δd = cᵀδX − δy (δy = 0
// from an ordinary flight). A touch with ḋ = 0 is a grazing: the map is not smooth there.
void TangentTracker::CompliantEntry(const Reset& r) {
  const auto n = sys_.dof();
  const int j = contacts_.size() > 1 ? r.contact : 0;
  const ContactTangent& ct = contacts_[static_cast<size_t>(j)];
  const double rate = r.contact_velocity_before;
  const double scale = ct.c.cwiseProduct(r.V_before).cwiseAbs().sum() +
                       (r.relaxing ? ct.stiffness / ct.damping * std::abs(r.surface) : 0.0);
  if (!(rate < -1e-9 * scale) || !(scale > 0)) {
    Undefined(fmt::format("a contact phase of compliant contact {} that just touches (grazing: the gap's rate "
                          "at entry is {:.3g}, forcing phase {:.17g}): the map is not smooth there",
                          j, rate, r.phase));
    return;
  }
  Eigen::RowVectorXd dd = ct.c.transpose() * phi_.topRows(n);
  if (r.relaxing && relax_contact_ == j) dd -= dy_;
  if (ct.damping != 0) phi_.bottomRows(n).noalias() -= (ct.damping * ct.T) * dd;
  relax_contact_ = -1;
  relax_y_ = 0;
  dy_.setZero();
  compliant_ = j;
  held_ = -1;
}

// The exit of a compliant contact phase (docs/compliant.md (C5)-(C6)). Rule "gap" (or no dashpot):
// the guard g = cᵀX − e, crossed with ġ > 0; λ = −c ġ there, so S = I + (0; c T)(cᵀ, 0): δẊ ← δẊ +
// c T cᵀδX. Rule "force": the guard λ = −k g − c ġ, crossed with λ̇ < 0; the fields agree at λ = 0
// (the surface's ẏ = −(k/c) y = ġ too): S = I, and the surface left at y₀ = g carries δy = cᵀδX.
void TangentTracker::CompliantExit(const Reset& r) {
  const auto n = sys_.dof();
  const int j = contacts_.size() > 1 ? r.contact : 0;
  const ContactTangent& ct = contacts_[static_cast<size_t>(j)];
  const double gdot = r.contact_velocity_before;
  compliant_ = -1;
  if (ct.gap_exit) {
    const double scale = ct.c.cwiseProduct(r.V_before).cwiseAbs().sum();
    if (!(gdot > 1e-9 * scale) || !(scale > 0)) {
      Undefined(fmt::format("a contact phase of compliant contact {} that ends tangentially (the gap's rate at "
                            "exit is {:.3g}, forcing phase {:.17g}): the map is not smooth there",
                            j, gdot, r.phase));
      return;
    }
    if (ct.damping != 0) phi_.bottomRows(n).noalias() += (ct.damping * ct.T) * (ct.c.transpose() * phi_.topRows(n));
  } else {
    // λ̇ = −k ġ − c g̈ with g̈ = cᵀ(the free acceleration): λ = 0 at the exit.
    const Eigen::VectorXd f = Field(Mode::kFree, r.X_before, r.V_before, r.phase);
    const double gddot = ct.c.dot(f.tail(n));
    const double rate = -ct.stiffness * gdot - ct.damping * gddot;
    const double scale = ct.stiffness * ct.c.cwiseProduct(r.V_before).cwiseAbs().sum() +
                         ct.damping * ct.c.cwiseProduct(f.tail(n)).cwiseAbs().sum();
    if (!(rate < -1e-9 * scale) || !(scale > 0)) {
      Undefined(fmt::format("a contact phase of compliant contact {} whose force returns to 0 tangentially "
                            "(λ̇ = {:.3g} at exit, forcing phase {:.17g}): the map is not smooth there",
                            j, rate, r.phase));
      return;
    }
  }
  if (r.relaxing) {
    relax_contact_ = j;
    relax_y_ = r.surface;
    dy_ = ct.c.transpose() * phi_.topRows(n);
  }
}

void TangentTracker::OnReset(const Reset& r) {
  if (r.kind == ResetKind::kCompliantEntry) {
    CompliantEntry(r);
    return;
  }
  if (r.kind == ResetKind::kCompliantExit) {
    CompliantExit(r);
    return;
  }
  if (r.kind == ResetKind::kGrazing && contacts_[static_cast<size_t>(contacts_.size() > 1 ? r.contact : 0)].compliant) {
    Undefined(fmt::format("a touch of compliant contact {} that the flow does not push in (grazing, forcing phase "
                          "{:.17g}): the map is not smooth there",
                          contacts_.size() > 1 ? r.contact : 0, r.phase));
    return;
  }
  const auto n = sys_.dof();
  if (pending_sim_.active) {
    // A simultaneous impact that leaves several contacts at rest names them (kSimultaneous): the
    // contact-force LCP's choice is the next stretch's flow, which resolves the impact.
    if (r.kind == ResetKind::kHeldSet && r.cause == HeldSetCause::kSimultaneous) return;
    pending_sim_.active = false;
    Undefined("another event at the instant of a simultaneous impact: its saltation is not implemented");
  }
  if (pending_jump_.active) {
    pending_jump_.active = false;
    Undefined("another event at the instant of a chattering accumulation beside held contacts: its "
              "saltation is not implemented");
  }
  if (pending_.active && !(r.kind == ResetKind::kHeldSet &&
                           (r.cause == HeldSetCause::kEntry || r.cause == HeldSetCause::kAccumulation))) {
    pending_.active = false;
    Undefined("another event at the instant of a plastic landing beside a held contact: its saltation is "
              "not implemented");
  }
  const bool multi = contacts_.size() > 1;
  const int j = multi ? r.contact : 0;
  const ContactTangent& ct = contacts_[static_cast<size_t>(j)];
  const Eigen::VectorXd& c = ct.c;
  // Saltation matrix S = ∂g + (f⁺ − ∂g f⁻) ∇hᵀ / (∇h·f⁻), guard h = c_jᵀX − e_j (docs/model.md §5.6).
  const auto salt = [&](const Eigen::MatrixXd& dV, Mode after) {
    const double denom = std::isnan(r.contact_velocity_before) ? c.dot(r.V_before) : r.contact_velocity_before;
    Saltation(dV, Field(Mode::kFree, r.X_before, r.V_before, r.phase),
              Field(after, r.X_after, r.V_after, r.phase, j), c, denom);
  };
  const bool another_held = multi && held_ >= 0 && held_ != j;
  switch (r.kind) {
    case ResetKind::kImpact:
      if (multi && r.simultaneous)
        SimultaneousImpact(r, AtZeroGap(r, HeldNow()), HeldNow());
      else if (another_held)
        ImpactWhileHeld(r);
      else
        Impact(r, j);
      break;
    case ResetKind::kPlasticStick:
      if (another_held) {
        Undefined("sticking on two contacts at once: its saltation is not implemented");
        break;
      }
      salt(ct.Pi, Mode::kSticking);
      held_ = j;
      break;
    case ResetKind::kPlasticLeave:
      salt(ct.Pi, Mode::kFree);
      held_ = -1;
      break;
    case ResetKind::kRelease:
      held_ = -1;
      break;  // free and constrained fields coincide at R = 0: S = I
    case ResetKind::kCompliantEntry:
    case ResetKind::kCompliantExit:
      break;  // handled above
    case ResetKind::kGrazing:
      singular_ = true;  // square-root singularity of the maps (docs/model.md §5.7)
      break;
    case ResetKind::kHeldSet:  // entering or leaving a set of several held contacts
      switch (r.cause) {
        case HeldSetCause::kEntry:  // after a plastic landing: its impact was deferred (no jump here)
          if (!pending_.active) held_ = -2;
          break;
        case HeldSetCause::kRelease:  // λ_c = 0: the flows with and without c coincide, S = I
          held_ = -2;
          break;
        case HeldSetCause::kImpact:
          ImpactWhileSetHeld(r);
          break;
        case HeldSetCause::kAccumulation:
          HeldAccumulation(r);
          break;
        case HeldSetCause::kGrazing:
          singular_ = true;  // a tangential arrival: the maps are singular there (docs/model.md §5.7)
          held_ = -2;
          break;
        case HeldSetCause::kSimultaneous:
          // Contacts left at rest together by a simultaneous impact: that impact's composite saltation
          // waits for the next stretch (pending_sim_, which returned above), or was refused with its reason.
          held_ = -2;
          break;
      }
      break;
    case ResetKind::kAccumulation: {
      // L: flow over Δ∞(z_k) from the post-impact state z_k, then projection onto the stop
      // (docs/model.md §5.4, §5.4). D L = Π (Φ(Δ∞) + f_free(t∞⁻) ∇Δ∞ᵀ) − f_stick(t∞⁺) ∇Δ∞ᵀ, with ∇Δ∞ and
      // the state at t∞⁻ those of the jump the automaton took (dynamics/chatter_tail.hpp).
      held_ = j;
      if (!r.delta_gradient || !r.X_end || !r.V_end) {
        singular_ = true;
        break;
      }
      const Eigen::MatrixXd& Pi = ct.Pi;
      const double delta = r.delta;
      const double phase_inf = r.phase + sys_.frequency() * delta;
      const Eigen::VectorXd f_free = Field(Mode::kFree, *r.X_end, *r.V_end, phase_inf);
      const Eigen::VectorXd f_stick = Field(Mode::kSticking, r.X_after, r.V_after, phase_inf, j);
      const Eigen::RowVectorXd grad_phi = r.delta_gradient->transpose() * phi_;  // ∇Δ∞ᵀ Φ
      FreeFlight(delta, phi_);                                                      // Φ(Δ∞) Φ
      // P = diag(Π, Π), applied by blocks.
      phi_.topRows(n) = Pi * phi_.topRows(n);
      phi_.bottomRows(n) = Pi * phi_.bottomRows(n);
      Eigen::VectorXd jump(2 * n);
      jump << Pi * f_free.head(n), Pi * f_free.tail(n);
      phi_ += (jump - f_stick) * grad_phi;
      break;
    }
  }
}

MapValue StroboscopicMap(const System& sys, const Scene& scene, double t0, const Eigen::VectorXd& X,
                         const Eigen::VectorXd& V, int q, int piece) {
  Scene sc = scene;
  sc.run.periods = q;
  sc.run.samples_per_period = 0;
  const InitialOverride init{t0, X, V};
  TangentTracker tracker(sys);
  tracker.SetCornerPiece(piece);
  SimulationOptions opt;
  opt.initial = &init;
  opt.observers = {&tracker};
  opt.max_segments = kMapSegmentsPerPeriod * q;
  const RunResult r = Simulate(sys, sc, opt);
  MapValue v{r.X, r.V, tracker.jacobian(), tracker.singular(), tracker.undefined(), r.status, tracker.corner()};
  // A compliant stop's surface still relaxing at the section (docs/compliant.md, "Periodic orbits"):
  // the state (X, Ẋ) does not hold the surface, so the map of (X, Ẋ) is not the flow's.
  if (v.undefined.empty() && tracker.relaxing_contact() >= 0 && r.X.size() == sys.dof()) {
    const ContactModel& c = sys.contacts()[static_cast<size_t>(tracker.relaxing_contact())];
    const double scale = std::abs(c.stop) + c.shape.cwiseProduct(r.X).cwiseAbs().sum() + 1.0;
    if (std::abs(tracker.relaxing_surface()) > 8 * std::numeric_limits<double>::epsilon() * scale)
      v.undefined = fmt::format("a section inside the relaxing flight after a force-rule exit of compliant contact {} "
                                "(the surface is still {:.3g} from the stop there): the section state does not "
                                "hold the surface",
                                tracker.relaxing_contact(), tracker.relaxing_surface());
  }
  return v;
}

MapValue HalfPeriodFlow(const System& sys, const Scene& scene, double t0, const Eigen::VectorXd& X,
                        const Eigen::VectorXd& V, int q) {
  // Periods counted from t0 − T/2 (the start half way into period 0): (q + 1)/2 of them end at
  // t0 + qT/2.
  const double T = 2.0 * M_PI / sys.frequency();
  Scene sc = scene;
  sc.run.periods = (q + 1) / 2;
  sc.run.samples_per_period = 0;
  const InitialOverride init{t0, X, V};
  TangentTracker tracker(sys);
  SimulationOptions opt;
  opt.initial = &init;
  opt.section_origin = t0 - 0.5 * T;
  opt.observers = {&tracker};
  opt.loads = false;
  opt.max_segments = kMapSegmentsPerPeriod * sc.run.periods;
  const RunResult r = Simulate(sys, sc, opt);
  return MapValue{r.X, r.V, tracker.jacobian(), tracker.singular(), tracker.undefined(), r.status, tracker.corner()};
}

namespace {

// Whether a run of `scene` left undetermined by double can be redone in quad: the exact engine.
bool QuadDecides(const Scene& scene) {
  return scene.run.precision == Precision::kDouble && scene.run.engine == Engine::kExact;
}

}  // namespace

void Characterize(const System& sys, const Scene& scene, OrbitResult& out) {
  const int q = out.period;
  Scene sc = scene;
  sc.initial_time = out.section_time;
  sc.run.periods = 3 * q;
  sc.run.samples_per_period = 0;
  sc.run.max_period = q;
  const InitialOverride here{out.section_time, out.X, out.V};
  const Eigen::VectorXd z0 = Stack(out.X, out.V);
  SequenceRecorder events(q);
  const auto classify = [&](const Scene& at) {
    AttractorRecorder rec(sys, at);
    events = SequenceRecorder(q, out.section_time, HeldAtSection(sys, z0));
    SimulationOptions opt;
    opt.initial = &here;
    opt.observers = {&rec, &events};
    opt.max_segments = kMapSegmentsPerPeriod * sc.run.periods;
    const RunStatus status = Simulate(sys, at, opt).status;
    out.summary = rec.Classify();
    return status;
  };
  // Near the end of a sticking branch double may leave a chattering sequence of the orbit
  // undetermined: the exact engine then decides it in quad precision, as the map does.
  if (classify(sc) == RunStatus::kUndetermined && QuadDecides(sc)) {
    sc.run.precision = Precision::kQuad;
    classify(sc);
    ++out.quad_evaluations;
  }
  // The contact sequence: every scene with [[contact]] tables, also a single one (docs/contacts.md).
  if (sys.contact_count() > 1 || !scene.contacts.empty()) out.sequence = ContactSequenceText(ContactSequenceOf(events.events));
  // Directions collapsed by sticking (several contacts, or a compliant stop), −1: as one rigid contact.
  const bool compliant = std::any_of(sys.contacts().begin(), sys.contacts().end(), [](const ContactModel& c) {
    return c.spec.compliance.compliant();
  });
  const int collapsed = sys.contact_count() > 1 || compliant ? events.Collapsed(sys) : -1;
  // The compliant contact phases of the orbit's q periods, with their loads (the release events).
  out.contact_phases.clear();
  std::vector<const Event*> open(static_cast<size_t>(sys.contact_count()), nullptr);
  for (const Event& e : events.events) {
    if (!sys.contacts()[static_cast<size_t>(e.contact)].spec.compliance.compliant()) continue;
    if (e.kind == EventKind::kStick) open[static_cast<size_t>(e.contact)] = &e;
    if (e.kind != EventKind::kRelease) continue;
    OrbitResult::ContactPhase p;
    p.contact = e.contact;
    p.exit = e.t;
    p.duration = e.stick_duration;
    p.entry = open[static_cast<size_t>(e.contact)] ? open[static_cast<size_t>(e.contact)]->t : e.t - e.stick_duration;
    p.entry_velocity = open[static_cast<size_t>(e.contact)] ? open[static_cast<size_t>(e.contact)]->v_before
                                                            : std::numeric_limits<double>::quiet_NaN();
    p.exit_velocity = e.v_before;
    p.peak_force = e.reaction_max;
    p.peak_time = e.peak_time;
    p.penetration = e.penetration_max;
    p.impulse = e.reaction_integral;
    p.dissipated = e.energy_dissipated;
    out.contact_phases.push_back(p);
    open[static_cast<size_t>(e.contact)] = nullptr;
  }
  if (!out.no_jacobian.empty()) {
    out.multipliers.clear();
    out.stable = false;
    return;
  }
  Eigen::ComplexEigenSolver<Eigen::MatrixXcd> es(out.monodromy.cast<std::complex<double>>());
  std::vector<std::complex<double>> mu(es.eigenvalues().data(),
                                       es.eigenvalues().data() + es.eigenvalues().size());
  std::sort(mu.begin(), mu.end(), [](auto x, auto y) { return std::abs(x) > std::abs(y); });
  // Sticking collapses x_B and ẋ_B: DF has two zero eigenvalues that are not multipliers of DP.
  // Several contacts: two per independent held contact (DF has that many zero eigenvalues).
  if (collapsed >= 0)
    mu.resize(mu.size() >= static_cast<size_t>(collapsed) ? mu.size() - static_cast<size_t>(collapsed) : 0);
  else if (!out.summary.stick_phases.empty() || HoldsContact(out.summary.kind))
    mu.resize(mu.size() >= 2 ? mu.size() - 2 : 0);
  out.multipliers = mu;
  out.stable = std::all_of(mu.begin(), mu.end(), [](auto x) { return std::abs(x) < 1.0; });
}


namespace {

// The orbit's events over its q periods from its section, in time order (as Characterize reads
// its sequence); none when the run fails.
std::vector<Event> EventsFromSection(const System& sys, const Scene& scene, const OrbitResult& o) {
  Scene sc = scene;
  sc.initial_time = o.section_time;
  sc.run.periods = o.period;
  sc.run.samples_per_period = 0;
  const InitialOverride here{o.section_time, o.X, o.V};
  const auto run = [&](const Scene& at) {
    SequenceRecorder events(o.period, o.section_time, HeldAtSection(sys, Stack(o.X, o.V)));
    SimulationOptions opt;
    opt.initial = &here;
    opt.observers = {&events};
    opt.max_segments = kMapSegmentsPerPeriod * o.period;
    const RunStatus status = Simulate(sys, at, opt).status;
    return std::make_pair(status, std::move(events.events));
  };
  auto [status, events] = run(sc);
  if (status == RunStatus::kUndetermined && QuadDecides(sc)) {
    sc.run.precision = Precision::kQuad;
    std::tie(status, events) = run(sc);
  }
  return status == RunStatus::kOk ? events : std::vector<Event>{};
}

}  // namespace

void StartAtCanonicalRotation(const System& sys, const Scene& scene, const OrbitRequest& req, OrbitResult& orbit) {
  if (orbit.status != "converged" || orbit.sequence.empty() || orbit.period < 1) return;
  const std::vector<Event> events = EventsFromSection(sys, scene, orbit);
  std::vector<size_t> first;
  const std::vector<std::string> word = ContactSequenceOf(events, &first);
  if (word.size() < 2 || CanonicalRotation(word) == word) return;  // already read from its start
  const size_t s = CanonicalStart(word);
  if (s == 0 || s >= first.size() || first[s] == 0) return;
  // The stretch between the event before the canonical start and its first event: its middle, on
  // a grid of T/N from the section (N = 1024·2^k, fine enough for a quarter of the stretch).
  const double T = sys.period(), t_prev = events[first[s] - 1].t, t_first = events[first[s]].t;
  const double stretch = t_first - t_prev;
  long long N = 1024;
  while (T / static_cast<double>(N) > stretch / 4 && N < (1LL << 16)) N *= 2;
  if (!(T / static_cast<double>(N) <= stretch / 4)) return;  // too short a stretch: kept as found
  const double h = T / static_cast<double>(N);
  const long long j = std::llround((0.5 * (t_prev + t_first) - orbit.section_time) / h);
  SampleCatcher catcher;
  catcher.target_time = orbit.section_time + static_cast<double>(j) * h;
  catcher.half_spacing = 0.5 * h;
  {
    Scene sc = scene;
    sc.initial_time = orbit.section_time;
    sc.run.periods = static_cast<long long>(std::floor(static_cast<double>(j) / static_cast<double>(N))) + 1;
    sc.run.samples_per_period = static_cast<int>(N);
    const InitialOverride here{orbit.section_time, orbit.X, orbit.V};
    SimulationOptions opt;
    opt.initial = &here;
    opt.observers = {&catcher};
    opt.max_segments = kMapSegmentsPerPeriod * sc.run.periods;
    const RunStatus status = Simulate(sys, sc, opt).status;
    if (status != RunStatus::kOk && !(status == RunStatus::kUndetermined && QuadDecides(sc))) return;
    if (status != RunStatus::kOk) {
      sc.run.precision = Precision::kQuad;
      catcher.caught = false;
      catcher.seen = 0;
      Simulate(sys, sc, opt);
    }
  }
  if (!catcher.caught || !(catcher.t > t_prev && catcher.t < t_first)) return;
  // A free section only: one inside a held phase would cut that phase's stick from its release.
  if (catcher.mode != Mode::kFree) return;
  // Newton there (a polish: the point is on the orbit to the transport's rounding), then the
  // orbit characterized again from it.
  OrbitResult moved;
  moved.period = orbit.period;
  NewtonOnStroboscopicMap(sys, scene, catcher.t, Stack(catcher.X, catcher.V), orbit.period, req, moved);
  if (moved.status != "converged") return;
  Characterize(sys, scene, moved);
  if (moved.sequence != orbit.sequence || moved.summary.kind != orbit.summary.kind ||
      moved.summary.period != orbit.summary.period)
    return;
  const std::vector<std::string> from_new = ContactSequenceOf(EventsFromSection(sys, scene, moved));
  if (from_new != CanonicalRotation(from_new)) return;
  moved.newton_iterations += orbit.newton_iterations;
  moved.quad_evaluations += orbit.quad_evaluations;
  moved.message = orbit.message;
  moved.distance_from_start = orbit.distance_from_start;
  moved.reached = orbit.reached;
  moved.undetermined = orbit.undetermined;
  orbit = std::move(moved);
}

// Newton on F(z) − z from z at the section time t0, with the analytic DF; the step is halved while
// it would put a contact on or through its stop. A section held on contacts S (an orbit of several
// contacts whose every period has a contact held, e.g. a stacked cradle whose lower mass never
// leaves its stop) restricts the unknowns to the held manifold {C_S X = e_S, C_S Ẋ = 0}: z = z₀ + B y
// with B an orthonormal basis of ker diag(C_S, C_S), and Newton solves Bᵀ(DF − I)B y = −Bᵀ r
// (F maps the manifold into itself). The monodromy reported is then DF·diag(P_S, P_S), P_S =
// I − T_S W_SS⁻¹ C_S the plastic projection onto the set: its eigenvalues are those of DF on the
// manifold and 2|S| zeros, the constrained directions.
void NewtonOnStroboscopicMap(const System& sys, const Scene& scene, double t0, Eigen::VectorXd z,
                             int q, const OrbitRequest& req, OrbitResult& out) {
  const auto n = sys.dof();
  const std::vector<int> held = HeldAtSection(sys, z);
  const auto is_held = [&](int j) { return std::find(held.begin(), held.end(), j) != held.end(); };
  // Every gap open (one contact: x_B above the stop), the held ones excepted.
  const auto admissible = [&](const Eigen::VectorXd& zz) {
    for (int j = 0; j < sys.contact_count(); ++j) {
      const ContactModel& c = sys.contacts()[static_cast<size_t>(j)];
      if (!is_held(j) && !(c.shape.dot(zz.head(n)) > c.stop)) return false;
    }
    return true;
  };
  Eigen::MatrixXd B = Eigen::MatrixXd::Identity(2 * n, 2 * n), Pz;
  if (!held.empty()) {
    const auto m = static_cast<Eigen::Index>(held.size());
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(2 * m, 2 * n), T(n, m), Cs(m, n);
    for (Eigen::Index a = 0; a < m; ++a) {
      const ContactModel& c = sys.contacts()[static_cast<size_t>(held[static_cast<size_t>(a)])];
      C.block(a, 0, 1, n) = c.shape.transpose();
      C.block(m + a, n, 1, n) = c.shape.transpose();
      T.col(a) = c.contact;
      Cs.row(a) = c.shape.transpose();
    }
    Eigen::FullPivLU<Eigen::MatrixXd> lu(C);
    B = lu.kernel();
    B = Eigen::HouseholderQR<Eigen::MatrixXd>(B).householderQ() * Eigen::MatrixXd::Identity(2 * n, B.cols());
    const Eigen::MatrixXd P = Eigen::MatrixXd::Identity(n, n) - T * (Cs * T).fullPivLu().solve(Cs);
    Pz = Eigen::MatrixXd::Zero(2 * n, 2 * n);
    Pz.topLeftCorner(n, n) = P;
    Pz.bottomRightCorner(n, n) = P;
  }
  MapValue m;
  for (int it = 0; it <= req.max_iterations; ++it) {
    m = StroboscopicMap(sys, scene, t0, z.head(n), z.tail(n), q);
    // Near the end of a sticking branch the double engine's chattering tails can reach the
    // rounding floor of ẋ_B before their accumulation point is predicted (docs/chattering.md):
    // that evaluation is redone with the quad engine, as continuation does.
    if (m.status == RunStatus::kUndetermined && QuadDecides(scene)) {
      Scene quad = scene;
      quad.run.precision = Precision::kQuad;
      m = StroboscopicMap(sys, quad, t0, z.head(n), z.tail(n), q);
      ++out.quad_evaluations;
    }
    if (m.status != RunStatus::kOk) {
      out.message = "the map evaluation failed (numerical failure of the simulation)";
      break;
    }
    if (!held.empty() && m.jacobian.size() > 0) m.jacobian = m.jacobian * Pz;
    const Eigen::VectorXd r = Stack(m.X, m.V) - z;
    out.residual = r.cwiseAbs().maxCoeff() / (1.0 + z.cwiseAbs().maxCoeff());
    out.newton_iterations = it;
    if (out.residual < req.tolerance) {
      out.status = "converged";
      if (!m.undefined.empty()) out.no_jacobian = "the orbit passes through " + m.undefined;
      if (m.undefined.empty() && !m.corner.empty()) {
        // A corner (docs/contacts.md, "Periodic orbits"): the map is piecewise smooth there, and its
        // multipliers exist when the pieces share them (a symmetric orbit: the corner's rank-one
        // difference maps antisymmetric perturbations onto symmetric ones only). The first order's
        // monodromy against the last order's.
        MapValue other = StroboscopicMap(sys, scene, t0, z.head(n), z.tail(n), q, 1);
        if (!held.empty() && other.jacobian.size() > 0) other.jacobian = other.jacobian * Pz;
        const auto spectrum = [](const Eigen::MatrixXd& A) {
          Eigen::ComplexEigenSolver<Eigen::MatrixXcd> es(A.cast<std::complex<double>>());
          std::vector<std::complex<double>> mu(es.eigenvalues().data(), es.eigenvalues().data() + es.eigenvalues().size());
          std::sort(mu.begin(), mu.end(), [](auto x, auto y) {
            return std::abs(x) != std::abs(y) ? std::abs(x) > std::abs(y) : std::arg(x) < std::arg(y);
          });
          return mu;
        };
        const auto a = spectrum(m.jacobian), b = spectrum(other.jacobian);
        double gap = a.size() == b.size() ? 0.0 : 1.0;
        for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
          // a complex pair's order within the pair is free: compare with the nearer of the two
          double d = std::abs(a[i] - b[i]);
          if (i + 1 < b.size()) d = std::min(d, std::abs(a[i] - b[i + 1]));
          if (i > 0) d = std::min(d, std::abs(a[i] - b[i - 1]));
          gap = std::max(gap, d);
        }
        if (gap > 1e-9)
          out.no_jacobian = fmt::format("the orbit passes through {}, and the pieces' multipliers differ by {:.3g}: "
                                        "no Floquet multipliers", m.corner, gap);
      }
      break;
    }
    if (!m.undefined.empty()) {
      out.message = "the map has no Jacobian on the way: " + m.undefined;
      break;
    }
    if (m.singular) {
      out.message = "a grazing contact on the orbit makes the map singular";
      break;
    }
    const Eigen::MatrixXd J = B.transpose() * (m.jacobian - Eigen::MatrixXd::Identity(2 * n, 2 * n)) * B;
    const Eigen::VectorXd step = -B * J.fullPivLu().solve(B.transpose() * r);
    double lambda = 1.0;
    Eigen::VectorXd next = z + step;
    for (int h = 0; h < 30 && !admissible(next); ++h) {
      lambda *= 0.5;
      next = z + lambda * step;
    }
    z = next;
  }
  out.section_time = t0;
  out.X = z.head(n);
  out.V = z.tail(n);
  out.monodromy = m.jacobian;
}

OrbitResult FindOrbit(const System& sys, const Scene& scene, const OrbitRequest& req) {
  OrbitResult out;
  const double T = sys.period(), w = sys.frequency();
  const auto n = sys.dof();

  // 1. A transient from the scene's state (or the guess) to the attractor.
  const auto transient = [&](const InitialOverride* init, Attractor& a, TransientLog& log,
                             RunResult& end) {
    Scene sc = scene;
    sc.run.periods = req.transient_periods;
    sc.run.samples_per_period = 0;
    if (req.period > 0) sc.run.max_period = std::max(sc.run.max_period, req.period);
    if (init) sc.initial_time = init->time;
    AttractorRecorder rec(sys, sc);
    log.keep_from = req.transient_periods - 2LL * sc.run.max_period - 2;
    SimulationOptions opt;
    opt.initial = init;
    opt.observers = {&rec, &log};
    end = Simulate(sys, sc, opt);
    a = rec.Classify();
  };
  const auto matches = [&](const Attractor& a) {
    if (req.kind == OrbitKind::kSticking) return HoldsContact(a.kind);
    return a.kind == "impact-periodic" &&
           (req.impacts == 0 || a.impacts_per_period == req.impacts);
  };
  const auto start_at = [&](double phase, double velocity) {
    InitialOverride init{phase / w, sys.stop() * sys.static_shape(),
                         sys.contact() * (velocity / sys.s_B())};
    if (sys.stop() < 0) init.X = Eigen::VectorXd::Zero(n);  // clearance: from the origin
    return init;
  };
  Attractor a;
  TransientLog log;
  RunResult end;
  double t_start = scene.initial_time;
  std::optional<InitialOverride> init;
  if (req.guess_phase)
    init = start_at(*req.guess_phase, req.guess_velocity.value_or(0.0));
  else if (req.start)
    init = *req.start;
  transient(init ? &*init : nullptr, a, log, end);
  if (init) t_start = init->time;
  if (!matches(a) && req.kind == OrbitKind::kImpact && !req.guess_phase && !req.start) {
    // Impact orbits often coexist with the sticking one: look from departures of several
    // phases and speeds.
    const double scale = std::max(1.0, std::abs(sys.stop())) * w;
    for (int i = 0; i < 16 && !matches(a); ++i) {
      for (double v : {0.5 * scale, 2.0 * scale, 4.0 * scale}) {
        init = start_at(2.0 * M_PI * i / 16.0, v);
        log = TransientLog();
        transient(&*init, a, log, end);
        t_start = init->time;
        if (matches(a)) break;
      }
    }
  }
  // Newton also starts from a transient that did not settle (a slow transient, or an unstable
  // orbit surrounded by a torus or a chaotic set).
  if (!matches(a) && a.kind != "not-periodic") {
    out.status = "no-orbit";
    out.message = "the transient reached a " + a.kind + " attractor, not the requested kind; give "
                  "--guess PHASE[,VELOCITY] or --period";
    return out;
  }
  // A transient that has not settled yet gives its state as the guess (period 1 unless given).
  const int q = req.period > 0 ? req.period : a.period.value_or(1);
  out.period = q;

  // 2. The section: the middle of the longest free flight of the last q periods.
  const long long K = req.transient_periods;
  const double tK = t_start + static_cast<double>(K) * T, from = tK - q * T;
  std::vector<Event> ev;
  for (const auto& e : log.events)
    if (e.t > from - 1e-12 && e.t <= tK) ev.push_back(e);
  double best = 0, t_mid = 0;
  // Free after an impact or a release (a plastic impact that sticks is followed by a stick at
  // the same time), on the stop after a stick or an accumulation; with several contacts, an
  // impact of another contact while one sticks leaves it stuck (its release says when it leaves).
  const auto update = [](int held, const Event& e) {
    if (e.kind == EventKind::kStick || e.kind == EventKind::kAccumulation) return e.contact;
    if (e.kind == EventKind::kRelease) return e.contact == held ? -1 : held;
    if (e.kind == EventKind::kImpact) return held >= 0 && e.contact != held ? held : -1;
    return held;
  };
  int held = -1;  // the contact held at `from` (−1: free)
  for (const auto& e : log.events) {
    if (e.t > from) break;
    held = update(held, e);
  }
  double last = from;
  for (const auto& e : ev) {
    if (held < 0 && e.t - last > best) {
      best = e.t - last;
      t_mid = 0.5 * (e.t + last);
    }
    held = update(held, e);
    last = e.t;
  }
  if (held < 0 && tK - last > best) {
    best = tK - last;
    t_mid = 0.5 * (tK + last);
  }
  // Several contacts: an orbit whose every period has a contact held (e.g. a stacked cradle whose
  // lower mass never leaves its stop while the upper one bounces on it) has its section in the
  // longest stretch between two events, held or free; Newton then works on the held manifold.
  const bool multi = sys.contact_count() > 1;
  const auto longest_stretch = [&] {
    double b = 0, mid = 0, prev = from;
    for (const auto& e : ev) {
      if (e.t - prev > b) {
        b = e.t - prev;
        mid = 0.5 * (e.t + prev);
      }
      prev = e.t;
    }
    if (tK - prev > b) mid = 0.5 * (tK + prev);
    return mid;
  };
  if (best <= 0 && multi) {
    best = 1;
    t_mid = longest_stretch();
  }
  if (best <= 0) {
    out.status = "no-orbit";
    out.message = "the orbit has no free flight (permanent contact)";
    return out;
  }
  // The state at t_mid + qT, from the end of the transient (one orbit period later).
  constexpr int kSamples = 1024;
  SampleCatcher catcher;
  // The transient's end state is a restart point unless it is on a contact moving into it (e.g. a start right
  // after an impact on the orbit: every period boundary is then an impact, and the run may end
  // with the state just before it, which a new run does not take as an impact). Then the same run
  // is made again, K + q periods from the same start, and the sample caught inside it.
  const bool event_at_end =
      end.X.size() == n && std::any_of(sys.contacts().begin(), sys.contacts().end(), [&](const ContactModel& c) {
        return std::abs(c.shape.dot(end.X) - c.stop) <= 1e-9 * std::max(1.0, std::abs(c.stop)) &&
               c.shape.dot(end.V) < 0;  // on it and moving into it: an impact not yet applied
      });
  const auto from_end = [&] {
    catcher = SampleCatcher();
    catcher.target = std::llround((t_mid + q * T - tK) / (T / kSamples));
    Scene sc = scene;
    sc.run.periods = q;
    sc.run.samples_per_period = kSamples;
    const InitialOverride here{tK, end.X, end.V};
    SimulationOptions opt;
    opt.initial = &here;
    opt.observers = {&catcher};
    Simulate(sys, sc, opt);
  };
  if (event_at_end) {
    Scene sc = scene;
    sc.run.periods = K + q;
    sc.run.samples_per_period = kSamples;
    if (req.period > 0) sc.run.max_period = std::max(sc.run.max_period, req.period);
    if (init) sc.initial_time = init->time;
    catcher.target_time = t_start + static_cast<double>(std::llround((t_mid + q * T - t_start) / (T / kSamples))) * (T / kSamples);
    catcher.half_spacing = 0.5 * T / kSamples;
    SampleCatcher at_end;  // the rerun's state at tK, to see that it repeats the transient
    at_end.target_time = tK;
    at_end.half_spacing = 0.5 * T / kSamples;
    SimulationOptions opt;
    opt.initial = init ? &*init : nullptr;
    opt.observers = {&catcher, &at_end};
    Simulate(sys, sc, opt);
    // A transient that has not settled may not repeat itself with dense samples (a sensitive
    // chattering motion): then the end state it is.
    const bool repeated = at_end.caught && (at_end.X - end.X).norm() <= 1e-9 * (1.0 + end.X.norm());
    if (!repeated || !catcher.caught || catcher.mode != Mode::kFree) from_end();
  } else {
    from_end();
  }
  if (multi && (!catcher.caught || catcher.mode != Mode::kFree)) {
    // The flight believed free was held (a contact held since before the transient's log): the
    // section goes to the longest stretch between events, held or not.
    t_mid = longest_stretch();
    if (event_at_end) {
      catcher = SampleCatcher();
      Scene sc = scene;
      sc.run.periods = K + q;
      sc.run.samples_per_period = kSamples;
      if (req.period > 0) sc.run.max_period = std::max(sc.run.max_period, req.period);
      if (init) sc.initial_time = init->time;
      catcher.target_time = t_start + static_cast<double>(std::llround((t_mid + q * T - t_start) / (T / kSamples))) * (T / kSamples);
      catcher.half_spacing = 0.5 * T / kSamples;
      SimulationOptions opt;
      opt.initial = init ? &*init : nullptr;
      opt.observers = {&catcher};
      Simulate(sys, sc, opt);
    } else {
      from_end();
    }
  }
  if (!catcher.caught || (!multi && catcher.mode != Mode::kFree)) {
    out.status = "no-orbit";
    out.message = multi ? "could not place the section on the orbit" : "could not place the section in a free flight";
    return out;
  }
  const double t0 = catcher.t;
  Eigen::VectorXd z = Stack(catcher.X, catcher.V);

  // 3. Newton on F(z) − z with the analytic DF.
  NewtonOnStroboscopicMap(sys, scene, t0, z, q, req, out);
  if (out.status != "converged") {
    if (out.message.empty()) out.message = "Newton did not converge";
    return out;
  }

  // 4. Summary over the converged orbit, and the multipliers.
  Characterize(sys, scene, out);
  // kAuto (a transient that has not settled): an orbit of either kind is what was asked for.
  const bool kind_ok = req.kind == OrbitKind::kSticking ? HoldsContact(out.summary.kind)
                       : req.kind == OrbitKind::kImpact ? out.summary.kind == "impact-periodic"
                                                        : HoldsContact(out.summary.kind) ||
                                                              out.summary.kind == "impact-periodic";
  if (!kind_ok) {
    out.status = "no-orbit";
    out.message = "Newton converged to a " + out.summary.kind + " orbit, not the requested kind";
  }
  return out;
}

}  // namespace vibro
