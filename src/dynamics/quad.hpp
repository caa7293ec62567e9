// The quad scalar: Boost.Multiprecision float128 (GCC's __float128, 113-bit significand,
// libquadmath). Chosen over MPFR/mpreal because it is a fixed-size value type with hardware-like
// semantics (no allocation, 10-50x the cost of double rather than 100-1000x), and 113 bits are
// what the reference needs: 34 significant digits, chattering speeds followed to 1e-30.
// Only the translation units that instantiate the quad engine include this header.
#pragma once

#include <boost/multiprecision/eigen.hpp>
#include <boost/multiprecision/float128.hpp>

#include "dynamics/scalar.hpp"

namespace vibro::detail {

using Quad = boost::multiprecision::float128;

template <>
struct Real<Quad> {
  static __float128 q(const Quad& x) { return x.backend().value(); }
  static Quad sin(const Quad& x) { return Quad(sinq(q(x))); }
  static Quad cos(const Quad& x) { return Quad(cosq(q(x))); }
  static void sincos(const Quad& x, Quad& s, Quad& c) {
    __float128 sv, cv;
    sincosq(q(x), &sv, &cv);
    s = Quad(sv);
    c = Quad(cv);
  }
  static Quad sqrt(const Quad& x) { return Quad(sqrtq(q(x))); }
  static Quad exp(const Quad& x) { return Quad(expq(q(x))); }
  static Quad expm1(const Quad& x) { return Quad(expm1q(q(x))); }
  static Quad hypot(const Quad& x, const Quad& y) { return Quad(hypotq(q(x), q(y))); }
  static Quad atan2(const Quad& y, const Quad& x) { return Quad(atan2q(q(y), q(x))); }
  static Quad floor(const Quad& x) { return Quad(floorq(q(x))); }
  static Quad fmod(const Quad& x, const Quad& y) { return Quad(fmodq(q(x), q(y))); }
  static Quad abs(const Quad& x) { return Quad(fabsq(q(x))); }
  static Quad copysign(const Quad& x, const Quad& y) { return Quad(copysignq(q(x), q(y))); }
  static bool isfinite(const Quad& x) { return finiteq(q(x)) != 0; }
  static Quad pi() { return Quad(M_PIq); }
  static double to_double(const Quad& x) { return static_cast<double>(q(x)); }
};

}  // namespace vibro::detail
