// The exact engine: free flight and sticking advanced with the closed forms of docs/model.md §2, §4.2
// and §7, guards located by certified stepping on the trigonometric sums (docs/model.md §2.1).
// Templated on the scalar: ExactEngineT<double> is the default engine, ExactEngineT<Quad> the
// quad-precision reference (run.precision = "quad", dynamics/quad.hpp).
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "dynamics/damped_sticking.hpp"
#include "dynamics/flight_window.hpp"
#include "dynamics/harmonic_flow.hpp"
#include "dynamics/model_t.hpp"
#include "dynamics/oscillator.hpp"
#include "dynamics/propagator.hpp"
#include "dynamics/root_finder.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

// The probes of the certified searches (jets with their bounds, one per step) made by the exact
// engines of this thread so far, each engine's added when it is destroyed: the benchmarks' probes
// per event (docs/performance.md).
long long& ThreadProbeCount();

template <class S>
class ExactEngineT final : public PropagatorT<S> {
 public:
  using Vec = typename ModelT<S>::Vec;

  // `model` is contact 0's; the engine builds the others' from the system (docs/contacts.md).
  ExactEngineT(const System& system, const ModelT<S>& model);

  void Begin(const SegmentStartT<S>& start) override;
  SegmentResultT<S> Advance(S sigma_max, bool detect_events,
                            const StretchCallbackT<S>& on_stretch) override;
  void Evaluate(S sigma, Vec& X, Vec& V) const override;
  S Gap(S sigma) const override;
  S EvaluateWithGap(S sigma, Vec& X, Vec& V) const override;
  S GapOf(int j, S sigma) const override;
  bool HeldReaction(const S& sigma, S& R, S& rate) const override;
  bool HeldReactionJet(const S& sigma, S& R, S& rate, S& accel) const override;
  bool HeldReactionBound(const S& H, S& M, S* m5 = nullptr) const override;
  bool HeldReactionTaylor(const S& sigma, S* d) const override;
  ~ExactEngineT() override { ThreadProbeCount() += probes_; }

  // Gap g = x_B − x0 and its derivatives at local time sigma, with a bound on |g'''| over
  // [sigma, sigma + H] (free flight), and with rest > H the far bound over a window of up to
  // `rest` (root_finder.hpp, AddFarBound). Public for tests.
  ProbeT<S> GapProbe(const S& sigma, const S& H, const S& rest = S(0)) const {
    return GapProbe(start_contact_, sigma, H, rest);
  }
  // The same for contact j (free flight).
  ProbeT<S> GapProbe(int j, const S& sigma, const S& H, const S& rest) const;
  // kWeighted: general c_i; else every c_i is 0 or 1 (contact 0), without the products.
  // Flattened: every mode's closed form, bounds and far bound inlined into the probe (the
  // same operations in the same order: docs/performance.md, "Probes per event").
  template <bool kWeighted>
  [[gnu::flatten]] ProbeT<S> GapProbeOf(int j, const S& sigma, const S& H, const S& rest) const;
  // Reaction R and its derivatives, with a bound on |R'''| (sticking, n ≥ 2), likewise.
  ProbeT<S> ReactionProbe(const S& sigma, const S& H, const S& rest = S(0)) const;

  // What the far bound needs of one mode, constant over a run: the steady forced response
  // U(σ) = P sin(φ+ωσ) + Q cos(φ+ωσ), |U| ≤ u_max (docs/model.md §7, ζ = 0 included).
  struct ModeFar {
    S P, Q, u_max;
    bool eligible;  // ν ≥ 2ω (far from resonance) and a nonzero weight
  };
  // One mode sampled at the probe point.
  struct ModeSample {
    S x, v, acc, A;  // coordinate, velocity, acceleration, energy amplitude
    S loss;          // w·x + |w|·(largest |coordinate| ever): what the mode can still take off
    bool far;        // bounded by its amplitude in the far bound
  };

 private:
  // What the engine keeps per contact: its model, the far-bound data of its gap, and sticking on
  // it alone (constrained modes, reaction), with the gaps of the other contacts while it is held:
  // g_k = held_base[k] + Σ_m held_weights[k]_m ξ_m (MODEL §11.5.1 with S = {j}).
  struct ContactData {
    const ModelT<S>* m = nullptr;
    std::vector<ModeFar> free_far;
    std::vector<OscillatorT<S>> stick_modes;
    std::vector<ModeFar> stick_far;
    std::vector<int> stick_order;
    S reaction_forcing{0}, static_reaction{0};
    std::vector<Vec> held_weights;
    std::vector<S> held_base;
  };
  // Gap of contact k (not held) during sticking on the current contact, with its jet and bound.
  ProbeT<S> HeldGapProbe(int k, const S& sigma, const S& H) const;
  FlightJetT<S> HeldGapStartJet(int k) const;

  SegmentResultT<S> AdvanceFree(const S& sigma_max, bool detect_events);
  SegmentResultT<S> AdvanceSticking(const S& sigma_max, bool detect_events);
  template <class ProbeFn>
  SegmentResultT<S> Search(const ProbeFn& probe, const S& from, const S& sigma_max, SegmentEnd end);
  // Start of the certified search: the end of the window free of the trivial root at σ = 0.
  S FlightWindow() const;
  // Loss of a mode of weight w sampled at a point where the forcing angle is (sf, cf).
  S Loss(const OscillatorT<S>& o, const ModeFar& mf, const S& w, const S& x, const S& v,
         const S& sf, const S& cf) const;
  // Adds the far bound to p from samples_ (see ProbeT::far).
  void AddFarBound(ProbeT<S>& p, const std::vector<OscillatorT<S>>& modes,
                   const std::vector<ModeFar>& far, const std::vector<int>& order,
                   const typename ModelT<S>::Vec* weights, const JetT<S>& base, const S& base_M,
                   const S& H, const S& rest) const;

  const ModelT<S>& m_;
  std::vector<ModelT<S>> others_;  // contacts 1..m−1
  std::vector<ContactData> contacts_;
  int start_contact_ = 0;          // free flight: the contact of flight_start_; sticking: the held one
  std::vector<S> gap0s_;           // free flight: every contact's gap at σ = 0
  std::vector<FlightStart> starts_;  // every contact's start kind
  int skip_ = -1;                  // contact left out of the search
  S omega_;
  S h_cap_;  // largest root-search step (the bounds grow with the step)
  std::vector<OscillatorT<S>> free_modes_;   // ω_i, ζ_i, T_A,i f
  std::vector<int> free_order_;                 // mode indices, fastest first
  mutable std::vector<ModeSample> samples_;     // scratch of the probes (no allocation per probe)
  // The last free-flight probe's flows, kept for the state at the same σ (docs/performance.md,
  // "The state at the root"): a search that ends within half an ulp of its last probe returns that
  // probe's σ, and Evaluate/EvaluateWithGap there reuse each mode's (Δq, v) instead of its closed
  // form again: the same function of the same arguments, so the same doubles. Valid while
  // `memo_contact_` ≥ 0: the probe was of that contact and flowed every mode (no zero weight
  // skipped); σ is compared bit for bit (±0 differ). Begin invalidates it.
  mutable std::vector<OscillatorStateT<S>> memo_flow_;
  mutable S memo_sigma_{0};
  mutable int memo_contact_ = -1;
  bool MemoHit(const S& sigma) const;
  bool damped_sticking_ = false;             // non-proportional damping in the constrained modes
  // Its closed form (docs/model.md §7): DampedStickingT<Quad> is declared in
  // dynamics/damped_sticking_quad.hpp, which the quad instantiation includes
  // (dynamics/exact_engine_quad.hpp).
  std::vector<DampedStickingT<S>> damped_;  // per contact
  DampedStickingT<S>& Damped() { return damped_[static_cast<size_t>(start_contact_)]; }
  const DampedStickingT<S>& Damped() const { return damped_[static_cast<size_t>(start_contact_)]; }

  // Current segment.
  Mode mode_ = Mode::kFree;
  S phase_{0};
  PhaseTrigT<S> trig_{S(0)};
  Vec X0_, V0_;     // free flight start
  Vec xi0_, dxi0_;  // sticking start, constrained modal coordinates
  mutable Vec xi_, dxi_;  // Evaluate's scratch (no allocation per dense-output point)
  // HeldReactionTaylor's form of each constrained mode over the segment, made at its first call:
  // ξ = P sin φ + a cos νσ + b sin νσ (P = F/(ν² − ω²)); `flow` where ω/ν is within √(3/4) …
  // √(5/4) (near resonance, P large and the sum cancelling) or ν = 0: Flow instead.
  struct TaylorMode {
    S P, a, b;
    bool flow;
  };
  mutable std::vector<TaylorMode> taylor_;
  mutable bool taylor_ready_ = false;
  S gap0_{0};
  // A sum of harmonics (docs/harmonics.md); empty for one harmonic (the closed forms above as they
  // are). free_hF_[i·H + h] = T_A,i^(h) f_h; per contact, its constrained modes' and its reaction's.
  bool harm() const { return !h_omega_.empty(); }
  std::vector<S> h_omega_;
  std::vector<PhaseTrigT<S>> h_trig_;  // φ_h at σ = 0
  mutable HarmonicTrigT<S> h_at_;     // at the probe's σ
  std::vector<S> free_hF_;
  std::vector<HarmonicSumsT<S>> free_hsum_;
  struct HarmonicContact {
    std::vector<S> stick_hF;               // [k·H + h]
    std::vector<HarmonicSumsT<S>> stick_hsum;
    std::vector<S> kappa;                  // s_A,j^(h) f_h / W_jj
  };
  std::vector<HarmonicContact> h_contacts_;
  // Σ_h F[h] sin φ_h(σ), and its derivative, at the probe's σ.
  S HForce(const S* F) const {
    S out(0);
    for (size_t h = 0; h < h_omega_.size(); ++h) out += F[h] * h_at_.s[h];
    return out;
  }
  S HForceRate(const S* F) const {
    S out(0);
    for (size_t h = 0; h < h_omega_.size(); ++h) out += F[h] * h_omega_[h] * h_at_.c[h];
    return out;
  }
  long long probes_ = 0;  // probes of the certified searches (ThreadProbeCount)
  FlightStart flight_start_ = FlightStart::kGeneric;
  StickStart stick_start_ = StickStart::kGeneric;
};

using ExactEngine = ExactEngineT<double>;

// Relative margin on the derivative bounds, for the rounding of the evaluated jets.
template <class S>
S BoundMargin() {
  return S(1) + S(1e-9);
}

template <class S>
ExactEngineT<S>::ExactEngineT(const System& sys, const ModelT<S>& m)
    : m_(m),
      omega_(m.w),
      damped_sticking_(sys.constrained().damping.size() > 0 &&
                       sys.constrained().damping.cwiseAbs().maxCoeff() > 0) {
  damped_.reserve(static_cast<size_t>(sys.contact_count()));
  for (int j = 0; j < sys.contact_count(); ++j) {
    const auto& d = sys.contacts()[static_cast<size_t>(j)].constrained.damping;
    if (j > 0 && d.size() > 0 && d.cwiseAbs().maxCoeff() > 0) damped_sticking_ = true;
    damped_.emplace_back(sys, j);
  }
  for (int j = 1; j < sys.contact_count(); ++j) others_.emplace_back(sys, j);
  contacts_.resize(static_cast<size_t>(sys.contact_count()));
  for (size_t j = 0; j < contacts_.size(); ++j) contacts_[j].m = j == 0 ? &m : &others_[j - 1];
  for (int i = 0; i < m.dof(); ++i)
    free_modes_.push_back({m.omega[i], m.zeta[i], m.forcing[i] * m.f});
  h_cap_ = StepCap<S>(m);
  for (const ModelT<S>& o : others_) {
    const S h = StepCap<S>(o);
    if (h < h_cap_) h_cap_ = h;
  }
  const auto far_of = [&](const std::vector<OscillatorT<S>>& modes, const auto& weight,
                          std::vector<ModeFar>& far, std::vector<int>* order) {
    for (size_t i = 0; i < modes.size(); ++i) {
      const OscillatorT<S>& o = modes[i];
      const S d = o.nu * o.nu - omega_ * omega_, e = S(2) * o.zeta * o.nu * omega_;
      const S den = d * d + e * e;
      const bool eligible = o.nu >= S(2) * omega_ && weight(i) != S(0) && m.harmonics.empty();
      far.push_back(eligible ? ModeFar{o.F * d / den, -o.F * e / den,
                                       Real<S>::abs(o.F) / Real<S>::sqrt(den), true}
                             : ModeFar{S(0), S(0), S(0), false});
      if (order) order->push_back(static_cast<int>(i));
    }
    if (order)
      std::stable_sort(order->begin(), order->end(), [&](int a, int b) {
        return modes[static_cast<size_t>(a)].nu > modes[static_cast<size_t>(b)].nu;
      });
  };
  size_t stick_max = 0;
  for (size_t j = 0; j < contacts_.size(); ++j) {
    ContactData& cd = contacts_[j];
    const ModelT<S>& mj = *cd.m;
    // The free modes' order (fastest first) is the contacts' common one: made once, with contact 0.
    far_of(free_modes_, [&](size_t i) { return mj.shape[static_cast<Eigen::Index>(i)]; }, cd.free_far,
           j == 0 ? &free_order_ : nullptr);
    for (Eigen::Index k = 0; k < mj.stick_frequencies.size(); ++k)
      cd.stick_modes.push_back({mj.stick_frequencies[k], S(0), mj.stick_forcing[k] * mj.f});
    far_of(cd.stick_modes, [&](size_t k) { return mj.stick_reaction[static_cast<Eigen::Index>(k)]; },
           cd.stick_far, &cd.stick_order);
    cd.reaction_forcing = mj.s_A / mj.s_B * mj.f;
    cd.static_reaction = mj.x0 / mj.flexibility;
    stick_max = std::max(stick_max, cd.stick_modes.size());
    // Gaps of the other contacts while j is held: X = e_j·static_shape_j + V_j ξ.
    cd.held_weights.resize(contacts_.size());
    cd.held_base.resize(contacts_.size());
    for (size_t k = 0; k < contacts_.size(); ++k) {
      if (k == j) continue;
      const ModelT<S>& mk = k == 0 ? m : others_[k - 1];
      cd.held_weights[k] = mj.stick_vectors.transpose() * mk.shape;
      cd.held_base[k] = mj.x0 * mk.shape.dot(mj.static_shape) - mk.x0;
    }
  }
  samples_.resize(std::max(free_modes_.size(), stick_max));
  memo_flow_.resize(free_modes_.size());
  if (!m.harmonics.empty()) {
    const size_t H = m.harmonics.size();
    for (const auto& hh : m.harmonics.h) h_omega_.push_back(hh.omega);
    h_trig_.assign(H, PhaseTrigT<S>(S(0)));
    const auto sums = [&](const S* F) {
      HarmonicSumsT<S> t;
      for (size_t h = 0; h < H; ++h) {
        t.f += Real<S>::abs(F[h]);
        t.fw += Real<S>::abs(F[h]) * h_omega_[h];
        t.fw2 += Real<S>::abs(F[h]) * h_omega_[h] * h_omega_[h];
      }
      return t;
    };
    for (int i = 0; i < m.dof(); ++i)
      for (size_t h = 0; h < H; ++h) free_hF_.push_back(m.harmonics.h[h].forcing[i]);
    for (int i = 0; i < m.dof(); ++i) free_hsum_.push_back(sums(&free_hF_[static_cast<size_t>(i) * H]));
    h_contacts_.resize(contacts_.size());
    for (size_t j = 0; j < contacts_.size(); ++j) {
      const ModelT<S>& mj = *contacts_[j].m;
      HarmonicContact& hc = h_contacts_[j];
      for (Eigen::Index k = 0; k < mj.stick_frequencies.size(); ++k)
        for (size_t h = 0; h < H; ++h) hc.stick_hF.push_back(mj.harmonics.h[h].stick[k]);
      for (Eigen::Index k = 0; k < mj.stick_frequencies.size(); ++k)
        hc.stick_hsum.push_back(sums(&hc.stick_hF[static_cast<size_t>(k) * H]));
      for (size_t h = 0; h < H; ++h) hc.kappa.push_back(mj.harmonics.h[h].contact / mj.s_B);
    }
  }
}

template <class S>
S ExactEngineT<S>::Loss(const OscillatorT<S>& o, const ModeFar& mf, const S& w, const S& x,
                        const S& v, const S& sf, const S& cf) const {
  // The homogeneous part h = x − U obeys ḧ + 2ζνḣ + ν²h = 0, whose energy ḣ² + ν²h² never rises:
  // |x(σ)| ≤ |h|max + |U|max ≤ √(ḣ² + ν²h²)/ν + u_max for every later σ.
  using R = Real<S>;
  const S h = x - (mf.P * sf + mf.Q * cf);
  const S dh = v - omega_ * (mf.P * cf - mf.Q * sf);
  const S reach = R::sqrt(dh * dh + o.nu * o.nu * h * h) / o.nu + mf.u_max;
  const S aw = R::abs(w);
  // Rounding of the terms (relative 1e-9 of their size, like BoundMargin).
  return w * x + aw * reach + S(1e-9) * aw * (R::abs(x) + reach + R::abs(h));
}

template <class S>
void ExactEngineT<S>::AddFarBound(ProbeT<S>& p, const std::vector<OscillatorT<S>>& modes,
                                  const std::vector<ModeFar>& far, const std::vector<int>& order,
                                  const typename ModelT<S>::Vec* weights, const JetT<S>& base,
                                  const S& base_M, const S& H, const S& rest) const {
  // Far from the stop (g well above what the fast modes can take off), bound the fastest modes by
  // their amplitude, Δ(w x) ≥ −loss, and keep the Taylor model for the slower ones only; the step
  // is then set by the fastest Taylor mode instead of the fastest mode. Greedy from the fastest,
  // while the losses sum to at most g/2.
  const S limit = S(0.5) * p.jet.g;
  S lost(0);
  int taken = 0;
  S fastest = omega_;
  for (const int i : order) {
    const auto ui = static_cast<size_t>(i);
    const S w = weights ? (*weights)[i] : S(1);
    if (w == S(0)) continue;
    if (!far[ui].eligible || !(lost + samples_[ui].loss <= limit)) {
      if (modes[ui].nu > fastest) fastest = modes[ui].nu;
      break;
    }
    lost += samples_[ui].loss;
    samples_[ui].far = true;
    ++taken;
  }
  if (taken == 0) return;
  S far_H = S(0.5) * Real<S>::pi() / fastest;  // a quarter of the fastest Taylor period
  if (far_H < H) far_H = H;
  if (far_H > rest) far_H = rest;
  p.far = {p.jet.g - lost, base.g1, base.g2};
  p.far_M = base_M;
  p.far_H = far_H;
  for (size_t i = 0; i < modes.size(); ++i) {
    ModeSample& smp = samples_[i];
    const S w = weights ? (*weights)[static_cast<Eigen::Index>(i)] : S(1);
    if (smp.far || w == S(0)) {
      smp.far = false;
      continue;
    }
    const OscillatorT<S>& o = modes[i];
    p.far.g1 += w * smp.v;
    p.far.g2 += w * smp.acc;
    p.far_M += Real<S>::abs(w) * Bounds<S>(o, omega_, smp.A + Real<S>::abs(o.F) * far_H).d3;
  }
  p.far_M *= BoundMargin<S>();
}

template <class S>
void ExactEngineT<S>::Begin(const SegmentStartT<S>& s) {
  taylor_ready_ = false;
  memo_contact_ = -1;
  mode_ = s.mode;
  phase_ = s.phase;
  trig_ = s.phase_sincos ? PhaseTrigT<S>(s.phase_sincos[0], s.phase_sincos[1]) : PhaseTrigT<S>(s.phase);
  gap0_ = s.gap;
  for (size_t h = 0; h < h_trig_.size(); ++h) h_trig_[h] = PhaseTrigT<S>(m_.harmonics.PhaseOf(h, s.phase));
  flight_start_ = s.flight_start;
  stick_start_ = s.stick_start;
  start_contact_ = s.contact;
  skip_ = s.skip;
  if (contacts_.size() > 1) {
    if (s.starts) starts_ = *s.starts;
    else starts_.assign(contacts_.size(), FlightStart::kGeneric);
    starts_[static_cast<size_t>(start_contact_)] = s.flight_start;
    gap0s_.resize(contacts_.size());
    for (size_t j = 0; j < contacts_.size(); ++j)
      gap0s_[j] = s.gaps ? (*s.gaps)[j] : contacts_[j].m->ContactDisplacement(s.X) - contacts_[j].m->x0;
    gap0s_[static_cast<size_t>(start_contact_)] = s.gap;
  }
  if (mode_ == Mode::kFree) {
    X0_ = s.X;
    V0_ = s.V;
  } else {
    // ξ = L X (L v0 = 0), ξ̇ = L Ẋ (docs/model.md §4.2), in the modes of the held contact.
    const ModelT<S>& h = *contacts_[static_cast<size_t>(start_contact_)].m;
    xi0_ = h.stick_left * s.X;
    dxi0_ = h.stick_left * s.V;
    if (damped_sticking_) Damped().Begin(xi0_, dxi0_, phase_);
  }
}

template <class S>
ProbeT<S> ExactEngineT<S>::GapProbe(int j, const S& sigma, const S& H, const S& rest) const {
  return contacts_[static_cast<size_t>(j)].m->unit_shape ? GapProbeOf<false>(j, sigma, H, rest)
                                                         : GapProbeOf<true>(j, sigma, H, rest);
}

template <class S>
template <bool kWeighted>
ProbeT<S> ExactEngineT<S>::GapProbeOf(int j, const S& sigma, const S& H, const S& rest) const {
  using R = Real<S>;
  const ContactData& cd = contacts_[static_cast<size_t>(j)];
  const auto& c = cd.m->shape;
  const ForcingTrigT<S> fw(omega_, sigma);
  const S s_forcing = fw.SinPhase(trig_);
  const bool far = rest > H;
  const S c_forcing = far ? fw.CosPhase(trig_) : S(0);
  const S g0 = contacts_.size() > 1 ? gap0s_[static_cast<size_t>(j)] : gap0_;
  ProbeT<S> p{{g0, S(0), S(0)}, S(0)};
  S dq_sum(0);
  const size_t Hn = h_omega_.size();
  if (Hn) h_at_.At(h_omega_, h_trig_, sigma);
  bool every_mode = true;
  for (size_t i = 0; i < free_modes_.size(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    const S ci = c[ii];
    if (ci == S(0)) {
      every_mode = false;
      continue;
    }
    const OscillatorT<S>& o = free_modes_[i];
    const auto st = Hn ? FlowSum<S>(o, &free_hF_[i * Hn], h_omega_, h_trig_, h_at_, X0_[ii], V0_[ii], sigma)
                       : Flow<S>(o, omega_, trig_, X0_[ii], V0_[ii], sigma, fw);
    memo_flow_[i] = st;
    const S x = X0_[ii] + st.dq;
    const S acc = -o.nu * o.nu * x - S(2) * o.zeta * o.nu * st.v +
                  (Hn ? HForce(&free_hF_[i * Hn]) : S(o.F * s_forcing));
    const S A = Amplitude<S>(o, x, st.v);
    const S d3 = Hn ? BoundsSum<S>(o, free_hsum_[i], A + free_hsum_[i].f * H).d3
                    : Bounds<S>(o, omega_, A + R::abs(o.F) * H).d3;
    if constexpr (kWeighted) {
      dq_sum += ci * st.dq;
      p.jet.g1 += ci * st.v;
      p.jet.g2 += ci * acc;
      p.M += R::abs(ci) * d3;
    } else {  // c_i = 1
      dq_sum += st.dq;
      p.jet.g1 += st.v;
      p.jet.g2 += acc;
      p.M += d3;
    }
    if (far) {
      const ModeFar& mf = cd.free_far[i];
      samples_[i] = {x, st.v, acc, A,
                     mf.eligible ? Loss(o, mf, ci, x, st.v, s_forcing, c_forcing) : S(0), false};
    }
  }
  p.jet.g += dq_sum;
  memo_sigma_ = sigma;
  memo_contact_ = every_mode && mode_ == Mode::kFree ? j : -1;
  p.M *= BoundMargin<S>();
  if (far && p.jet.g > 0)
    AddFarBound(p, free_modes_, cd.free_far, free_order_, &c, {S(0), S(0), S(0)}, S(0), H, rest);
  return p;
}

// g_k = base + Σ w_m ξ_m while the current contact is held (undamped constrained modes).
template <class S>
ProbeT<S> ExactEngineT<S>::HeldGapProbe(int k, const S& sigma, const S& H) const {
  using R = Real<S>;
  const ContactData& cd = contacts_[static_cast<size_t>(start_contact_)];
  const Vec& w = cd.held_weights[static_cast<size_t>(k)];
  // The gap is its value at the start plus increments (as a flight's, docs/model.md §2): at σ = 0
  // it is exactly the automaton's, whatever the rounding of the constrained modes (a gap snapped
  // to 0 by an impact stays 0 there, so a chattering sequence beside a held contact gains no
  // energy from the reconstruction of the state).
  // Modal damping: the damped constrained flow's closed form (docs/model.md §7).
  if (damped_sticking_) return Damped().LinearProbe(w, gap0s_[static_cast<size_t>(k)], sigma);
  const ForcingTrigT<S> fw(omega_, sigma);
  ProbeT<S> p{{gap0s_[static_cast<size_t>(k)], S(0), S(0)}, S(0)};
  const S sf = fw.SinPhase(trig_);
  const size_t Hn = h_omega_.size();
  if (Hn) h_at_.At(h_omega_, h_trig_, sigma);
  for (size_t q = 0; q < cd.stick_modes.size(); ++q) {
    const auto qq = static_cast<Eigen::Index>(q);
    if (w[qq] == S(0)) continue;
    const OscillatorT<S>& o = cd.stick_modes[q];
    const S* hF = Hn ? &h_contacts_[static_cast<size_t>(start_contact_)].stick_hF[q * Hn] : nullptr;
    const auto st = Hn ? FlowSum<S>(o, hF, h_omega_, h_trig_, h_at_, xi0_[qq], dxi0_[qq], sigma)
                       : Flow<S>(o, omega_, trig_, xi0_[qq], dxi0_[qq], sigma, fw);
    const S xi = xi0_[qq] + st.dq;
    const S acc = -o.nu * o.nu * xi + (Hn ? HForce(hF) : S(o.F * sf));
    p.jet.g += w[qq] * st.dq;
    p.jet.g1 += w[qq] * st.v;
    p.jet.g2 += w[qq] * acc;
    const S A = Amplitude<S>(o, xi, st.v);
    const auto* hs = Hn ? &h_contacts_[static_cast<size_t>(start_contact_)].stick_hsum[q] : nullptr;
    p.M += R::abs(w[qq]) * (Hn ? BoundsSum<S>(o, *hs, A + hs->f * H).d3 : Bounds<S>(o, omega_, A + R::abs(o.F) * H).d3);
  }
  p.M *= BoundMargin<S>();
  return p;
}

// The jet of g_k at the start of a held phase, with bounds of |g'''| and |g''''| over [0, h_cap]
// (a gap that starts at zero: after an impact, a departure, or a release of a contact held with
// this one, docs/contacts.md); damped, those of the damped closed form.
template <class S>
FlightJetT<S> ExactEngineT<S>::HeldGapStartJet(int k) const {
  const ContactData& cd = contacts_[static_cast<size_t>(start_contact_)];
  const Vec& w = cd.held_weights[static_cast<size_t>(k)];
  if (damped_sticking_) return Damped().StartJet(w);
  const ProbeT<S> p0 = HeldGapProbe(k, S(0), h_cap_);
  FlightJetT<S> j{p0.jet.g1, p0.jet.g2, S(0), p0.M, S(0)};
  S M4(0);
  for (size_t q = 0; q < cd.stick_modes.size(); ++q) {
    const auto qq = static_cast<Eigen::Index>(q);
    if (w[qq] == S(0)) continue;
    const OscillatorT<S>& o = cd.stick_modes[q];
    if (harm()) {  // a sum of harmonics: each harmonic's jerk and the summed bounds
      const size_t Hn = h_omega_.size();
      const HarmonicContact& hc = h_contacts_[static_cast<size_t>(start_contact_)];
      S jerk = -o.nu * o.nu * dxi0_[qq];
      for (size_t h = 0; h < Hn; ++h) jerk += hc.stick_hF[q * Hn + h] * h_omega_[h] * h_trig_[h].c;
      j.g3 += w[qq] * jerk;
      M4 += Real<S>::abs(w[qq]) *
            BoundsSum<S>(o, hc.stick_hsum[q], Amplitude<S>(o, xi0_[qq], dxi0_[qq]) + hc.stick_hsum[q].f * h_cap_).d4;
      continue;
    }
    j.g3 += w[qq] * (-o.nu * o.nu * dxi0_[qq] + o.F * omega_ * trig_.c);
    M4 += Real<S>::abs(w[qq]) *
          Bounds<S>(o, omega_, Amplitude<S>(o, xi0_[qq], dxi0_[qq]) + Real<S>::abs(o.F) * h_cap_).d4;
  }
  j.M4 = M4 * BoundMargin<S>();
  return j;
}

template <class S>
ProbeT<S> ExactEngineT<S>::ReactionProbe(const S& sigma, const S& H, const S& rest) const {
  using R = Real<S>;
  const ContactData& cd = contacts_[static_cast<size_t>(start_contact_)];
  const auto& rho = cd.m->stick_reaction;
  const auto& stick_modes_ = cd.stick_modes;
  const ForcingTrigT<S> fw(omega_, sigma);
  const S sf = fw.SinPhase(trig_), cf = fw.CosPhase(trig_);
  JetT<S> base{cd.static_reaction - cd.reaction_forcing * sf, -cd.reaction_forcing * omega_ * cf,
               cd.reaction_forcing * omega_ * omega_ * sf};
  S base_M = R::abs(cd.reaction_forcing) * omega_ * omega_ * omega_;
  const size_t Hn = h_omega_.size();
  const HarmonicContact* hc = Hn ? &h_contacts_[static_cast<size_t>(start_contact_)] : nullptr;
  if (Hn) {  // R = R_st + ρᵀξ − Σ_h κ_h sin φ_h
    h_at_.At(h_omega_, h_trig_, sigma);
    for (size_t h = 0; h < Hn; ++h) {
      const S k = hc->kappa[h], w = h_omega_[h];
      base.g -= k * h_at_.s[h];
      base.g1 -= k * w * h_at_.c[h];
      base.g2 += k * w * w * h_at_.s[h];
      base_M += R::abs(k) * w * w * w;
    }
  }
  ProbeT<S> p{base, base_M};
  const bool far = rest > H;
  for (size_t k = 0; k < stick_modes_.size(); ++k) {
    const auto kk = static_cast<Eigen::Index>(k);
    const OscillatorT<S>& o = stick_modes_[k];
    const S* hF = Hn ? &hc->stick_hF[k * Hn] : nullptr;
    const auto st = Hn ? FlowSum<S>(o, hF, h_omega_, h_trig_, h_at_, xi0_[kk], dxi0_[kk], sigma)
                       : Flow<S>(o, omega_, trig_, xi0_[kk], dxi0_[kk], sigma, fw);
    const S xi = xi0_[kk] + st.dq;
    const S acc = -o.nu * o.nu * xi + (Hn ? HForce(hF) : S(o.F * sf));
    const S A = Amplitude<S>(o, xi, st.v);
    p.jet.g += rho[kk] * xi;
    p.jet.g1 += rho[kk] * st.v;
    p.jet.g2 += rho[kk] * acc;
    p.M += R::abs(rho[kk]) * (Hn ? BoundsSum<S>(o, hc->stick_hsum[k], A + hc->stick_hsum[k].f * H).d3
                                 : Bounds<S>(o, omega_, A + R::abs(o.F) * H).d3);
    if (far) {
      const ModeFar& mf = cd.stick_far[k];
      samples_[k] = {xi, st.v, acc, A,
                     mf.eligible ? Loss(o, mf, rho[kk], xi, st.v, sf, cf) : S(0), false};
    }
  }
  p.M *= BoundMargin<S>();
  if (far && p.jet.g > 0)
    AddFarBound(p, stick_modes_, cd.stick_far, cd.stick_order, &rho, base, base_M * BoundMargin<S>(),
                H, rest);
  return p;
}

// Several contacts: keeps in `best` the earlier of it and the search result r for contact j (a
// root within rounding of the segment's start is at its start).
template <class S>
void KeepEarliest(SegmentResultT<S>& best, SegmentResultT<S>& r, int j) {
  if (r.end != SegmentEnd::kContact) return;
  if (r.sigma < S(0)) r.sigma = S(0);
  if (best.end == SegmentEnd::kLimit || r.sigma < best.sigma) {
    best = r;
    best.contact = j;
  }
}

template <class S>
S ExactEngineT<S>::FlightWindow() const {
  // docs/model.md §2.1: divide out the known zero at σ = 0; no root in the certified window (0, σ_w).
  if (flight_start_ == FlightStart::kGeneric) return S(0);
  const ModelT<S>& m = contacts_.size() == 1 ? m_ : *contacts_[static_cast<size_t>(start_contact_)].m;
  return CertifiedWindow<S>(flight_start_, StartJet<S>(m, X0_, V0_, trig_.s, trig_.c, h_cap_, &phase_), h_cap_);
}

template <class S>
template <class ProbeFn>
SegmentResultT<S> ExactEngineT<S>::Search(const ProbeFn& probe, const S& from, const S& sigma_max,
                                          SegmentEnd end) {
  const auto counted = [&](const S& u, const S& H, const S& rest) {
    ++probes_;
    return probe(u, H, rest);
  };
  const auto rs = FirstRootPolled<S>(counted, from, sigma_max, h_cap_,
                                     [this] { return this->StopRequested(); });
  if (rs.stopped)
    return {SegmentEnd::kFailure, rs.result.sigma, "stopped inside a root search", S(-1), true};
  if (!rs.result.found) return {SegmentEnd::kLimit, sigma_max, {}};
  return {end, rs.result.sigma, {}};
}

template <class S>
SegmentResultT<S> ExactEngineT<S>::AdvanceFree(const S& sigma_max, bool detect_events) {
  if (!detect_events) return {SegmentEnd::kLimit, sigma_max, {}};
  if (contacts_.size() == 1) {
    const S w = FlightWindow();
    if (w >= sigma_max) return {SegmentEnd::kLimit, sigma_max, {}};
    return Search([this](const S& u, const S& H, const S& rest) { return GapProbe(0, u, H, rest); },
                  w, sigma_max, SegmentEnd::kContact);
  }
  // Several gaps (MODEL §11.2.3): the first certified root over all contacts; each search ends at
  // the best root so far. The start contact divides out its known zero; the others start generic.
  SegmentResultT<S> best{SegmentEnd::kLimit, sigma_max, {}};
  for (int j = 0; j < static_cast<int>(contacts_.size()); ++j) {
    if (j == skip_) continue;
    // A start kind is a known zero only while the gap is 0 (the automaton resets it once the gap
    // opens; a zero divided out from a non-zero gap would skip its next root).
    const FlightStart start = gap0s_[static_cast<size_t>(j)] == S(0) ? starts_[static_cast<size_t>(j)]
                                                                      : FlightStart::kGeneric;
    const S w = start == FlightStart::kGeneric
                    ? S(0)
                    : CertifiedWindow<S>(start, StartJet<S>(*contacts_[static_cast<size_t>(j)].m, X0_, V0_,
                                                            trig_.s, trig_.c, h_cap_, &phase_),
                                         h_cap_);
    if (w >= best.sigma) continue;
    auto r = Search([this, j](const S& u, const S& H, const S& rest) { return GapProbe(j, u, H, rest); },
                    w, best.sigma, SegmentEnd::kContact);
    if (r.end == SegmentEnd::kFailure) return r;
    KeepEarliest(best, r, j);
  }
  return best;
}

template <class S>
SegmentResultT<S> ExactEngineT<S>::AdvanceSticking(const S& sigma_max, bool detect_events) {
  if (damped_sticking_ && !Damped().ok()) {
    if constexpr (std::is_same_v<S, double>)
      return {SegmentEnd::kFailure, 0.0,
              "the damped constrained system is defective (critically damped constrained mode): "
              "no closed form; change structure.damping_ratios slightly, or use run.engine = "
              "\"cvode\""};
    else
      return {SegmentEnd::kFailure, S(0),
              "the damped constrained system is defective (critically damped constrained mode, or "
              "eigenvectors that do not refine to quad precision): no closed form; change "
              "structure.damping_ratios slightly"};
  }
  if (damped_sticking_ && harm())
    return {SegmentEnd::kFailure, S(0),
            "sticking under a sum of harmonics with non-proportional constrained damping has no closed "
            "form in vibro yet (docs/harmonics.md): use one harmonic, or an undamped structure"};
  if (!detect_events) return {SegmentEnd::kLimit, sigma_max, {}};
  const auto probe = [this](const S& u, const S& H, const S& rest) -> ProbeT<S> {
    if (damped_sticking_) return Damped().ReactionProbe(u);
    return ReactionProbe(u, H, rest);
  };
  S w(0);
  if (stick_start_ != StickStart::kGeneric) {
    const ProbeT<S> p = probe(S(0), h_cap_, S(0));
    ++probes_;
    const auto cap = [&](const S& x) { return x < h_cap_ ? x : h_cap_; };
    if (stick_start_ == StickStart::kRising) {
      const S v = p.jet.g1, a = p.jet.g2, M = p.M;
      if (v > 0)
        w = cap(M > 0 ? S((S(0.5) * a + Real<S>::sqrt(S(0.25) * a * a + S(2) * M * v / 3)) / (M / 3))
                      : S(a < 0 ? S(S(2) * v / -a) : h_cap_));
    } else if (p.jet.g2 > 0) {
      w = p.M > 0 ? cap(S(3) * p.jet.g2 / p.M) : h_cap_;
    }
  }
  SegmentResultT<S> best{SegmentEnd::kLimit, sigma_max, {}};
  if (w < sigma_max) {
    best = Search(probe, w, sigma_max, SegmentEnd::kRelease);
    if (best.end == SegmentEnd::kFailure) return best;
  }
  best.contact = start_contact_;
  // The other contacts' gaps under the held flow (MODEL §11.5.4: a free contact hits while this
  // one sticks). A gap the held flow cannot change (zero weights, e.g. the other side of a
  // one-DOF clearance) has no root.
  const ContactData& cd = contacts_[static_cast<size_t>(start_contact_)];
  for (int k = 0; k < static_cast<int>(contacts_.size()); ++k) {
    const Vec& hw = cd.held_weights[static_cast<size_t>(k)];
    if (k == start_contact_ || k == skip_ || hw.size() == 0 || hw.cwiseAbs().maxCoeff() == S(0))
      continue;
    // A gap that starts at zero (an impact or a departure at this contact while the other was
    // held) divides out its known zero as a flight does (docs/model.md §2.1).
    S wk(0);
    const FlightStart start = gap0s_[static_cast<size_t>(k)] == S(0) ? starts_[static_cast<size_t>(k)]
                                                                      : FlightStart::kGeneric;
    if (start != FlightStart::kGeneric) wk = CertifiedWindow<S>(start, HeldGapStartJet(k), h_cap_);
    if (wk >= best.sigma) continue;
    auto r = Search([this, k](const S& u, const S& H, const S&) { return HeldGapProbe(k, u, H); },
                    wk, best.sigma, SegmentEnd::kContact);
    if (r.end == SegmentEnd::kFailure) return r;
    KeepEarliest(best, r, k);
  }
  return best;
}

template <class S>
SegmentResultT<S> ExactEngineT<S>::Advance(S sigma_max, bool detect_events,
                                           const StretchCallbackT<S>& on_stretch) {
  SegmentResultT<S> r = mode_ == Mode::kFree ? AdvanceFree(sigma_max, detect_events)
                                             : AdvanceSticking(sigma_max, detect_events);
  if (r.end != SegmentEnd::kFailure && on_stretch) on_stretch(S(0), r.sigma);
  return r;
}

template <class S>
void ExactEngineT<S>::Evaluate(S sigma, Vec& X, Vec& V) const {
  const auto n = m_.dof();
  X.resize(n);
  V.resize(n);
  const size_t Hn = h_omega_.size();
  if (mode_ == Mode::kFree && MemoHit(sigma)) {
    for (int i = 0; i < n; ++i) {
      const auto& st = memo_flow_[static_cast<size_t>(i)];
      X[i] = X0_[i] + st.dq;
      V[i] = st.v;
    }
    return;
  }
  if (Hn) h_at_.At(h_omega_, h_trig_, sigma);
  if (mode_ == Mode::kFree) {
    const ForcingTrigT<S> fw(omega_, sigma);
    for (int i = 0; i < n; ++i) {
      const auto st =
          Hn ? FlowSum<S>(free_modes_[static_cast<size_t>(i)], &free_hF_[static_cast<size_t>(i) * Hn], h_omega_,
                          h_trig_, h_at_, X0_[i], V0_[i], sigma)
             : Flow<S>(free_modes_[static_cast<size_t>(i)], omega_, trig_, X0_[i], V0_[i], sigma, fw);
      X[i] = X0_[i] + st.dq;
      V[i] = st.v;
    }
    return;
  }
  const ContactData& cd = contacts_[static_cast<size_t>(start_contact_)];
  const auto k_count = static_cast<Eigen::Index>(cd.stick_modes.size());
  Vec& xi = xi_;
  Vec& dxi = dxi_;
  xi.resize(k_count);
  dxi.resize(k_count);
  bool done = false;
  if (damped_sticking_) {
    Damped().Evaluate(sigma, xi, dxi);
    done = true;
  }
  const ForcingTrigT<S> fw(omega_, sigma);
  for (Eigen::Index k = 0; k < k_count && !done; ++k) {
    const auto st =
        Hn ? FlowSum<S>(cd.stick_modes[static_cast<size_t>(k)],
                        &h_contacts_[static_cast<size_t>(start_contact_)].stick_hF[static_cast<size_t>(k) * Hn],
                        h_omega_, h_trig_, h_at_, xi0_[k], dxi0_[k], sigma)
           : Flow<S>(cd.stick_modes[static_cast<size_t>(k)], omega_, trig_, xi0_[k], dxi0_[k], sigma, fw);
    xi[k] = xi0_[k] + st.dq;
    dxi[k] = st.v;
  }
  X.noalias() = cd.m->stick_vectors * xi;
  X += cd.m->x0 * cd.m->static_shape;
  V.noalias() = cd.m->stick_vectors * dxi;
}

// R and Ṙ as the release search sees them (AdvanceSticking's probe, ReactionProbe's R and Ṙ
// without its bounds): the constrained modes' closed form, without forming X.
template <class S>
bool ExactEngineT<S>::HeldReaction(const S& sigma, S& R, S& rate) const {
  S accel(0);
  return HeldReactionJet(sigma, R, rate, accel);
}

// R̈ = κ ω² sin φ + Σ ρ_k ξ̈_k, ξ̈_k = −ν_k² ξ_k + F_k sin φ (ReactionProbe's g2): two products per
// mode on top of R and Ṙ.
template <class S>
bool ExactEngineT<S>::HeldReactionJet(const S& sigma, S& R, S& rate, S& accel) const {
  if (mode_ == Mode::kFree) return false;
  if (damped_sticking_) {
    const ProbeT<S> p = Damped().ReactionProbe(sigma);
    R = p.jet.g;
    rate = p.jet.g1;
    accel = p.jet.g2;
    return true;
  }
  if (harm()) {  // a sum of harmonics: the release search's own probe (its jet without bounds)
    const ProbeT<S> p = ReactionProbe(sigma, S(0));
    R = p.jet.g;
    rate = p.jet.g1;
    accel = p.jet.g2;
    return true;
  }
  const ContactData& cd = contacts_[static_cast<size_t>(start_contact_)];
  const auto& rho = cd.m->stick_reaction;
  const ForcingTrigT<S> fw(omega_, sigma);
  const S sf = fw.SinPhase(trig_);
  R = cd.static_reaction - cd.reaction_forcing * sf;
  rate = -cd.reaction_forcing * omega_ * fw.CosPhase(trig_);
  accel = cd.reaction_forcing * omega_ * omega_ * sf;
  for (size_t k = 0; k < cd.stick_modes.size(); ++k) {
    const auto kk = static_cast<Eigen::Index>(k);
    const OscillatorT<S>& o = cd.stick_modes[k];
    const auto st = Flow<S>(o, omega_, trig_, xi0_[kk], dxi0_[kk], sigma, fw);
    const S xi = xi0_[kk] + st.dq;
    R += rho[kk] * xi;
    rate += rho[kk] * st.v;
    accel += rho[kk] * (-o.nu * o.nu * xi + o.F * sf);
  }
  return true;
}

// |R'''| ≤ |κ f| ω³ + Σ |ρ_k| max|ξ_k'''| over [0, H], each mode bounded from its energy amplitude at
// σ = 0 as ReactionProbe(0, H) bounds it (oscillator.hpp, Bounds); damped, the damped closed
// form's bound, valid for every σ ≥ 0. No trigonometric function: amplitudes only.
// |R⁽⁵⁾| ≤ |κ f| ω⁵ + Σ |ρ_k| (ν_k² max|ξ_k'''| + |F_k| ω³) likewise (ξ⁽⁵⁾ = −ν²ξ''' − Fω³ cos φ
// for an undamped constrained mode); none for the damped closed form (m5 = 0).
template <class S>
bool ExactEngineT<S>::HeldReactionBound(const S& H, S& M, S* m5) const {
  if (mode_ == Mode::kFree || (harm() && damped_sticking_)) return false;
  if (m5) *m5 = S(0);
  if (harm()) {  // M = Σ_h |κ_h| ω_h³ + Σ_k |ρ_k| max|ξ_k‴| (no bound of R⁽⁵⁾: m5 = 0)
    using R = Real<S>;
    const ContactData& cd = contacts_[static_cast<size_t>(start_contact_)];
    const HarmonicContact& hc = h_contacts_[static_cast<size_t>(start_contact_)];
    const auto& rho = cd.m->stick_reaction;
    S b(0);
    for (size_t h = 0; h < h_omega_.size(); ++h) b += R::abs(hc.kappa[h]) * h_omega_[h] * h_omega_[h] * h_omega_[h];
    for (size_t k = 0; k < cd.stick_modes.size(); ++k) {
      const auto kk = static_cast<Eigen::Index>(k);
      const OscillatorT<S>& o = cd.stick_modes[k];
      b += R::abs(rho[kk]) *
           BoundsSum<S>(o, hc.stick_hsum[k], Amplitude<S>(o, xi0_[kk], dxi0_[kk]) + hc.stick_hsum[k].f * H).d3;
    }
    M = b * BoundMargin<S>();
    return true;
  }
  if (damped_sticking_) {
    M = Damped().ReactionProbe(S(0)).M;
    return true;
  }
  using R = Real<S>;
  const ContactData& cd = contacts_[static_cast<size_t>(start_contact_)];
  const auto& rho = cd.m->stick_reaction;
  const S w3 = omega_ * omega_ * omega_;
  S b = R::abs(cd.reaction_forcing) * w3, b5 = b * omega_ * omega_;
  for (size_t k = 0; k < cd.stick_modes.size(); ++k) {
    const auto kk = static_cast<Eigen::Index>(k);
    const OscillatorT<S>& o = cd.stick_modes[k];
    const S d3 = Bounds<S>(o, omega_, Amplitude<S>(o, xi0_[kk], dxi0_[kk]) + R::abs(o.F) * H).d3;
    b += R::abs(rho[kk]) * d3;
    b5 += R::abs(rho[kk]) * (o.nu * o.nu * d3 + R::abs(o.F) * w3);
  }
  M = b * BoundMargin<S>();
  if (m5) *m5 = b5 * BoundMargin<S>();
  return true;
}

// R⁽³⁾ = κω³ cos φ + Σ ρ_k ξ_k''', R⁽⁴⁾ = −κω⁴ sin φ + Σ ρ_k ξ_k'''' with ξ''' = −ν²ξ' + Fω cos φ,
// ξ'''' = −ν²ξ'' − Fω² sin φ (undamped constrained modes); the damped closed form has none.
template <class S>
bool ExactEngineT<S>::HeldReactionTaylor(const S& sigma, S* d) const {
  if (mode_ == Mode::kFree || damped_sticking_ || harm()) return false;
  const ContactData& cd = contacts_[static_cast<size_t>(start_contact_)];
  const auto& rho = cd.m->stick_reaction;
  const ForcingTrigT<S> fw(omega_, sigma);
  const S sf = fw.SinPhase(trig_), cf = fw.CosPhase(trig_);
  const S k = cd.reaction_forcing, w = omega_, w2 = omega_ * omega_;
  d[0] = cd.static_reaction - k * sf;
  d[1] = -k * w * cf;
  d[2] = k * w2 * sf;
  d[3] = k * w2 * w * cf;
  d[4] = -k * w2 * w2 * sf;
  if (!taylor_ready_) {
    taylor_.resize(cd.stick_modes.size());
    for (size_t q = 0; q < cd.stick_modes.size(); ++q) {
      const auto qq = static_cast<Eigen::Index>(q);
      const OscillatorT<S>& o = cd.stick_modes[q];
      const S den = o.nu * o.nu - w2;
      TaylorMode& tm = taylor_[q];
      tm.flow = !(o.nu > S(0)) || !(Real<S>::abs(den) >= S(0.25) * o.nu * o.nu);
      if (tm.flow) continue;
      tm.P = o.F / den;
      tm.a = xi0_[qq] - tm.P * trig_.s;
      tm.b = (dxi0_[qq] - tm.P * w * trig_.c) / o.nu;
    }
    taylor_ready_ = true;
  }
  for (size_t q = 0; q < cd.stick_modes.size(); ++q) {
    const auto qq = static_cast<Eigen::Index>(q);
    const OscillatorT<S>& o = cd.stick_modes[q];
    const S nu2 = o.nu * o.nu;
    const TaylorMode& tm = taylor_[q];
    if (!tm.flow) {
      // h = a cos νσ + b sin νσ, h' = ν(−a sin νσ + b cos νσ) = ν hp.
      S sn(0), cn(0);
      Real<S>::sincos(o.nu * sigma, sn, cn);
      const S h = tm.a * cn + tm.b * sn, hp = tm.b * cn - tm.a * sn;
      d[0] += rho[qq] * (tm.P * sf + h);
      d[1] += rho[qq] * (tm.P * w * cf + o.nu * hp);
      d[2] += rho[qq] * (-tm.P * w2 * sf - nu2 * h);
      d[3] += rho[qq] * (-tm.P * w2 * w * cf - nu2 * o.nu * hp);
      d[4] += rho[qq] * (tm.P * w2 * w2 * sf + nu2 * nu2 * h);
      continue;
    }
    const auto st = Flow<S>(o, omega_, trig_, xi0_[qq], dxi0_[qq], sigma, fw);
    const S xi = xi0_[qq] + st.dq;
    const S acc = -nu2 * xi + o.F * sf;
    d[0] += rho[qq] * xi;
    d[1] += rho[qq] * st.v;
    d[2] += rho[qq] * acc;
    d[3] += rho[qq] * (-nu2 * st.v + o.F * w * cf);
    d[4] += rho[qq] * (-nu2 * acc - o.F * w2 * sf);
  }
  return true;
}

template <class S>
S ExactEngineT<S>::Gap(S sigma) const {
  if (mode_ != Mode::kFree) return S(0);
  return GapProbe(start_contact_, sigma, S(0), S(0)).jet.g;
}

// Evaluate and Gap in one pass over the modes: the same flows, the same sums (GapProbeOf's g).
template <class S>
S ExactEngineT<S>::EvaluateWithGap(S sigma, Vec& X, Vec& V) const {
  if (mode_ != Mode::kFree) {
    Evaluate(sigma, X, V);
    return S(0);
  }
  const auto n = m_.dof();
  X.resize(n);
  V.resize(n);
  const ModelT<S>& mc = *contacts_[static_cast<size_t>(start_contact_)].m;
  const auto& c = mc.shape;
  S dq_sum(0);
  // Mode i's (Δq, v) into X, V and the gap's sum (the same operations on either path below).
  const auto put = [&](int i, const OscillatorStateT<S>& st) {
    X[i] = X0_[i] + st.dq;
    V[i] = st.v;
    if (c[i] != S(0)) dq_sum += mc.unit_shape ? st.dq : S(c[i] * st.dq);
  };
  if (MemoHit(sigma) && memo_contact_ == start_contact_) {
    for (int i = 0; i < n; ++i) put(i, memo_flow_[static_cast<size_t>(i)]);
  } else {
    const ForcingTrigT<S> fw(omega_, sigma);
    const size_t Hn = h_omega_.size();
    if (Hn) h_at_.At(h_omega_, h_trig_, sigma);
    for (int i = 0; i < n; ++i)
      put(i, Hn ? FlowSum<S>(free_modes_[static_cast<size_t>(i)], &free_hF_[static_cast<size_t>(i) * Hn],
                             h_omega_, h_trig_, h_at_, X0_[i], V0_[i], sigma)
                : Flow<S>(free_modes_[static_cast<size_t>(i)], omega_, trig_, X0_[i], V0_[i], sigma, fw));
  }
  const S g0 = contacts_.size() > 1 ? gap0s_[static_cast<size_t>(start_contact_)] : gap0_;
  return g0 + dq_sum;
}

template <class S>
bool ExactEngineT<S>::MemoHit(const S& sigma) const {
  if (memo_contact_ < 0) return false;
  if constexpr (std::is_same_v<S, double>)
    return std::bit_cast<std::uint64_t>(sigma) == std::bit_cast<std::uint64_t>(memo_sigma_);
  else
    return false;  // quad: no memo (its scalar's bits are not compared here)
}

template <class S>
S ExactEngineT<S>::GapOf(int j, S sigma) const {
  if (mode_ == Mode::kFree) return GapProbe(j, sigma, S(0), S(0)).jet.g;
  if (j == start_contact_) return S(0);
  return HeldGapProbe(j, sigma, S(0)).jet.g;
}

extern template class ExactEngineT<double>;

}  // namespace vibro::detail
