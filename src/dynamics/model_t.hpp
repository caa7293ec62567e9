// The modal model of a System in the engine's scalar S (double, or quad for the reference engine):
// the data of docs/model.md §1.3 and §4.2 converted once, and the contact quantities the automaton needs.
// The quad model is the double model's data converted exactly: the quad engine solves the same
// (double-rounded) structure, so differences between the engines are the engines' own errors.
#pragma once

#include <Eigen/Dense>

#include "dynamics/harmonic_forcing.hpp"
#include "dynamics/scalar.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

template <class S>
struct ModelT {
  using Vec = Eigen::Matrix<S, Eigen::Dynamic, 1>;
  using Mat = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;

  // The model seen by contact j (docs/contacts.md): its gap c_jᵀX − e_j, its impact law and the
  // flow with it held. j = 0 is the single stop's model, to the bit.
  explicit ModelT(const System& sys, int j = 0)
      : ModelT(sys, sys.contacts()[static_cast<size_t>(j)]) {}

  ModelT(const System& sys, const ContactModel& k)
      : omega(sys.omega().cast<S>()),
        forcing(sys.forcing().cast<S>()),
        contact(k.contact.cast<S>()),
        shape(k.shape.cast<S>()),
        zeta(sys.damping().cast<S>()),
        damped(sys.damped()),
        s_A(k.s_A),
        s_B(k.s_B),
        x0(k.stop),
        r(k.restitution),
        f(sys.harmonic_sum() ? 0.0 : sys.amplitude()),
        w(sys.frequency()),
        period(S(2) * Real<S>::pi() / S(sys.frequency())),
        flexibility(k.flexibility),
        static_shape(k.static_shape.cast<S>()),
        stick_frequencies(k.constrained.frequencies.cast<S>()),
        stick_vectors(k.constrained.vectors.cast<S>()),
        stick_left(k.constrained.left.cast<S>()),
        stick_forcing(k.constrained.modal_forcing.cast<S>()),
        stick_reaction(k.constrained.reaction.cast<S>()),
        side(k.spec.side == Side::kAbove ? S(-1) : S(1)),
        harmonics(sys, static_cast<int>(&k - sys.contacts().data())),
        compliant(k.spec.compliance.compliant()),
        stiffness(k.spec.compliance.stiffness),
        damping(k.spec.compliance.damping),
        separation(k.spec.compliance.separation) {
    for (Eigen::Index i = 0; i < omega.size(); ++i) {
      contact_stiffness += shape[i] * contact[i] * omega[i] * omega[i];
      contact_damping += shape[i] * contact[i] * S(2) * zeta[i] * omega[i];
      if (shape[i] != S(0) && shape[i] != S(1)) unit_shape = false;
    }
    contact_stiffness /= s_B;
    contact_damping /= s_B;
  }

  int dof() const { return static_cast<int>(omega.size()); }

  // Inlined on the hot paths of every event (their callers grew with several contacts).
  [[gnu::always_inline]] S ContactDisplacement(const Vec& X) const { return shape.dot(X); }
  [[gnu::always_inline]] S ContactVelocity(const Vec& V) const { return shape.dot(V); }

  // R = (Σ c_i(ω_i² X_i + 2ζ_iω_i Ẋ_i) − s_A f sin φ)/s_B (the paper's eq. (5); docs/model.md §7).
  [[gnu::always_inline]] S Reaction(const Vec& X, const Vec& V, const S& phase) const {
    return ReactionSin(X, V, Real<S>::sin(phase), &phase);
  }
  // The same with sin φ at hand; a sum of harmonics needs the phase φ itself.
  [[gnu::always_inline]] S ReactionSin(const Vec& X, const Vec& V, const S& sin_phase,
                                       const S* phase = nullptr) const {
    S elastic(0);
    if (unit_shape) {  // the contact of the scaling (every c_i is 0 or 1): no products by c_i
      for (Eigen::Index i = 0; i < X.size(); ++i) {
        if (shape[i] == S(0)) continue;
        elastic += omega[i] * omega[i] * X[i] + S(2) * zeta[i] * omega[i] * V[i];
      }
    } else {
      for (Eigen::Index i = 0; i < X.size(); ++i) {
        if (shape[i] == S(0)) continue;
        elastic += shape[i] * (omega[i] * omega[i] * X[i] + S(2) * zeta[i] * omega[i] * V[i]);
      }
    }
    if (!harmonics.empty()) return (elastic - harmonics.Contact(*phase)) / s_B;
    return (elastic - s_A * f * sin_phase) / s_B;
  }

  // Ṙ along the sticking flow (docs/model.md §4.2; damped constrained acceleration of §7).
  S ReactionRate(const Vec& X, const Vec& V, const S& phase) const {
    return ReactionRateTrig(X, V, Real<S>::sin(phase), Real<S>::cos(phase), &phase);
  }
  // The same with sin φ, cos φ at hand, without allocation: the products are summed in the order
  // of the vector expression; damped, the free acceleration is kept in a per-thread scratch vector
  // (the same element-wise operations as the temporaries it replaces, so the same doubles).
  S ReactionRateTrig(const Vec& X, const Vec& V, const S& sin_phase, const S& cos_phase,
                     const S* phase = nullptr) const {
    if (!harmonics.empty()) {  // a sum of harmonics (docs/harmonics.md)
      S rate = shape.dot(omega.cwiseAbs2().cwiseProduct(V)) - harmonics.Contact(*phase, 1);
      if (damped) {
        const Vec free_acc = -omega.cwiseAbs2().cwiseProduct(X) -
                             S(2) * zeta.cwiseProduct(omega).cwiseProduct(V) + harmonics.Vector(*phase);
        const S pull = shape.dot(free_acc) / s_B;
        rate += shape.dot(S(2) * zeta.cwiseProduct(omega).cwiseProduct(free_acc - contact * pull));
      }
      return rate / s_B;
    }
    S rate = shape.dot(omega.cwiseAbs2().cwiseProduct(V)) - s_A * f * w * cos_phase;
    if (damped) {
      thread_local Vec free_acc;
      free_acc.resize(X.size());
      free_acc = -omega.cwiseAbs2().cwiseProduct(X) - S(2) * zeta.cwiseProduct(omega).cwiseProduct(V) +
                 forcing * (f * sin_phase);
      const S pull = shape.dot(free_acc) / s_B;
      rate += shape.dot(S(2) * zeta.cwiseProduct(omega).cwiseProduct(free_acc - contact * pull));
    }
    return rate / s_B;
  }

  // Restitution law (the paper's eq. (12)).
  void ApplyImpact(Vec& V, const S& restitution) const {
    const S p = -(S(1) + restitution) * ContactVelocity(V) / s_B;
    V += p * contact;
  }
  // Plastic projection onto the stop (docs/model.md §4.4).
  void ProjectOntoStop(Vec& X, Vec& V) const {
    V -= contact * (ContactVelocity(V) / s_B);
    X -= contact * ((ContactDisplacement(X) - x0) / s_B);
  }

  Vec omega, forcing, contact, shape, zeta;
  bool damped;
  S s_A, s_B, x0, r, f, w, period, flexibility;
  Vec static_shape;
  Vec stick_frequencies;  // ω'_k
  Mat stick_vectors;      // v_k (columns)
  Mat stick_left;         // l_kᵀ (rows)
  Vec stick_forcing;      // l_kᵀ F_c
  Vec stick_reaction;     // ρ_k
  S side{1};               // σ: the physical coordinate wᵀq is σ·cᵀX (docs/contacts.md)
  bool unit_shape = true;  // every c_i is 0 or 1 (contact 0, the contact of the scaling)
  S contact_stiffness{0};  // ω_c² = Σ c_i T_B,i ω_i² / s_B, the stiffness the contact point sees
  // A sum of harmonics (docs/harmonics.md); empty for today's forcing f sin ωt.
  HarmonicsT<S> harmonics;
  S contact_damping{0};    // β = Σ c_i T_B,i 2ζ_iω_i / s_B, the damping the contact velocity feels
  // A compliant stop (docs/compliant.md, dynamics/compliant_contact.hpp): λ = −k g − c ġ in contact.
  bool compliant = false;
  double stiffness = 0, damping = 0;
  Separation separation = Separation::kForce;
};

}  // namespace vibro::detail
