// Closed-form oscillator flow (MODEL §2, §7, §8.1).
#include "dynamics/oscillator.hpp"

#include <cmath>

namespace vibro::detail {
namespace {

// sin(x)/x, accurate at and near 0.
double Sinc(double x) {
  const double x2 = x * x;
  if (x2 < 1e-6) return 1.0 - x2 / 6.0 * (1.0 - x2 / 20.0);
  return std::sin(x) / x;
}

// Undamped: Δq = q0 (cos νσ − 1) + v0 sin(νσ)/ν + F K(σ), v = −q0 ν sin νσ + v0 cos νσ + F K'(σ),
// K(σ) = sin φ C(σ) + cos φ S(σ), K'(σ) = sin φ E(σ) + cos φ ω C(σ), with δ = ν − ω, Σ = ν + ω:
//   C = (cos ωσ − cos νσ)/(ν² − ω²)         = σ sin(Σσ/2) sinc(δσ/2) / Σ
//   S = (sin ωσ − (ω/ν) sin νσ)/(ν² − ω²)    = [sin νσ − νσ cos(Σσ/2) sinc(δσ/2)] / (νΣ)
//   E = (ν sin νσ − ω sin ωσ)/(ν² − ω²)      = [νσ cos(Σσ/2) sinc(δσ/2) + sin ωσ] / Σ
// finite at ν = ω (MODEL §8.1: K → [sin ωσ cos φ − ωσ cos(φ + ωσ)]/(2ω²)).
OscillatorState Undamped(const Oscillator& o, double omega, const PhaseTrig& ph, double q0,
                         double v0, double sigma) {
  const double nu = o.nu;
  const double sn = std::sin(nu * sigma), half = std::sin(0.5 * nu * sigma);
  const double cn = 1.0 - 2.0 * half * half;
  OscillatorState out{q0 * (-2.0 * half * half) + v0 * sn / nu, -q0 * nu * sn + v0 * cn};
  if (o.F == 0.0) return out;
  const double sum = nu + omega, diff = nu - omega;
  const double sc = Sinc(0.5 * diff * sigma);
  const double s_half = std::sin(0.5 * sum * sigma), c_half = std::cos(0.5 * sum * sigma);
  const double C = sigma * s_half * sc / sum;
  const double S = (sn - nu * sigma * c_half * sc) / (nu * sum);
  const double E = (nu * sigma * c_half * sc + std::sin(omega * sigma)) / sum;
  const double sp = ph.s, cp = ph.c;
  out.dq += o.F * (sp * C + cp * S);
  out.v += o.F * (sp * E + cp * omega * C);
  return out;
}

// Damped (MODEL §7): q = U(φ + ωσ) + h(σ), U = P sin + Q cos the steady forced response,
// h the decaying homogeneous part; Δq = [U(φ+ωσ) − U(φ)] + [h(σ) − h(0)] written as increments.
OscillatorState Damped(const Oscillator& o, double omega, const PhaseTrig& ph, double q0,
                       double v0, double sigma) {
  const double nu = o.nu, z = o.zeta;
  const double a = z * nu, nud = nu * std::sqrt(1.0 - z * z);
  const double den = (nu * nu - omega * omega) * (nu * nu - omega * omega) +
                     (2.0 * z * nu * omega) * (2.0 * z * nu * omega);
  const double P = o.F * (nu * nu - omega * omega) / den;
  const double Q = -o.F * 2.0 * z * nu * omega / den;
  const double sp = ph.s, cp = ph.c;
  const double U0 = P * sp + Q * cp, dU0 = omega * (P * cp - Q * sp);
  const double A = q0 - U0, B = v0 - dU0;
  const double Cc = (B + a * A) / nud;
  const double e = std::exp(-a * sigma), em1 = std::expm1(-a * sigma);
  const double sd = std::sin(nud * sigma), hd = std::sin(0.5 * nud * sigma);
  const double cd = 1.0 - 2.0 * hd * hd;
  const double dh = A * (em1 * cd - 2.0 * hd * hd) + Cc * e * sd;
  const double vh = e * (B * cd - (a * B + nu * nu * A) / nud * sd);
  const double sw = std::sin(omega * sigma), hw = std::sin(0.5 * omega * sigma);
  const double cwm1 = -2.0 * hw * hw;  // cos ωσ − 1
  const double dsin = sp * cwm1 + cp * sw;  // sin(φ+ωσ) − sin φ
  const double dcos = cp * cwm1 - sp * sw;  // cos(φ+ωσ) − cos φ
  const double dU = P * dsin + Q * dcos;
  const double vU = omega * (P * (cp + dcos) - Q * (sp + dsin));
  return {dU + dh, vU + vh};
}

}  // namespace

PhaseTrig::PhaseTrig(double phase) : s(std::sin(phase)), c(std::cos(phase)) {}

OscillatorState Flow(const Oscillator& o, double omega, const PhaseTrig& phase, double q0,
                     double v0, double sigma) {
  return o.zeta > 0.0 ? Damped(o, omega, phase, q0, v0, sigma)
                      : Undamped(o, omega, phase, q0, v0, sigma);
}

double Amplitude(const Oscillator& o, double q, double v) { return std::hypot(v, o.nu * q); }

DerivativeBounds Bounds(const Oscillator& o, double omega, double A) {
  // q'' = −ν²q − 2ζνq' + F sin, q''' = −ν²q' − 2ζνq'' + Fω cos, q'''' = −ν²q'' − 2ζνq''' − Fω² sin
  // with |q'| ≤ A and ν|q| ≤ A.
  const double F = std::abs(o.F), nu = o.nu, tz = 2.0 * o.zeta * nu;
  DerivativeBounds b{};
  b.d2 = nu * A + tz * A + F;
  b.d3 = nu * nu * A + tz * b.d2 + F * omega;
  b.d4 = nu * nu * b.d2 + tz * b.d3 + F * omega * omega;
  return b;
}

}  // namespace vibro::detail
