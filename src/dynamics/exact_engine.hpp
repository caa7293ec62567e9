// The exact engine: free flight and sticking advanced with the closed forms of docs/model.md §2, §4.2
// and §7, guards located by certified stepping on the trigonometric sums (docs/model.md §2.1).
// Templated on the scalar: ExactEngineT<double> is the default engine, ExactEngineT<Quad> the
// quad-precision reference (run.precision = "quad", dynamics/quad.hpp).
#pragma once

#include <algorithm>
#include <type_traits>
#include <vector>

#include "dynamics/damped_sticking.hpp"
#include "dynamics/flight_window.hpp"
#include "dynamics/model_t.hpp"
#include "dynamics/oscillator.hpp"
#include "dynamics/propagator.hpp"
#include "dynamics/root_finder.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

template <class S>
class ExactEngineT final : public PropagatorT<S> {
 public:
  using Vec = typename ModelT<S>::Vec;

  ExactEngineT(const System& system, const ModelT<S>& model);

  void Begin(const SegmentStartT<S>& start) override;
  SegmentResultT<S> Advance(S sigma_max, bool detect_events,
                            const StretchCallbackT<S>& on_stretch) override;
  void Evaluate(S sigma, Vec& X, Vec& V) const override;
  S Gap(S sigma) const override;

  // Gap g = x_B − x0 and its derivatives at local time sigma, with a bound on |g'''| over
  // [sigma, sigma + H] (free flight), and with rest > H the far bound over a window of up to
  // `rest` (root_finder.hpp, AddFarBound). Public for tests.
  ProbeT<S> GapProbe(const S& sigma, const S& H, const S& rest = S(0)) const;
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
  S omega_;
  S h_cap_;  // largest root-search step (the bounds grow with the step)
  std::vector<OscillatorT<S>> free_modes_;   // ω_i, ζ_i, T_A,i f
  std::vector<OscillatorT<S>> stick_modes_;  // ω'_k, 0, l_kᵀF_c f
  std::vector<ModeFar> free_far_, stick_far_;
  std::vector<int> free_order_, stick_order_;  // mode indices, fastest first
  mutable std::vector<ModeSample> samples_;     // scratch of the probes (no allocation per probe)
  S reaction_forcing_;                       // (s_A/s_B) f
  bool damped_sticking_ = false;             // non-proportional damping in the constrained modes
  // Its closed form (docs/model.md §7): DampedStickingT<Quad> is declared in
  // dynamics/damped_sticking_quad.hpp, which the quad instantiation includes
  // (dynamics/exact_engine_quad.hpp).
  DampedStickingT<S> damped_;

  // Current segment.
  Mode mode_ = Mode::kFree;
  S phase_{0};
  PhaseTrigT<S> trig_{S(0)};
  Vec X0_, V0_;     // free flight start
  Vec xi0_, dxi0_;  // sticking start, constrained modal coordinates
  S gap0_{0};
  S static_reaction_{0};  // x0 / flexibility
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
                       sys.constrained().damping.cwiseAbs().maxCoeff() > 0),
      damped_(sys) {
  for (int i = 0; i < m.dof(); ++i)
    free_modes_.push_back({m.omega[i], m.zeta[i], m.forcing[i] * m.f});
  for (Eigen::Index k = 0; k < m.stick_frequencies.size(); ++k)
    stick_modes_.push_back({m.stick_frequencies[k], S(0), m.stick_forcing[k] * m.f});
  h_cap_ = StepCap<S>(m);
  reaction_forcing_ = m.s_A / m.s_B * m.f;
  static_reaction_ = m.x0 / m.flexibility;
  const auto far_of = [&](const std::vector<OscillatorT<S>>& modes, const auto& weight,
                          std::vector<ModeFar>& far, std::vector<int>& order) {
    for (size_t i = 0; i < modes.size(); ++i) {
      const OscillatorT<S>& o = modes[i];
      const S d = o.nu * o.nu - omega_ * omega_, e = S(2) * o.zeta * o.nu * omega_;
      const S den = d * d + e * e;
      const bool eligible = o.nu >= S(2) * omega_ && weight(i) != S(0);
      far.push_back(eligible ? ModeFar{o.F * d / den, -o.F * e / den,
                                       Real<S>::abs(o.F) / Real<S>::sqrt(den), true}
                             : ModeFar{S(0), S(0), S(0), false});
      order.push_back(static_cast<int>(i));
    }
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return modes[static_cast<size_t>(a)].nu > modes[static_cast<size_t>(b)].nu;
    });
  };
  far_of(free_modes_, [&](size_t i) { return m.shape[static_cast<Eigen::Index>(i)]; }, free_far_,
         free_order_);
  far_of(stick_modes_, [&](size_t k) { return m.stick_reaction[static_cast<Eigen::Index>(k)]; },
         stick_far_, stick_order_);
  samples_.resize(std::max(free_modes_.size(), stick_modes_.size()));
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
  mode_ = s.mode;
  phase_ = s.phase;
  trig_ = PhaseTrigT<S>(s.phase);
  gap0_ = s.gap;
  flight_start_ = s.flight_start;
  stick_start_ = s.stick_start;
  if (mode_ == Mode::kFree) {
    X0_ = s.X;
    V0_ = s.V;
  } else {
    // ξ = L X (L v0 = 0), ξ̇ = L Ẋ (docs/model.md §4.2).
    xi0_ = m_.stick_left * s.X;
    dxi0_ = m_.stick_left * s.V;
    if (damped_sticking_) damped_.Begin(xi0_, dxi0_, phase_);
  }
}

template <class S>
ProbeT<S> ExactEngineT<S>::GapProbe(const S& sigma, const S& H, const S& rest) const {
  using R = Real<S>;
  const auto& c = m_.shape;
  const ForcingTrigT<S> fw(omega_, sigma);
  const S s_forcing = fw.SinPhase(trig_);
  const bool far = rest > H;
  const S c_forcing = far ? fw.CosPhase(trig_) : S(0);
  ProbeT<S> p{{gap0_, S(0), S(0)}, S(0)};
  S dq_sum(0);
  for (size_t i = 0; i < free_modes_.size(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    if (c[ii] == S(0)) continue;
    const OscillatorT<S>& o = free_modes_[i];
    const auto st = Flow<S>(o, omega_, trig_, X0_[ii], V0_[ii], sigma, fw);
    const S x = X0_[ii] + st.dq;
    const S acc = -o.nu * o.nu * x - S(2) * o.zeta * o.nu * st.v + o.F * s_forcing;
    const S A = Amplitude<S>(o, x, st.v);
    dq_sum += st.dq;
    p.jet.g1 += st.v;
    p.jet.g2 += acc;
    p.M += Bounds<S>(o, omega_, A + R::abs(o.F) * H).d3;
    if (far) {
      const ModeFar& mf = free_far_[i];
      samples_[i] = {x, st.v, acc, A,
                     mf.eligible ? Loss(o, mf, S(1), x, st.v, s_forcing, c_forcing) : S(0), false};
    }
  }
  p.jet.g += dq_sum;
  p.M *= BoundMargin<S>();
  if (far && p.jet.g > 0)
    AddFarBound(p, free_modes_, free_far_, free_order_, nullptr, {S(0), S(0), S(0)}, S(0), H, rest);
  return p;
}

template <class S>
ProbeT<S> ExactEngineT<S>::ReactionProbe(const S& sigma, const S& H, const S& rest) const {
  using R = Real<S>;
  const auto& rho = m_.stick_reaction;
  const ForcingTrigT<S> fw(omega_, sigma);
  const S sf = fw.SinPhase(trig_), cf = fw.CosPhase(trig_);
  const JetT<S> base{static_reaction_ - reaction_forcing_ * sf, -reaction_forcing_ * omega_ * cf,
                     reaction_forcing_ * omega_ * omega_ * sf};
  const S base_M = R::abs(reaction_forcing_) * omega_ * omega_ * omega_;
  ProbeT<S> p{base, base_M};
  const bool far = rest > H;
  for (size_t k = 0; k < stick_modes_.size(); ++k) {
    const auto kk = static_cast<Eigen::Index>(k);
    const OscillatorT<S>& o = stick_modes_[k];
    const auto st = Flow<S>(o, omega_, trig_, xi0_[kk], dxi0_[kk], sigma, fw);
    const S xi = xi0_[kk] + st.dq;
    const S acc = -o.nu * o.nu * xi + o.F * sf;
    const S A = Amplitude<S>(o, xi, st.v);
    p.jet.g += rho[kk] * xi;
    p.jet.g1 += rho[kk] * st.v;
    p.jet.g2 += rho[kk] * acc;
    p.M += R::abs(rho[kk]) * Bounds<S>(o, omega_, A + R::abs(o.F) * H).d3;
    if (far) {
      const ModeFar& mf = stick_far_[k];
      samples_[k] = {xi, st.v, acc, A,
                     mf.eligible ? Loss(o, mf, rho[kk], xi, st.v, sf, cf) : S(0), false};
    }
  }
  p.M *= BoundMargin<S>();
  if (far && p.jet.g > 0)
    AddFarBound(p, stick_modes_, stick_far_, stick_order_, &rho, base, base_M * BoundMargin<S>(),
                H, rest);
  return p;
}

template <class S>
S ExactEngineT<S>::FlightWindow() const {
  // docs/model.md §2.1: divide out the known zero at σ = 0; no root in the certified window (0, σ_w).
  if (flight_start_ == FlightStart::kGeneric) return S(0);
  return CertifiedWindow<S>(flight_start_, StartJet<S>(m_, X0_, V0_, phase_, h_cap_), h_cap_);
}

template <class S>
template <class ProbeFn>
SegmentResultT<S> ExactEngineT<S>::Search(const ProbeFn& probe, const S& from, const S& sigma_max,
                                          SegmentEnd end) {
  const auto rs = FirstRootPolled<S>(probe, from, sigma_max, h_cap_,
                                     [this] { return this->StopRequested(); });
  if (rs.stopped)
    return {SegmentEnd::kFailure, rs.result.sigma, "stopped inside a root search", S(-1), true};
  if (!rs.result.found) return {SegmentEnd::kLimit, sigma_max, {}};
  return {end, rs.result.sigma, {}};
}

template <class S>
SegmentResultT<S> ExactEngineT<S>::AdvanceFree(const S& sigma_max, bool detect_events) {
  if (!detect_events) return {SegmentEnd::kLimit, sigma_max, {}};
  const S w = FlightWindow();
  if (w >= sigma_max) return {SegmentEnd::kLimit, sigma_max, {}};
  return Search([this](const S& u, const S& H, const S& rest) { return GapProbe(u, H, rest); }, w,
                sigma_max,
                SegmentEnd::kContact);
}

template <class S>
SegmentResultT<S> ExactEngineT<S>::AdvanceSticking(const S& sigma_max, bool detect_events) {
  if (damped_sticking_ && !damped_.ok()) {
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
  if (!detect_events) return {SegmentEnd::kLimit, sigma_max, {}};
  const auto probe = [this](const S& u, const S& H, const S& rest) -> ProbeT<S> {
    if (damped_sticking_) return damped_.ReactionProbe(u);
    return ReactionProbe(u, H, rest);
  };
  S w(0);
  if (stick_start_ != StickStart::kGeneric) {
    const ProbeT<S> p = probe(S(0), h_cap_, S(0));
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
  if (w >= sigma_max) return {SegmentEnd::kLimit, sigma_max, {}};
  return Search(probe, w, sigma_max, SegmentEnd::kRelease);
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
  if (mode_ == Mode::kFree) {
    const ForcingTrigT<S> fw(omega_, sigma);
    for (int i = 0; i < n; ++i) {
      const auto st =
          Flow<S>(free_modes_[static_cast<size_t>(i)], omega_, trig_, X0_[i], V0_[i], sigma, fw);
      X[i] = X0_[i] + st.dq;
      V[i] = st.v;
    }
    return;
  }
  const auto k_count = static_cast<Eigen::Index>(stick_modes_.size());
  Vec xi(k_count), dxi(k_count);
  bool done = false;
  if (damped_sticking_) {
    damped_.Evaluate(sigma, xi, dxi);
    done = true;
  }
  const ForcingTrigT<S> fw(omega_, sigma);
  for (Eigen::Index k = 0; k < k_count && !done; ++k) {
    const auto st =
        Flow<S>(stick_modes_[static_cast<size_t>(k)], omega_, trig_, xi0_[k], dxi0_[k], sigma, fw);
    xi[k] = xi0_[k] + st.dq;
    dxi[k] = st.v;
  }
  X = m_.x0 * m_.static_shape + m_.stick_vectors * xi;
  V = m_.stick_vectors * dxi;
}

template <class S>
S ExactEngineT<S>::Gap(S sigma) const {
  if (mode_ != Mode::kFree) return S(0);
  return GapProbe(sigma, S(0)).jet.g;
}

extern template class ExactEngineT<double>;

}  // namespace vibro::detail
