// A univariate second-order Taylor jet (value, first and second derivative in one variable), each an
// enclosure: forward differentiation to second order, for the Taylor form of the shooting residual
// in the forcing frequency over a segment of a branch (impact_proof.cpp; docs/prove.md "Along a
// branch"). Evaluated over an interval of the variable, d2 encloses the second derivative there.
#pragma once

#include "proof/interval.hpp"

namespace vibro::proof {

struct Jet2 {
  Interval v, d1, d2;
  Jet2() = default;
  Jet2(const Interval& value) : v(value), d1(0.0), d2(0.0) {}  // NOLINT: a constant
  Jet2(double value) : v(value), d1(0.0), d2(0.0) {}           // NOLINT: a constant
  Jet2(const Interval& value, const Interval& first, const Interval& second) : v(value), d1(first), d2(second) {}
  static Jet2 Variable(const Interval& value) { return {value, Interval(1.0), Interval(0.0)}; }
};

inline Jet2 operator+(const Jet2& a, const Jet2& b) { return {a.v + b.v, a.d1 + b.d1, a.d2 + b.d2}; }
inline Jet2 operator-(const Jet2& a, const Jet2& b) { return {a.v - b.v, a.d1 - b.d1, a.d2 - b.d2}; }
inline Jet2 operator-(const Jet2& a) { return {-a.v, -a.d1, -a.d2}; }
// (ab)'' = a''b + 2a'b' + ab''.
inline Jet2 operator*(const Jet2& a, const Jet2& b) {
  return {a.v * b.v, a.d1 * b.v + a.v * b.d1, a.d2 * b.v + Interval(2.0) * a.d1 * b.d1 + a.v * b.d2};
}
// (1/b)' = −b'/b², (1/b)'' = −b''/b² + 2b'²/b³.
inline Jet2 operator/(const Jet2& a, const Jet2& b) {
  const Interval inv = Interval(1.0) / b.v, inv2 = inv * inv;
  const Jet2 r{inv, -(b.d1 * inv2), Interval(2.0) * Sqr(b.d1) * inv2 * inv - b.d2 * inv2};
  return a * r;
}
// (f∘x)'' = f''(x) x'² + f'(x) x''.
inline Jet2 Sin(const Jet2& x) {
  const Interval s = Sin(x.v), c = Cos(x.v);
  return {s, c * x.d1, c * x.d2 - s * Sqr(x.d1)};
}
inline Jet2 Cos(const Jet2& x) {
  const Interval s = Sin(x.v), c = Cos(x.v);
  return {c, -(s * x.d1), -(s * x.d2) - c * Sqr(x.d1)};
}
inline Jet2 Exp(const Jet2& x) {
  const Interval e = Exp(x.v);
  return {e, e * x.d1, e * (x.d2 + Sqr(x.d1))};
}

}  // namespace vibro::proof
