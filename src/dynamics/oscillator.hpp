// Closed-form flow of one linear oscillator  q̈ + 2ζν q̇ + ν² q = F sin(φ + ω σ)  in local time σ
// from (q0, v0) at σ = 0 (MODEL §2 relative form, §7 damping, §8.1 resonance).
//
// Results are increments Δq = q(σ) − q0: during chattering the gap is O(v²) while the modal
// terms are O(1), and only increments keep relative accuracy (MODEL §2, §8.12). The undamped
// kernel is written with divided differences that stay finite and accurate at and near exact
// resonance ν = ω.
#pragma once

namespace vibro::detail {

struct Oscillator {
  double nu;    // ν > 0, natural pulsation
  double zeta;  // ζ ∈ [0, 1)
  double F;     // forcing amplitude (T_A,i f, or l_kᵀF_c f in sticking)
};

struct OscillatorState {
  double dq;  // q(σ) − q0
  double v;   // q̇(σ)
};

// sin and cos of the forcing phase φ at σ = 0 (computed once per segment).
struct PhaseTrig {
  double s, c;
  explicit PhaseTrig(double phase);
};

// Flow over σ ≥ 0; ω > 0 forcing pulsation, φ forcing phase at σ = 0.
OscillatorState Flow(const Oscillator& o, double omega, const PhaseTrig& phase, double q0,
                     double v0, double sigma);
inline OscillatorState Flow(const Oscillator& o, double omega, double phase, double q0, double v0,
                            double sigma) {
  return Flow(o, omega, PhaseTrig(phase), q0, v0, sigma);
}

// Energy amplitude A = √(v² + ν² q²). Over a window of length h starting at a state of amplitude
// A, A(σ) ≤ A + |F| h (damping only removes energy), which bounds every derivative:
struct DerivativeBounds {
  double d2, d3, d4;  // bounds on |q''|, |q'''|, |q''''| over the window
};
DerivativeBounds Bounds(const Oscillator& o, double omega, double amplitude_at_window_end);

double Amplitude(const Oscillator& o, double q, double v);

}  // namespace vibro::detail
