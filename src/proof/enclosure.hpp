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
inline const Interval& Value(const Interval& x) { return x; }
inline const Interval& Value(const Dual& x) { return x.v; }

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

  // From decimal texts (throws std::invalid_argument on a text that is not a decimal).
  static IntervalModel FromDecimals(std::vector<std::string> omega, std::vector<std::string> forcing,
                                    std::vector<std::string> contact, std::vector<std::string> shape,
                                    std::string stop, std::string restitution, std::string amplitude,
                                    std::string frequency);
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
template <class T>
FlightEnd<T> Flight(const IntervalModel& m, const T& t0, const std::vector<T>& X, const std::vector<T>& V,
                    const T& s) {
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

template <class T>
T ContactSum(const IntervalModel& m, const std::vector<T>& X) {
  T sum(0.0);
  for (int i = 0; i < m.n; ++i) sum = sum + T(m.shape[static_cast<std::size_t>(i)]) * X[static_cast<std::size_t>(i)];
  return sum;
}

// The restitution law (10)-(12): Ẋ⁺ = Ẋ⁻ − (1+r)(cᵀẊ⁻/s_B) T_B.
template <class T>
std::vector<T> Impact(const IntervalModel& m, const std::vector<T>& V) {
  const T p = T(-(1.0 + m.restitution) / m.s_B) * ContactSum(m, V);
  std::vector<T> out;
  for (int i = 0; i < m.n; ++i) out.push_back(V[static_cast<std::size_t>(i)] + p * T(m.contact[static_cast<std::size_t>(i)]));
  return out;
}

// Free acceleration of B at time t: cᵀẌ = Σ c_i(−ω_i² X_i + T_A,i f sin ωt).
template <class T>
T ContactAcceleration(const IntervalModel& m, const T& t, const std::vector<T>& X) {
  T sum = T(m.s_A * m.amplitude) * Sin(T(m.frequency) * t);
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    sum = sum - T(m.shape[k] * Sqr(m.omega[k])) * X[k];
  }
  return sum;
}

// An upper bound of |d^order/ds^order cᵀX(t0+s)| over all s for flights from the box (t0, X, Ẋ):
// Σ_k ν_k^order √(α_k² + β_k²) over the modes (ν = ω_i) and the forcing (ν = ω), docs/model.md §2.1.
Interval DerivativeBound(const IntervalModel& m, const Interval& t0, const std::vector<Interval>& X,
                         const std::vector<Interval>& V, int order);

}  // namespace vibro::proof
