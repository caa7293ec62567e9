// The tail of a chattering sequence (docs/model.md §5.4, §5.4; docs/chattering.md): from the state just
// after an impact, predict the time Δ∞ to the accumulation point and estimate the error of that
// prediction, so that the automaton jumps only when the estimate is within the run's target and
// otherwise follows the next impact.
//
// With u = ẋ_B⁺ the contact speed after the impact and R, Ṙ the reaction and its rate on the
// stuck state (the post-impact state projected onto the stop, the mean path of the tail):
//   Δ0 = 2u / ((1−r) s_B R)          constant-R sum of the geometric tail (docs/model.md §5.4)
//   ε  = −Ṙ Δ0 / R                   how much R falls over the tail (docs/model.md §5.4)
//   Δ∞ = Δ0 (1 + ε/3)                first-order correction for a linearly varying R
// The prediction is accepted only when |ε| ≤ 0.1 (a sequence with ε above ≈ 0.6 never completes;
// near it no truncated expansion can be trusted) and the estimated time error
//   E = Δ0 [0.3 ε² + |R̈| Δ0²/(2R) + M3 Δ0³/(6R) + (ω_c Δ0)²/4 + |β| Δ0/2]
// is within the target: 0.3 ε² is the residual of the linear-R correction (docs/model.md §5.4); the
// curvature terms bound what a quadratic and cubic change of R over the tail can do (R̈ the free
// second derivative at the start, M3 a bound on |R'''| over the window from the modal amplitudes,
// docs/model.md §2.1); ω_c² = Σ c_i T_B,i ω_i² / s_B is the contact's own stiffness, whose restoring force
// on the O(v²) gap of the tail the constant-R model ignores; β = Σ c_i 2ζ_iω_i T_B,i / s_B is the
// damping the contact velocity itself feels (g'' = −s_B R − β g' over a flight of the tail), which
// shortens the tail by β Δ0²/6 to first order (each flight by 2βv²/(3a²), the arrival speeds by
// 2βv²/(3a)); the term bounds it with a factor 3 to spare. It is 0 without damping.
#pragma once

#include <cmath>

#include <Eigen/Dense>

#include "dynamics/model_t.hpp"
#include "dynamics/harmonic_flow.hpp"
#include "dynamics/oscillator.hpp"

namespace vibro::detail {

// Largest |ε| at which a prediction is trusted.
inline constexpr double kTailEpsilonMax = 0.1;

template <class S>
struct TailPrediction {
  bool accepted = false;
  S delta{0};    // Δ∞, time from the impact to the accumulation point
  S delta0{0};   // Δ0
  S epsilon{0};  // ε
  S error{0};    // estimated error of Δ∞ (time)
  S reaction{0}, rate{0}, speed{0};  // R, Ṙ on the stuck state, u = ẋ_B⁺
};

// The terms of E are computed cheapest first and the prediction is refused as soon as their sum
// exceeds the target (early in a sequence, most impacts), so that `error` of a refused prediction
// is a lower bound of E.
// sp, cp = sin φ, cos φ of the phase; W scratch (no allocation per impact).
template <class S>
TailPrediction<S> PredictTail(const ModelT<S>& m, const typename ModelT<S>::Vec& X,
                              const typename ModelT<S>::Vec& V, const S& sp, const S& cp,
                              const S& target, typename ModelT<S>::Vec& W, const S* phase = nullptr) {
  using R = Real<S>;
  TailPrediction<S> t;
  t.speed = m.ContactVelocity(V);
  if (!(t.speed > 0) || !(m.r > 0) || !(m.r < 1)) return t;
  W = V - m.contact * (t.speed / m.s_B);  // ΠẊ: the stuck velocity
  t.reaction = m.ReactionSin(X, W, sp, phase);
  if (!(t.reaction > 0)) return t;
  t.delta0 = S(2) * t.speed / ((S(1) - m.r) * m.s_B * t.reaction);
  const S d = t.delta0;
  t.error = d * m.contact_stiffness * d * d / 4;
  if (m.damped) t.error += d * R::abs(m.contact_damping) * d / 2;
  if (!(t.error <= target)) return t;
  t.rate = m.ReactionRateTrig(X, W, sp, cp, phase);
  t.epsilon = -t.rate * t.delta0 / t.reaction;
  t.delta = t.delta0 * (S(1) + t.epsilon / 3);
  t.error += d * S(0.3) * t.epsilon * t.epsilon;
  if (!(t.error <= target) || !(R::abs(t.epsilon) <= S(kTailEpsilonMax))) return t;

  // Free second derivative of R at the start and a bound on |R'''| over [0, 2Δ0].
  const S H = S(2) * t.delta0;
  S r2 = m.s_A * m.f * m.w * m.w * sp, M3 = R::abs(m.s_A * m.f) * m.w * m.w * m.w;
  if (!m.harmonics.empty()) {  // a sum of harmonics (docs/harmonics.md)
    const auto& hs = m.harmonics;
    r2 = -hs.Contact(*phase, 2);
    M3 = hs.ContactBound(3);
    const typename ModelT<S>::Vec f0 = hs.Vector(*phase, 0), f1 = hs.Vector(*phase, 1);
    for (int i = 0; i < m.dof(); ++i) {
      if (m.shape[i] == S(0)) continue;
      const OscillatorT<S> o{m.omega[i], m.zeta[i], S(0)};
      HarmonicSumsT<S> F;
      for (const auto& h : hs.h) {
        const S a = R::abs(h.forcing[i]);
        F.f += a;
        F.fw += a * h.omega;
        F.fw2 += a * h.omega * h.omega;
      }
      const S w2 = o.nu * o.nu, tz = S(2) * o.zeta * o.nu;
      const S acc = -w2 * X[i] - tz * W[i] + f0[i];
      const S jerk = -w2 * W[i] - tz * acc + f1[i];
      r2 += m.shape[i] * (w2 * acc + tz * jerk);
      const auto b = BoundsSum<S>(o, F, Amplitude<S>(o, X[i], W[i]) + F.f * H);
      M3 += R::abs(m.shape[i]) * (w2 * b.d3 + tz * b.d4);
    }
  }
  for (int i = 0; i < m.dof() && m.harmonics.empty(); ++i) {
    if (m.shape[i] == S(0)) continue;
    const OscillatorT<S> o{m.omega[i], m.zeta[i], m.forcing[i] * m.f};
    const S w2 = o.nu * o.nu, tz = S(2) * o.zeta * o.nu;
    const S acc = -w2 * X[i] - tz * W[i] + o.F * sp;
    const S jerk = -w2 * W[i] - tz * acc + o.F * m.w * cp;
    r2 += m.shape[i] * (w2 * acc + tz * jerk);
    const auto b = Bounds<S>(o, m.w, Amplitude<S>(o, X[i], W[i]) + R::abs(o.F) * H);
    M3 += R::abs(m.shape[i]) * (w2 * b.d3 + tz * b.d4);
  }
  r2 /= m.s_B;
  M3 /= m.s_B;
  t.error += d * (R::abs(r2) * d * d / (S(2) * t.reaction) + M3 * d * d * d / (S(6) * t.reaction));
  t.accepted = R::isfinite(t.error) && t.error <= target;
  return t;
}

template <class S>
TailPrediction<S> PredictTail(const ModelT<S>& m, const typename ModelT<S>::Vec& X,
                              const typename ModelT<S>::Vec& V, const S& phase, const S& target) {
  typename ModelT<S>::Vec W;
  return PredictTail<S>(m, X, V, Real<S>::sin(phase), Real<S>::cos(phase), target, W, &phase);
}

// Gradient of the jump time for the Jacobian of the jump (docs/model.md §5.6), length 2n in (X, Ẋ).
// Δ∞ = Δ0 − Ṙ Δ0²/(3R) with Δ0 = 2u/((1−r) s_B R), u = cᵀẊ, R and Ṙ affine in (X, ΠẊ):
//   ∂Δ∞ = ∂Δ0 (1 + 2ε/3) − Δ0²/(3R) ∂Ṙ − εΔ0/(3R) ∂R,   ∂Δ0 = Δ0 (∂u/u − ∂R/R).
// The Poincaré solver expresses a perturbation after an impact as a state at the nominal impact
// time (saltation matrices), off the stop by δg = cᵀδX; the impact really happened τ = −δg/u
// later or earlier, and the prediction was made there. So the gradient of the jump actually taken
// is ∇Δ∞ − (1 + dΔ∞/dt)(c, 0)/u, with dΔ∞/dt the rate of the prediction along the free flow from
// the impact state (state and forcing phase). Without that term the Jacobian is off by O(u).
template <class S>
Eigen::VectorXd DeltaGradient(const ModelT<S>& m, const typename ModelT<S>::Vec& X,
                              const typename ModelT<S>::Vec& V, const S& phase,
                              const TailPrediction<S>& t) {
  using Vec = typename ModelT<S>::Vec;
  using Rl = Real<S>;
  const auto n = m.dof();
  const auto PiT = [&](const Vec& y) -> Vec { return y - m.shape * (m.contact.dot(y) / m.s_B); };
  const auto Pi = [&](const Vec& y) -> Vec { return y - m.contact * (m.shape.dot(y) / m.s_B); };
  const Vec w2 = m.omega.cwiseAbs2();
  const Vec D = S(2) * m.zeta.cwiseProduct(m.omega);
  const Vec cw2 = m.shape.cwiseProduct(w2), cD = m.shape.cwiseProduct(D);
  Vec gR(2 * n), gRd(2 * n), gu = Vec::Zero(2 * n);
  gR << cw2 / m.s_B, PiT(cD) / m.s_B;
  gRd << Vec::Zero(n), PiT(cw2) / m.s_B;
  if (m.damped) {
    const Vec PcD = PiT(cD);
    gRd.head(n) -= w2.cwiseProduct(PcD) / m.s_B;
    gRd.tail(n) -= PiT(D.cwiseProduct(PcD)) / m.s_B;
  }
  gu.tail(n) = m.shape;
  const S R = t.reaction, d0 = t.delta0, eps = t.epsilon;
  const S dD_dR = -(d0 / R) * (S(1) + S(2) * eps / 3) - eps * d0 / (S(3) * R);
  const S dD_dRd = -d0 * d0 / (S(3) * R);
  Vec g = dD_dR * gR + dD_dRd * gRd + (d0 / t.speed) * (S(1) + S(2) * eps / 3) * gu;

  // dΔ∞/dt along the free flow from (X, Ẋ) at the forcing phase φ.
  const S sp = Rl::sin(phase), cp = Rl::cos(phase);
  Vec field(2 * n);
  field << V, -w2.cwiseProduct(X) - D.cwiseProduct(V) + m.forcing * (m.f * sp);
  S dR_dphi = -m.s_A * m.f * cp / m.s_B;
  S dRd_dphi = m.s_A * m.f * m.w * sp / m.s_B;
  if (m.damped) dRd_dphi += cD.dot(Pi(m.forcing * (m.f * cp))) / m.s_B;
  S rate = g.dot(field) + m.w * (dD_dR * dR_dphi + dD_dRd * dRd_dphi);
  if (!m.harmonics.empty()) {  // a sum of harmonics: the forcing's rates in time (docs/harmonics.md)
    field.tail(n) += m.harmonics.Vector(phase);
    const S dR_dt = -m.harmonics.Contact(phase, 1) / m.s_B;
    S dRd_dt = -m.harmonics.Contact(phase, 2) / m.s_B;
    if (m.damped) dRd_dt += cD.dot(Pi(m.harmonics.Vector(phase, 1))) / m.s_B;
    rate = g.dot(field) + dD_dR * dR_dt + dD_dRd * dRd_dt;
  }
  g.head(n) -= (S(1) + rate) * m.shape / t.speed;
  return g.template cast<double>();
}

}  // namespace vibro::detail
