// Interval enclosures of vibro's closed forms (docs/prove.md), written again here from the model
// (docs/model.md §2, §3, §4.1, the paper's eqs (10)-(14), (5)) rather than borrowed from the engines, so that a
// proof depends on the formulas only:
//   free flight  X_i(t0+s) = U_i(t0+s) + a_i cos ω_i s + b_i sin ω_i s,  U_i(t) = T_A,i f sin ωt/(ω_i² − ω²),
//                a_i = X_i(t0) − U_i(t0),  b_i = (Ẋ_i(t0) − U̇_i(t0))/ω_i                      (13), (14)
//   impact       Ẋ⁺ = Ẋ⁻ + p T_B,  p = −(1+r) cᵀẊ⁻/s_B                                         (10)-(12)
//   reaction     R = (Σ c_i ω_i² X_i − s_A f sin ωt)/s_B on the stop                             (5)
// Every function is a template on the scalar: Interval (an enclosure over a box) or Dual (an
// enclosure together with the enclosure of its gradient over the box, for Krawczyk's test).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "proof/interval.hpp"

namespace vibro::proof {

// A value and its gradient with respect to the prover's unknowns, both enclosed. An empty
// gradient is a constant.
struct Dual {
  Interval v;
  std::vector<Interval> d;
  Dual() = default;
  Dual(const Interval& value) : v(value) {}  // NOLINT: a constant
  Dual(double value) : v(value) {}           // NOLINT: a constant
  static Dual Variable(const Interval& value, std::size_t index, std::size_t size) {
    Dual x(value);
    x.d.assign(size, Interval(0.0));
    x.d[index] = Interval(1.0);
    return x;
  }
};

namespace detail {
// out.d = α a.d + β b.d (either may be empty).
inline std::vector<Interval> Combine(const Interval& alpha, const std::vector<Interval>& a, const Interval& beta,
                                     const std::vector<Interval>& b) {
  const std::size_t n = a.size() > b.size() ? a.size() : b.size();
  std::vector<Interval> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (k < a.size()) out[k] += alpha * a[k];
    if (k < b.size()) out[k] += beta * b[k];
  }
  return out;
}
}  // namespace detail

inline Dual operator+(const Dual& a, const Dual& b) {
  Dual y(a.v + b.v);
  y.d = detail::Combine(1.0, a.d, 1.0, b.d);
  return y;
}
inline Dual operator-(const Dual& a, const Dual& b) {
  Dual y(a.v - b.v);
  y.d = detail::Combine(1.0, a.d, -1.0, b.d);
  return y;
}
inline Dual operator-(const Dual& a) { return Dual(0.0) - a; }
inline Dual operator*(const Dual& a, const Dual& b) {
  Dual y(a.v * b.v);
  y.d = detail::Combine(b.v, a.d, a.v, b.d);
  return y;
}
inline Dual operator/(const Dual& a, const Dual& b) {
  Dual y(a.v / b.v);
  y.d = detail::Combine(1.0 / b.v, a.d, -(a.v / Sqr(b.v)), b.d);
  return y;
}
inline Dual Sin(const Dual& x) {
  Dual y(Sin(x.v));
  y.d = detail::Combine(Cos(x.v), x.d, 0.0, {});
  return y;
}
inline Dual Cos(const Dual& x) {
  Dual y(Cos(x.v));
  y.d = detail::Combine(-Sin(x.v), x.d, 0.0, {});
  return y;
}
inline Dual Exp(const Dual& x) {
  Dual y(Exp(x.v));
  y.d = detail::Combine(y.v, x.d, 0.0, {});
  return y;
}
inline const Interval& Value(const Interval& x) { return x; }
inline const Interval& Value(const Dual& x) { return x.v; }

// One contact of the model (docs/contacts.md, MODEL (M2)): the gap g = cᵀX − e ≥ 0, the modal
// projection T of a unit contact force, the restitution r, and W = cᵀT (the inverse effective mass).
struct ContactData {
  std::vector<std::string> shape_text, contact_text;
  std::string stop_text, restitution_text;
  std::vector<Interval> shape, contact;
  Interval stop, restitution, W;
};

// The model with its parameters as exact decimals (docs/prove.md: the theorem is about these
// numbers) and their enclosures.
struct IntervalModel {
  int n = 0;
  // Decimal texts, as in the certificate: ω_i, T_A,i, T_B,i, c_i, x0, r, f, ω.
  std::vector<std::string> omega_text, forcing_text, contact_text, shape_text;
  std::string stop_text, restitution_text, amplitude_text, frequency_text;
  std::vector<Interval> omega, forcing, contact, shape;
  Interval stop, restitution, amplitude, frequency;
  Interval s_A, s_B, period;  // cᵀT_A, cᵀT_B, T = 2π/ω
  // Modal damping ratios ζ_i (docs/model.md §7): empty texts for an undamped model, whose
  // enclosures are then computed exactly as before damping was covered.
  std::vector<std::string> damping_text;
  std::vector<Interval> damping;
  bool damped() const { return !damping.empty(); }
  // Damped modes: σ_i = ζ_iω_i, ω_d,i = ω_i√(1 − ζ_i²), and the forced response
  // U_i(t) = P_i sin ωt + Q_i cos ωt, P_i = T_A,i f (ω_i² − ω²)/Δ_i, Q_i = −T_A,i f 2σ_iω/Δ_i,
  // Δ_i = (ω_i² − ω²)² + (2σ_iω)²; empty when undamped.
  std::vector<Interval> sigma, omega_d, forced_sin, forced_cos;
  // Every contact: contacts[0] is the one of the fields above (shape, contact, stop, restitution,
  // s_B); a model of several contacts (two-sided clearances, stops on several DOFs, impact pairs)
  // has more, added by AddContact.
  std::vector<ContactData> contacts;
  int contact_count() const { return static_cast<int>(contacts.size()); }
  // Appends contact j = contact_count() (throws std::invalid_argument on a text that is not a decimal).
  void AddContact(std::vector<std::string> shape, std::vector<std::string> contact, std::string stop,
                  std::string restitution);

  // From decimal texts (throws std::invalid_argument on a text that is not a decimal).
  static IntervalModel FromDecimals(std::vector<std::string> omega, std::vector<std::string> forcing,
                                    std::vector<std::string> contact, std::vector<std::string> shape,
                                    std::string stop, std::string restitution, std::string amplitude,
                                    std::string frequency, std::vector<std::string> damping = {});
};

// The state after a free flight of duration s from (t0, X, Ẋ), its contact displacement and
// velocity, and the free acceleration of B.
template <class T>
struct FlightEnd {
  std::vector<T> X, V;
};

// The relative, cancellation-free form of docs/model.md §2: every term that depends on t0 is
// multiplied by an increment O(s²) or O(s³), so that an enclosure of t0 widens a short flight's end
// by O(s²) of its width only (chattering flights are short):
//   X_i(t0+s) = X_i cos ω_i s + Ẋ_i sin(ω_i s)/ω_i + T_A,i f K_i(s),
//   K_i(s) = [sin ωt0 (cos ωs − cos ω_i s) + cos ωt0 (sin ωs − (ω/ω_i) sin ω_i s)]/(ω_i² − ω²),
// with cos x − 1 = −2 sin²(x/2).
// With damping (docs/model.md §7), in the same relative form: per mode, with
//   h1 = e^{−σs}(cos ω_d s + (σ/ω_d) sin ω_d s), h2 = e^{−σs} sin(ω_d s)/ω_d (the free response
//   to a unit displacement and to a unit velocity),
//   X(t0+s) = X h1 + Ẋ h2 + sin ωt0 A(s) + cos ωt0 B(s),
//   A = P(cos ωs − h1) − Q(sin ωs − ω h2),  B = P(sin ωs − ω h2) + Q(cos ωs − h1),
// (the forced response U = P sin ωt + Q cos ωt minus its own free continuation), and the velocity
// from h1' = −ω_i² h2, h2' = h3 = e^{−σs}(cos ω_d s − (σ/ω_d) sin ω_d s). Undamped (σ = 0, Q = 0)
// this is the form below.
template <class T>
FlightEnd<T> DampedFlight(const IntervalModel& m, const T& t0, const std::vector<T>& X, const std::vector<T>& V,
                          const T& s) {
  FlightEnd<T> e;
  const T w(m.frequency), two(2.0), half(0.5);
  const T sin0 = Sin(w * t0), cos0 = Cos(w * t0);
  const T sw = Sin(w * s), hw = Sin(half * w * s), cw = T(1.0) - two * hw * hw;  // cos ωs
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const T w2(Sqr(m.omega[k])), sg(m.sigma[k]), wd(m.omega_d[k]), P(m.forced_sin[k]), Q(m.forced_cos[k]);
    const T decay = Exp(-(sg * s)), sd = Sin(wd * s), hd = Sin(half * wd * s), cd = T(1.0) - two * hd * hd;
    const T h1 = decay * (cd + sg / wd * sd), h2 = decay * sd / wd, h3 = decay * (cd - sg / wd * sd);
    const T dc = cw - h1, ds = sw - w * h2;            // cos ωs − h1, sin ωs − ω h2
    const T dcp = w2 * h2 - w * sw, dsp = w * (cw - h3);  // their derivatives in s
    const T A = P * dc - Q * ds, B = P * ds + Q * dc;
    const T Ap = P * dcp - Q * dsp, Bp = P * dsp + Q * dcp;
    e.X.push_back(X[k] * h1 + V[k] * h2 + sin0 * A + cos0 * B);
    e.V.push_back(V[k] * h3 - X[k] * w2 * h2 + sin0 * Ap + cos0 * Bp);
  }
  return e;
}

template <class T>
FlightEnd<T> Flight(const IntervalModel& m, const T& t0, const std::vector<T>& X, const std::vector<T>& V,
                    const T& s) {
  if (m.damped()) return DampedFlight(m, t0, X, V, s);
  FlightEnd<T> e;
  const T w(m.frequency), two(2.0), half(0.5);
  const T sin0 = Sin(w * t0), cos0 = Cos(w * t0);
  const T sw = Sin(w * s), hw = Sin(half * w * s), cw_m1 = -(two * hw * hw);  // cos ωs − 1
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const T wi(m.omega[k]);
    const T den(Sqr(m.omega[k]) - Sqr(m.frequency)), kappa(m.forcing[k] * m.amplitude);
    const T sn = Sin(wi * s), hi = Sin(half * wi * s), c_m1 = -(two * hi * hi);  // cos ω_i s − 1
    const T dcos = cw_m1 - c_m1;            // cos ωs − cos ω_i s
    const T dsin = sw - (w / wi) * sn;      // sin ωs − (ω/ω_i) sin ω_i s
    const T K = (sin0 * dcos + cos0 * dsin) / den;
    const T Kp = (sin0 * (wi * sn - w * sw) + w * cos0 * dcos) / den;  // dK/ds
    e.X.push_back(X[k] + X[k] * c_m1 + V[k] * sn / wi + kappa * K);
    e.V.push_back(V[k] + V[k] * c_m1 - X[k] * wi * sn + kappa * Kp);
  }
  return e;
}

// c_jᵀX: contact j's displacement (of velocities: its gap velocity).
template <class T>
T ContactSum(const IntervalModel& m, const std::vector<T>& X, int j = 0) {
  const auto& c = m.contacts[static_cast<std::size_t>(j)].shape;
  T sum(0.0);
  for (int i = 0; i < m.n; ++i) sum = sum + T(c[static_cast<std::size_t>(i)]) * X[static_cast<std::size_t>(i)];
  return sum;
}

// The restitution law at contact j, (10)-(12) and MODEL (I1): Ẋ⁺ = Ẋ⁻ − (1+r_j)(c_jᵀẊ⁻/W_jj) T_j.
template <class T>
std::vector<T> Impact(const IntervalModel& m, const std::vector<T>& V, int j = 0) {
  const auto& k = m.contacts[static_cast<std::size_t>(j)];
  const T p = T(-(1.0 + k.restitution) / k.W) * ContactSum(m, V, j);
  std::vector<T> out;
  for (int i = 0; i < m.n; ++i) out.push_back(V[static_cast<std::size_t>(i)] + p * T(k.contact[static_cast<std::size_t>(i)]));
  return out;
}

// The free acceleration of every mode, Ẍ_i = T_A,i f sin ωt − ω_i² X_i − 2σ_i Ẋ_i (σ = 0 undamped).
template <class T>
std::vector<T> Acceleration(const IntervalModel& m, const T& t, const std::vector<T>& X, const std::vector<T>& V) {
  const T load = T(m.amplitude) * Sin(T(m.frequency) * t);
  std::vector<T> a;
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    T ai = T(m.forcing[k]) * load - T(Sqr(m.omega[k])) * X[k];
    if (m.damped()) ai = ai - T(Interval(2.0) * m.sigma[k]) * V[k];
    a.push_back(ai);
  }
  return a;
}

// Free acceleration of contact j at time t (undamped): c_jᵀẌ = Σ c_j,i(−ω_i² X_i + T_A,i f sin ωt).
template <class T>
T ContactAcceleration(const IntervalModel& m, const T& t, const std::vector<T>& X, int j = 0) {
  const auto& c = m.contacts[static_cast<std::size_t>(j)].shape;
  Interval sA(0.0);
  if (j == 0) sA = m.s_A;
  else
    for (int i = 0; i < m.n; ++i) sA += c[static_cast<std::size_t>(i)] * m.forcing[static_cast<std::size_t>(i)];
  T sum = T(sA * m.amplitude) * Sin(T(m.frequency) * t);
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    sum = sum - T(c[k] * Sqr(m.omega[k])) * X[k];
  }
  return sum;
}

// An upper bound of |d^order/ds^order cᵀX(t0+s)| over all s for flights from the box (t0, X, Ẋ):
// Σ_k ν_k^order √(α_k² + β_k²) over the modes (ν = ω_i) and the forcing (ν = ω), docs/model.md §2.1.
// Of contact j's gap, c_jᵀX.
Interval DerivativeBound(const IntervalModel& m, const Interval& t0, const std::vector<Interval>& X,
                         const std::vector<Interval>& V, int order, int j = 0);

}  // namespace vibro::proof
