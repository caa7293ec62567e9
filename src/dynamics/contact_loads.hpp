// What the contacts endure, per event (docs/loads.md): the impulse and dissipated energy of an
// impact, the summed tail of a chattering sequence, and the duration, ∫R dt and max R of a
// sticking phase. The automaton (automaton.hpp) calls these at its events and after every sticking
// segment; everything is in the contact's physical units (impulse = effective mass m = 1/s_B
// times a gap velocity, the paper's eq. (10)-(11); R of the paper's eq. (5)).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "dynamics/model_t.hpp"
#include "dynamics/propagator.hpp"
#include "dynamics/reaction_max.hpp"
#include "vibro/observer.hpp"

namespace vibro::detail {

// An impact of one contact with gap velocities v⁻ → v⁺. `impulse` ≥ 0 is P when the caller knows it
// (the impact LCP); otherwise P = (v⁺ − v⁻)/s_B, exact for an impact of this contact alone
// (the paper's eq. (11): v⁺ − v⁻ = s_B P). The energy dissipated is −P(v⁻ + v⁺)/2, which is
// ½(1 − r)P|v⁻| whenever v⁺ = −r v⁻ (docs/loads.md §1): the share of this contact in the loss of
// kinetic energy ΔT = Σ_j P_j(v_j⁻ + v_j⁺)/2 of the impact.
template <class S>
void ImpactLoads(Event& e, const ModelT<S>& m, const S& v_before, const S& v_after, const S& impulse) {
  using R = Real<S>;
  const S P = impulse >= S(0) ? impulse : S((v_after - v_before) / m.s_B);
  e.impulse = R::to_double(P);
  e.energy_dissipated = std::max(0.0, R::to_double(-P * (v_before + v_after) / S(2)));
}

// The tail of a chattering sequence not followed (docs/loads.md §2): after an impact that leaves
// at gap speed u = v⁺ with restitution r under a constant pull s_B R, the impacts not followed
// arrive at u, r u, r² u, …, so their impulses and losses sum to
//   P_tail = Σ (1 + r) m rⁿ u = (1 + r) m u / (1 − r),   E_tail = Σ ½(1 − r²) m r²ⁿ u² = ½ m u²,
// m = 1/s_B (all the relative kinetic energy left after the last impact followed). When R falls
// over the tail (ε = −ṘΔ0/R of the prediction, docs/model.md §5.4a) each arrival speed shrinks
// by κs_n/(3R) of its flight s_n; to first order in ε the sums become
//   P_tail (1 − ε/(3(1 + r))),   E_tail (1 − 2ε/(3(1 + r + r²))),
// with a residual O(ε²) (ε ≤ 0.1 and far smaller where a prediction is taken).
template <class S>
void TailLoads(const ModelT<S>& m, const S& u, const S& epsilon, S& impulse, S& energy) {
  impulse = (S(1) + m.r) * u / ((S(1) - m.r) * m.s_B) * (S(1) - epsilon / (S(3) * (S(1) + m.r)));
  energy = u * u / (S(2) * m.s_B) * (S(1) - S(2) * epsilon / (S(3) * (S(1) + m.r + m.r * m.r)));
}

// The sticking phase of one contact, accumulated segment by segment. A phase resumed from a
// checkpoint that has time held and no max (written by an earlier release, which did not compute
// the max of λ over held sets) keeps its max NaN: max_unknown.
struct StickAccount {
  double duration = 0, integral = 0, max = std::numeric_limits<double>::quiet_NaN();
  bool open = false;
  bool max_unknown = false;
};

template <class S>
class ContactLoadsT {
 public:
  using Vec = typename ModelT<S>::Vec;
  using R = Real<S>;

  void Resize(size_t contacts) { phases_.assign(contacts, {}); }
  void Begin(int j) {
    phases_[static_cast<size_t>(j)] = {0, 0, std::numeric_limits<double>::quiet_NaN(), true, false};
    end_model_ = nullptr;
  }
  // Sticking on several contacts at once: every open account is abandoned (its release reports NaN).
  void Invalidate() {
    for (StickAccount& a : phases_) a = {};
    end_model_ = nullptr;
  }
  // Impulsive reaction received by a held contact (an impact elsewhere while it sticks).
  void AddImpulse(int j, const S& P) { phases_[static_cast<size_t>(j)].integral += R::to_double(P); }
  // A segment of a compliant stop's contact phase (docs/compliant.md): its duration, ∫λ dt and
  // largest force, computed by the phase's closed form.
  void AddCompliant(int j, double duration, double integral, double max) {
    StickAccount& a = phases_[static_cast<size_t>(j)];
    if (!a.open) return;
    a.duration += duration;
    a.integral += integral;
    if (!(a.max >= max)) a.max = max;
  }
  // A release: the phase's account into the event, then closed.
  void End(int j, Event& e) {
    StickAccount& a = phases_[static_cast<size_t>(j)];
    if (a.open) {
      e.stick_duration = a.duration;
      e.reaction_integral = a.integral;
      e.reaction_max = a.max;
    }
    a = {};
    end_model_ = nullptr;
  }
  // The state at the start of a sticking segment (kept before the propagator advances).
  // A segment that starts where the last one of the same phase ended (a section cut) takes that
  // end's jet of R and cos φ as its start's (the phase restarts at 0 there: equal to rounding).
  void SegmentStart(const Vec& X, const Vec& V) {
    X0_ = X;
    V0_ = V;
    start_model_ = end_model_ && X.size() == X1_.size() && (X.array() == X1_.array()).all() &&
                           (V.array() == V1_.array()).all()
                       ? end_model_
                       : nullptr;
    end_model_ = nullptr;
    stretches_ = 0;
    stretch_max_ = S(0);
  }
  // A stretch [lo, hi] of a sticking segment's dense output as an integrator reports it (each valid
  // only until the next, so that the max R search cannot wait for the segment's end): the grid
  // search on it, from the segment's start phase. Segment() takes the largest.
  void Stretch(const ModelT<S>& m, const PropagatorT<S>& p, const S& phase, const S& lo, const S& hi) {
    if (!(hi >= lo)) return;
    const S mx = search_.OnStretch(m, p, phase, lo, hi);
    if (stretches_++ == 0 || mx > stretch_max_) stretch_max_ = mx;
  }
  // A sticking segment of the held contact m over local time sigma from forcing phase `phase`,
  // ending at (X1, V1): duration, ∫R dt in closed form and max R, certified on the engine's closed
  // form of the held flow (ReactionMax) or searched on the stretches an integrator reported.
  void Segment(int j, const ModelT<S>& m, const PropagatorT<S>& p, const S& phase, const S& sigma,
               const Vec& X1, const Vec& V1) {
    StickAccount& a = phases_[static_cast<size_t>(j)];
    if (!a.open) return;  // a phase begun before a resume whose checkpoint had no account
    a.duration += R::to_double(sigma);
    if (a.max_unknown) {
      a.integral += R::to_double(ReactionIntegral(m, phase, sigma, X0_, V0_, X1, V1));
      return;
    }
    // max R first: it evaluates cos φ0 and cos(φ0 + ωσ), which ∫R dt needs too.
    const double mx = R::to_double(ReactionMax(m, p, phase, sigma, X1, V1));
    a.integral += R::to_double(ReactionIntegral(m, phase, sigma, X0_, V0_, X1, V1, &cos_ends_));
    if (!(a.max >= mx)) a.max = mx;
  }

  // A segment held on the set `held` of several contacts (models[j] each contact's), over local
  // time sigma from forcing phase `phase`, ending at (X1, V1): every held contact's duration and
  // ∫λ_j dt in closed form (SetReactionIntegrals), and max λ_j certified as max R is (from the set's
  // closed form of λ_j, without the Taylor step). A set whose flexibility matrix cannot be solved
  // (dependent contacts) abandons its contacts' accounts.
  // force_of(j): contact j's force λ_j as a source of the max R search (its jets and bound,
  // ReactionMaxT::Max), from the set's closed form.
  template <class ForceOf>
  void SetSegment(const std::vector<int>& held, const std::vector<const ModelT<S>*>& models, const S& phase,
                  const S& sigma, const Vec& X1, const Vec& V1, const ForceOf& force_of) {
    Vec lambda;
    const bool ok = SetReactionIntegrals(held, models, phase, sigma, X0_, V0_, X1, V1, lambda);
    for (size_t a = 0; a < held.size(); ++a) {
      StickAccount& acc = phases_[static_cast<size_t>(held[a])];
      if (!acc.open) continue;
      if (!ok) {
        acc = {};
        continue;
      }
      acc.duration += R::to_double(sigma);
      acc.integral += R::to_double(lambda[static_cast<Eigen::Index>(a)]);
      if (acc.max_unknown) continue;
      const auto source = force_of(held[a]);
      Jet j0{}, j1{};
      source.HeldReactionJet(S(0), j0.R, j0.rate, j0.accel);
      source.HeldReactionJet(sigma, j1.R, j1.rate, j1.accel);
      const double mx = R::to_double(search_.Max(*models[static_cast<size_t>(held[a])], source, phase, sigma, j0, j1));
      if (!(acc.max >= mx)) acc.max = mx;
    }
  }

  // ∫λ_j dt of every contact j of a held set S over a segment, in closed form from the end states
  // (docs/loads.md, "Phases held on several contacts"): the modal equations of motion
  //   Ẍ + DẊ + ΩX = T_A f sin ωt + Σ_{j∈S} T_j λ_j
  // integrated over [0, σ] give Ω∫X dt = Σ T_j Λ_j − b, b = [Ẋ] + D[X] − T_A f ∫sin ωt dt, and the
  // held constraints c_jᵀX = x0_j give c_jᵀ∫X dt = x0_j σ; so, with u_j = Ω⁻¹c_j,
  //   Σ_k (u_jᵀT_k) Λ_k = x0_j σ + u_jᵀ b   for every j ∈ S,
  // the flexibility matrix of the set times Λ (for one contact: ReactionIntegral). False when that
  // matrix is singular.
  static bool SetReactionIntegrals(const std::vector<int>& held, const std::vector<const ModelT<S>*>& models,
                                   const S& phase, const S& sigma, const Vec& X0, const Vec& V0, const Vec& X1,
                                   const Vec& V1, Vec& lambda) {
    const size_t zs = held.size();
    if (zs == 0 || zs > 4096) return false;
    const auto z = static_cast<Eigen::Index>(zs);
    const ModelT<S>& m0 = *models[static_cast<size_t>(held.front())];
    const Eigen::Index n = m0.omega.size();
    const S sin_integral = (R::cos(phase) - R::cos(phase + m0.w * sigma)) / m0.w;
    Vec b(n);
    for (Eigen::Index i = 0; i < n; ++i)
      b[i] = (V1[i] - V0[i]) + S(2) * m0.zeta[i] * m0.omega[i] * (X1[i] - X0[i]) - m0.forcing[i] * m0.f * sin_integral;
    if (!m0.harmonics.empty()) b -= HarmonicImpulse(m0, phase, sigma);
    // The augmented system [F | rhs], solved by Gaussian elimination with partial pivoting.
    std::vector<std::vector<S>> A(zs, std::vector<S>(zs + 1, S(0)));
    S scale(0);
    for (Eigen::Index a = 0; a < z; ++a) {
      const ModelT<S>& ma = *models[static_cast<size_t>(held[static_cast<size_t>(a)])];
      auto& row = A[static_cast<size_t>(a)];
      S rhs = ma.x0 * sigma;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (ma.shape[i] == S(0)) continue;
        const S u = ma.shape[i] / (m0.omega[i] * m0.omega[i]);
        rhs += u * b[i];
        for (Eigen::Index k = 0; k < z; ++k)
          row[static_cast<size_t>(k)] += u * models[static_cast<size_t>(held[static_cast<size_t>(k)])]->contact[i];
      }
      row[zs] = rhs;
      for (Eigen::Index k = 0; k < z; ++k) scale = std::max(scale, R::abs(row[static_cast<size_t>(k)]));
    }
    for (size_t c = 0; c < zs; ++c) {
      size_t piv = c;
      for (size_t r = c + 1; r < zs; ++r)
        if (R::abs(A[r][c]) > R::abs(A[piv][c])) piv = r;
      if (!(R::abs(A[piv][c]) > S(1e-12) * scale)) return false;
      std::swap(A[c], A[piv]);
      for (size_t r = c + 1; r < zs; ++r) {
        const S q = A[r][c] / A[c][c];
        for (size_t k = c; k <= zs; ++k) A[r][k] -= q * A[c][k];
      }
    }
    lambda.resize(z);
    for (size_t c = zs; c-- > 0;) {
      S v = A[c][zs];
      for (size_t k = c + 1; k < zs; ++k) v -= A[c][k] * lambda[static_cast<Eigen::Index>(k)];
      lambda[static_cast<Eigen::Index>(c)] = v / A[c][c];
    }
    return true;
  }

  // ∫ Σ_h T_A^(h) f_h sin φ_h dt over [0, σ] from base phase φ (docs/harmonics.md).
  static Vec HarmonicImpulse(const ModelT<S>& m, const S& phase, const S& sigma) {
    Vec J = Vec::Zero(m.omega.size());
    const auto& hs = m.harmonics;
    for (size_t h = 0; h < hs.size(); ++h) {
      const S p0 = hs.PhaseOf(h, phase), p1 = hs.PhaseOf(h, phase + m.w * sigma);
      // cos p0 − cos p1 = 2 sin((p0+p1)/2) sin((p1−p0)/2), without cancellation for short segments.
      const S d = S(2) * R::sin(S(0.5) * (p0 + p1)) * R::sin(S(0.5) * hs.h[h].omega * sigma);
      J += hs.h[h].forcing * (d / hs.h[h].omega);
    }
    return J;
  }

  // Checkpoint (open phases) and resume.
  void Save(Checkpoint& cp) const {
    cp.stick_duration.resize(phases_.size());
    cp.reaction_integral.resize(phases_.size());
    cp.reaction_max.resize(phases_.size());
    for (size_t j = 0; j < phases_.size(); ++j) {
      const StickAccount& a = phases_[j];
      cp.stick_duration[j] = a.open ? a.duration : std::numeric_limits<double>::quiet_NaN();
      cp.reaction_integral[j] = a.open ? a.integral : std::numeric_limits<double>::quiet_NaN();
      cp.reaction_max[j] = a.open ? a.max : std::numeric_limits<double>::quiet_NaN();
    }
  }
  void Restore(const Checkpoint& cp) {
    end_model_ = nullptr;
    if (cp.stick_duration.size() != phases_.size() || cp.reaction_integral.size() != phases_.size() ||
        cp.reaction_max.size() != phases_.size())
      return;
    for (size_t j = 0; j < phases_.size(); ++j) {
      const bool open = !std::isnan(cp.stick_duration[j]);
      // An open phase with time held and no max (an earlier release's held set): its max stays unknown.
      phases_[j] = {open ? cp.stick_duration[j] : 0.0, open ? cp.reaction_integral[j] : 0.0, cp.reaction_max[j],
                    open, open && cp.stick_duration[j] > 0 && std::isnan(cp.reaction_max[j])};
    }
  }

  // ∫R dt over a sticking segment in closed form (docs/loads.md §3). With u = Ω⁻¹c / φ, φ = cᵀΩ⁻¹T_B
  // the static flexibility of the contact (uᵀT_B = 1, uᵀΩ = cᵀ/φ), uᵀ of the equation of motion
  // Ẍ + DẊ + ΩX = T_A f sin ωt + T_B R integrated over [0, σ], with cᵀX = x0 held, gives
  //   ∫R dt = uᵀ[Ẋ] + uᵀD[X] + x0 σ / φ − (uᵀT_A) f (cos φ0 − cos(φ0 + ωσ)) / ω
  // from the end states alone (exact: no quadrature).
  // cos_ends: cos φ0 and cos(φ0 + ωσ) when the caller has them.
  S ReactionIntegral(const ModelT<S>& m, const S& phase, const S& sigma, const Vec& X0, const Vec& V0,
                     const Vec& X1, const Vec& V1, const S (*cos_ends)[2] = nullptr) const {
    const auto& k = search_.CoefsOf(m);
    S sum(0);
    for (Eigen::Index i = 0; i < m.omega.size(); ++i) sum += k.u[i] * (V1[i] - V0[i]) + k.ud[i] * (X1[i] - X0[i]);
    S forcing = k.uTA * m.f *
                (cos_ends ? S((*cos_ends)[0] - (*cos_ends)[1]) : S(R::cos(phase) - R::cos(phase + m.w * sigma))) /
                m.w;
    if (!m.harmonics.empty()) {  // Σ_h uᵀT_A^(h) f_h ∫ sin φ_h dt (docs/harmonics.md)
      const Vec J = HarmonicImpulse(m, phase, sigma);
      forcing = S(0);
      for (Eigen::Index i = 0; i < m.omega.size(); ++i) forcing += k.u[i] * J[i];
    }
    return (sum - forcing + m.x0 * sigma) / m.flexibility;
  }

  // max R over a sticking segment (docs/loads.md §3): the jets at its ends from the states (the
  // start's taken from the previous segment's end at a section cut), then the search (ReactionMax
  // of dynamics/reaction_max.hpp), or the largest of the stretches an integrator reported.
  // X1, V1: the state at sigma (the segment's end, already evaluated); the start is X0_, V0_.
  S ReactionMax(const ModelT<S>& m, const PropagatorT<S>& p, const S& phase, const S& sigma, const Vec& X1,
                const Vec& V1) {
    Jet j0 = end_jet_;
    if (start_model_ == &m) {
      cos_ends_[0] = end_cos_;
    } else {
      j0 = search_.JetAt(m, X0_, V0_, phase);
      cos_ends_[0] = search_.LastCos();
    }
    const Jet j1 = search_.JetAt(m, X1, V1, phase + m.w * sigma);
    cos_ends_[1] = search_.LastCos();
    end_jet_ = j1;
    end_cos_ = cos_ends_[1];
    X1_ = X1;
    V1_ = V1;
    end_model_ = &m;
    if (stretches_ > 0) {
      const S ends = j0.R > j1.R ? j0.R : j1.R;
      return stretch_max_ > ends ? stretch_max_ : ends;
    }
    return search_.Max(m, p, phase, sigma, j0, j1);
  }

 private:
  using Jet = typename ReactionMaxT<S>::Jet;

  std::vector<StickAccount> phases_;
  Vec X0_, V0_;
  ReactionMaxT<S> search_;
  // The last segment's end (its jet, cos φ and state) and the model it was held on, for the next
  // segment's start (SegmentStart); null when the phase ended or nothing is kept.
  const ModelT<S>* end_model_ = nullptr;
  const ModelT<S>* start_model_ = nullptr;
  Jet end_jet_{};
  S end_cos_{0};
  Vec X1_, V1_;
  int stretches_ = 0;  // stretches of the current segment searched by Stretch()
  S stretch_max_{0};
  S cos_ends_[2] = {};  // cos φ0, cos(φ0 + ωσ) of the last ReactionMax
};

}  // namespace vibro::detail
