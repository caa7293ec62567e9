// Closed-form flow of one linear oscillator  q̈ + 2ζν q̇ + ν² q = F sin(φ + ω σ)  in local time σ
// from (q0, v0) at σ = 0 (docs/model.md §2 relative form, §7 damping, §8.1 resonance), in the scalar S of
// the engine (dynamics/scalar.hpp).
//
// Results are increments Δq = q(σ) − q0: during chattering the gap is O(v²) while the modal
// terms are O(1), and only increments keep relative accuracy (docs/model.md §2, §8.12). The undamped
// kernel is written with divided differences that stay finite and accurate at and near exact
// resonance ν = ω.
#pragma once

#include <type_traits>

#include "dynamics/scalar.hpp"

namespace vibro::detail {

template <class S>
struct OscillatorT {
  S nu;    // ν > 0, natural pulsation
  S zeta;  // ζ ∈ [0, 1)
  S F;     // forcing amplitude (T_A,i f, or l_kᵀF_c f in sticking)
};

template <class S>
struct OscillatorStateT {
  S dq;  // q(σ) − q0
  S v;   // q̇(σ)
};

// sin and cos of the forcing phase φ at σ = 0 (computed once per segment).
template <class S>
struct PhaseTrigT {
  S s, c;
  explicit PhaseTrigT(const S& phase) : s(Real<S>::sin(phase)), c(Real<S>::cos(phase)) {}
  PhaseTrigT(const S& sin_phase, const S& cos_phase) : s(sin_phase), c(cos_phase) {}
};

// The forcing's angle ωσ at one local time σ, shared by every mode evaluated at that σ (one
// sincos per probe instead of one per mode): sin and cos of ωσ/2, sin ωσ and cos ωσ − 1 written
// with the half angle so that they keep relative accuracy as σ → 0.
template <class S>
struct ForcingTrigT {
  S s2, c2;  // sin(ωσ/2), cos(ωσ/2)
  S s, cm1;  // sin ωσ, cos ωσ − 1
  ForcingTrigT(const S& omega, const S& sigma) {
    Real<S>::sincos(S(0.5) * omega * sigma, s2, c2);
    s = S(2) * s2 * c2;
    cm1 = S(-2) * s2 * s2;
  }
  // sin(φ + ωσ), cos(φ + ωσ) for the segment's phase φ.
  S SinPhase(const PhaseTrigT<S>& ph) const { return ph.s * (S(1) + cm1) + ph.c * s; }
  S CosPhase(const PhaseTrigT<S>& ph) const { return ph.c * (S(1) + cm1) - ph.s * s; }
};

using Oscillator = OscillatorT<double>;
using OscillatorState = OscillatorStateT<double>;
using PhaseTrig = PhaseTrigT<double>;

namespace osc {

// sin(x)/x, accurate at and near 0.
template <class S>
S Sinc(const S& x) {
  const S x2 = x * x;
  if constexpr (std::is_same_v<S, double>) {
    if (x2 < 1e-6) return 1.0 - x2 / 6.0 * (1.0 - x2 / 20.0);
  } else {
    if (x2 < S(1e-10)) return S(1) - x2 / 6 * (S(1) - x2 / 20 * (S(1) - x2 / 42));
  }
  return Real<S>::sin(x) / x;
}

// Undamped: Δq = q0 (cos νσ − 1) + v0 sin(νσ)/ν + F K(σ), v = −q0 ν sin νσ + v0 cos νσ + F K'(σ),
// K(σ) = sin φ C(σ) + cos φ S(σ), K'(σ) = sin φ E(σ) + cos φ ω C(σ), with δ = ν − ω, Σ = ν + ω:
//   C = (cos ωσ − cos νσ)/(ν² − ω²)         = σ sin(Σσ/2) sinc(δσ/2) / Σ
//   S = (sin ωσ − (ω/ν) sin νσ)/(ν² − ω²)    = [sin νσ − νσ cos(Σσ/2) sinc(δσ/2)] / (νΣ)
//   E = (ν sin νσ − ω sin ωσ)/(ν² − ω²)      = [νσ cos(Σσ/2) sinc(δσ/2) + sin ωσ] / Σ
// finite at ν = ω (docs/model.md §8: K → [sin ωσ cos φ − ωσ cos(φ + ωσ)]/(2ω²)).
// The half angles νσ/2 and ωσ/2 are the only ones evaluated: νσ and Σσ/2 = νσ/2 + ωσ/2 follow
// by the double-angle and addition formulas (absolute error a few ulps, like the direct sines of
// the rounded arguments), δσ/2 = νσ/2 − ωσ/2 by the subtraction formula only where |δσ/2| ≥ 1/2
// (relative error ≤ 4 ulps · νσ there); closer to resonance sinc(δσ/2) is evaluated directly.
template <class S>
OscillatorStateT<S> Undamped(const OscillatorT<S>& o, const S& omega, const PhaseTrigT<S>& ph,
                             const S& q0, const S& v0, const S& sigma, const ForcingTrigT<S>& fw) {
  using R = Real<S>;
  const S nu = o.nu;
  S half, half_c;
  R::sincos(S(0.5) * nu * sigma, half, half_c);
  const S sn = S(2) * half * half_c;
  const S cn = S(1) - S(2) * half * half;
  OscillatorStateT<S> out{q0 * (S(-2) * half * half) + v0 * sn / nu, -q0 * nu * sn + v0 * cn};
  if (o.F == S(0)) return out;
  const S sum = nu + omega, diff = nu - omega;
  const S x = S(0.5) * diff * sigma;
  const S sc = R::abs(x) < S(0.5) ? Sinc<S>(x) : S((half * fw.c2 - half_c * fw.s2) / x);
  const S s_half = half * fw.c2 + half_c * fw.s2, c_half = half_c * fw.c2 - half * fw.s2;
  const S C = sigma * s_half * sc / sum;
  const S Sk = (sn - nu * sigma * c_half * sc) / (nu * sum);
  const S E = (nu * sigma * c_half * sc + fw.s) / sum;
  out.dq += o.F * (ph.s * C + ph.c * Sk);
  out.v += o.F * (ph.s * E + ph.c * omega * C);
  return out;
}

// Damped (docs/model.md §7): q = U(φ + ωσ) + h(σ), U = P sin + Q cos the steady forced response,
// h the decaying homogeneous part; Δq = [U(φ+ωσ) − U(φ)] + [h(σ) − h(0)] written as increments.
template <class S>
OscillatorStateT<S> Damped(const OscillatorT<S>& o, const S& omega, const PhaseTrigT<S>& ph,
                           const S& q0, const S& v0, const S& sigma, const ForcingTrigT<S>& fw) {
  using R = Real<S>;
  const S nu = o.nu, z = o.zeta;
  const S a = z * nu, nud = nu * R::sqrt(S(1) - z * z);
  const S den = (nu * nu - omega * omega) * (nu * nu - omega * omega) +
                (S(2) * z * nu * omega) * (S(2) * z * nu * omega);
  const S P = o.F * (nu * nu - omega * omega) / den;
  const S Q = -o.F * S(2) * z * nu * omega / den;
  const S sp = ph.s, cp = ph.c;
  const S U0 = P * sp + Q * cp, dU0 = omega * (P * cp - Q * sp);
  const S A = q0 - U0, B = v0 - dU0;
  const S Cc = (B + a * A) / nud;
  // e = 1 + (e − 1) keeps relative accuracy while e ≥ 1/2; below, exp itself.
  const S em1 = R::expm1(-a * sigma);
  const S e = em1 > S(-0.5) ? S(S(1) + em1) : R::exp(-a * sigma);
  S hd, hdc;
  R::sincos(S(0.5) * nud * sigma, hd, hdc);
  const S sd = S(2) * hd * hdc;
  const S cd = S(1) - S(2) * hd * hd;
  const S dh = A * (em1 * cd - S(2) * hd * hd) + Cc * e * sd;
  const S vh = e * (B * cd - (a * B + nu * nu * A) / nud * sd);
  const S dsin = sp * fw.cm1 + cp * fw.s;  // sin(φ+ωσ) − sin φ
  const S dcos = cp * fw.cm1 - sp * fw.s;  // cos(φ+ωσ) − cos φ
  const S dU = P * dsin + Q * dcos;
  const S vU = omega * (P * (cp + dcos) - Q * (sp + dsin));
  return {dU + dh, vU + vh};
}

}  // namespace osc

// Flow over σ ≥ 0; ω > 0 forcing pulsation, φ forcing phase at σ = 0, fw the forcing's angle at σ.
template <class S>
OscillatorStateT<S> Flow(const OscillatorT<S>& o, const S& omega, const PhaseTrigT<S>& phase,
                         const S& q0, const S& v0, const S& sigma, const ForcingTrigT<S>& fw) {
  return o.zeta > S(0) ? osc::Damped(o, omega, phase, q0, v0, sigma, fw)
                       : osc::Undamped(o, omega, phase, q0, v0, sigma, fw);
}
template <class S>
OscillatorStateT<S> Flow(const OscillatorT<S>& o, const S& omega, const PhaseTrigT<S>& phase,
                         const S& q0, const S& v0, const S& sigma) {
  return Flow<S>(o, omega, phase, q0, v0, sigma, ForcingTrigT<S>(omega, sigma));
}
inline OscillatorState Flow(const Oscillator& o, double omega, double phase, double q0, double v0,
                            double sigma) {
  return Flow<double>(o, omega, PhaseTrig(phase), q0, v0, sigma);
}

// Energy amplitude A = √(v² + ν² q²). Over a window of length h starting at a state of amplitude
// A, A(σ) ≤ A + |F| h (damping only removes energy), which bounds every derivative:
template <class S>
struct DerivativeBoundsT {
  S d2, d3, d4;  // bounds on |q''|, |q'''|, |q''''| over the window
};

template <class S>
DerivativeBoundsT<S> Bounds(const OscillatorT<S>& o, const S& omega, const S& A) {
  // q'' = −ν²q − 2ζνq' + F sin, q''' = −ν²q' − 2ζνq'' + Fω cos, q'''' = −ν²q'' − 2ζνq''' − Fω² sin
  // with |q'| ≤ A and ν|q| ≤ A.
  const S F = Real<S>::abs(o.F), nu = o.nu, tz = S(2) * o.zeta * nu;
  DerivativeBoundsT<S> b{};
  b.d2 = nu * A + tz * A + F;
  // Undamped (tz = ±0) with d2 finite, tz·d2 = ±0 and ν²A + ±0 = ν²A (ν²A ≥ +0 or NaN): the same
  // double without waiting for d2, which is on the path from a probe's state to its bound (an
  // `if`, not a select, so that the bound does not wait for both; docs/performance.md, "The
  // first Newton step without M").
  if (tz == S(0) && Real<S>::isfinite(b.d2))
    b.d3 = nu * nu * A + F * omega;
  else
    b.d3 = nu * nu * A + tz * b.d2 + F * omega;
  b.d4 = nu * nu * b.d2 + tz * b.d3 + F * omega * omega;
  return b;
}

template <class S>
S Amplitude(const OscillatorT<S>& o, const S& q, const S& v) {
  // √(v² + (νq)²) rounds within a few ulps, far inside BoundMargin; hypot's care for overflow
  // costs a fifth of a stiff run, so it is kept for the (never seen) overflowing case only.
  const S nq = o.nu * q;
  const S a = Real<S>::sqrt(v * v + nq * nq);
  // Below 1e-150 the squares may underflow: hypot again.
  return Real<S>::isfinite(a) && a > S(1e-150) ? a : Real<S>::hypot(v, nq);
}

}  // namespace vibro::detail
