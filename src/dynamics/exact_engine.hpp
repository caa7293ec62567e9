// The exact engine: free flight and sticking advanced with the closed forms of docs/model.md §2, §4.2
// and §7, guards located by certified stepping on the trigonometric sums (docs/model.md §2.1).
// Templated on the scalar: ExactEngineT<double> is the default engine, ExactEngineT<Quad> the
// quad-precision reference (run.precision = "quad", dynamics/quad.hpp).
#pragma once

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
  // [sigma, sigma + H] (free flight). Public for tests.
  ProbeT<S> GapProbe(const S& sigma, const S& H) const;
  // Reaction R and its derivatives, with a bound on |R'''| (sticking, n ≥ 2).
  ProbeT<S> ReactionProbe(const S& sigma, const S& H) const;

 private:
  SegmentResultT<S> AdvanceFree(const S& sigma_max, bool detect_events);
  SegmentResultT<S> AdvanceSticking(const S& sigma_max, bool detect_events);
  template <class ProbeFn>
  SegmentResultT<S> Search(const ProbeFn& probe, const S& from, const S& sigma_max, SegmentEnd end);
  // Start of the certified search: the end of the window free of the trivial root at σ = 0.
  S FlightWindow() const;

  const ModelT<S>& m_;
  S omega_;
  S h_cap_;  // largest root-search step (the bounds grow with the step)
  std::vector<OscillatorT<S>> free_modes_;   // ω_i, ζ_i, T_A,i f
  std::vector<OscillatorT<S>> stick_modes_;  // ω'_k, 0, l_kᵀF_c f
  S reaction_forcing_;                       // (s_A/s_B) f
  bool damped_sticking_ = false;             // non-proportional damping in the constrained modes
  DampedSticking damped_;                    // its closed form (docs/model.md §7), double only

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
    if constexpr (std::is_same_v<S, double>) {
      if (damped_sticking_) damped_.Begin(xi0_, dxi0_, phase_);
    }
  }
}

template <class S>
ProbeT<S> ExactEngineT<S>::GapProbe(const S& sigma, const S& H) const {
  using R = Real<S>;
  const auto& c = m_.shape;
  const S s_forcing = trig_.s * R::cos(omega_ * sigma) + trig_.c * R::sin(omega_ * sigma);
  ProbeT<S> p{{gap0_, S(0), S(0)}, S(0)};
  S dq_sum(0);
  for (size_t i = 0; i < free_modes_.size(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    if (c[ii] == S(0)) continue;
    const OscillatorT<S>& o = free_modes_[i];
    const auto st = Flow<S>(o, omega_, trig_, X0_[ii], V0_[ii], sigma);
    const S x = X0_[ii] + st.dq;
    dq_sum += st.dq;
    p.jet.g1 += st.v;
    p.jet.g2 += -o.nu * o.nu * x - S(2) * o.zeta * o.nu * st.v + o.F * s_forcing;
    p.M += Bounds<S>(o, omega_, Amplitude<S>(o, x, st.v) + R::abs(o.F) * H).d3;
  }
  p.jet.g += dq_sum;
  p.M *= BoundMargin<S>();
  return p;
}

template <class S>
ProbeT<S> ExactEngineT<S>::ReactionProbe(const S& sigma, const S& H) const {
  using R = Real<S>;
  const auto& rho = m_.stick_reaction;
  const S sf = R::sin(phase_ + omega_ * sigma), cf = R::cos(phase_ + omega_ * sigma);
  ProbeT<S> p{{static_reaction_ - reaction_forcing_ * sf, -reaction_forcing_ * omega_ * cf,
               reaction_forcing_ * omega_ * omega_ * sf},
              R::abs(reaction_forcing_) * omega_ * omega_ * omega_};
  for (size_t k = 0; k < stick_modes_.size(); ++k) {
    const auto kk = static_cast<Eigen::Index>(k);
    const OscillatorT<S>& o = stick_modes_[k];
    const auto st = Flow<S>(o, omega_, trig_, xi0_[kk], dxi0_[kk], sigma);
    const S xi = xi0_[kk] + st.dq;
    p.jet.g += rho[kk] * xi;
    p.jet.g1 += rho[kk] * st.v;
    p.jet.g2 += rho[kk] * (-o.nu * o.nu * xi + o.F * sf);
    p.M += R::abs(rho[kk]) * Bounds<S>(o, omega_, Amplitude<S>(o, xi, st.v) + R::abs(o.F) * H).d3;
  }
  p.M *= BoundMargin<S>();
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
  return Search([this](const S& u, const S& H) { return GapProbe(u, H); }, w, sigma_max,
                SegmentEnd::kContact);
}

template <class S>
SegmentResultT<S> ExactEngineT<S>::AdvanceSticking(const S& sigma_max, bool detect_events) {
  if constexpr (std::is_same_v<S, double>) {
    if (damped_sticking_ && !damped_.ok())
      return {SegmentEnd::kFailure, 0.0,
              "the damped constrained system is defective (critically damped constrained mode): "
              "no closed form; change structure.damping_ratios slightly, or use run.engine = "
              "\"cvode\""};
  } else {
    if (damped_sticking_)
      return {SegmentEnd::kFailure, S(0),
              "run.precision = \"quad\" has no closed form for damped sticking of two or more "
              "modes; use run.precision = \"double\""};
  }
  if (!detect_events) return {SegmentEnd::kLimit, sigma_max, {}};
  const auto probe = [this](const S& u, const S& H) -> ProbeT<S> {
    if constexpr (std::is_same_v<S, double>) {
      if (damped_sticking_) return damped_.ReactionProbe(u);
    }
    return ReactionProbe(u, H);
  };
  S w(0);
  if (stick_start_ != StickStart::kGeneric) {
    const ProbeT<S> p = probe(S(0), h_cap_);
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
    for (int i = 0; i < n; ++i) {
      const auto st =
          Flow<S>(free_modes_[static_cast<size_t>(i)], omega_, trig_, X0_[i], V0_[i], sigma);
      X[i] = X0_[i] + st.dq;
      V[i] = st.v;
    }
    return;
  }
  const auto k_count = static_cast<Eigen::Index>(stick_modes_.size());
  Vec xi(k_count), dxi(k_count);
  bool done = false;
  if constexpr (std::is_same_v<S, double>) {
    if (damped_sticking_) {
      damped_.Evaluate(sigma, xi, dxi);
      done = true;
    }
  }
  for (Eigen::Index k = 0; k < k_count && !done; ++k) {
    const auto st =
        Flow<S>(stick_modes_[static_cast<size_t>(k)], omega_, trig_, xi0_[k], dxi0_[k], sigma);
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
