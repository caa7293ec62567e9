// The scalar of the exact engine and the automaton: `double` (the default) or a 113-bit quad
// (run.precision = "quad", dynamics/quad.hpp). Templated code calls its elementary functions
// through Real<S> so that the quad specialisation can map them onto libquadmath.
#pragma once

#include <cmath>
#include <limits>

namespace vibro::detail {

template <class S>
struct Real;

template <>
struct Real<double> {
  static double sin(double x) { return std::sin(x); }
  static double cos(double x) { return std::cos(x); }
  static void sincos(double x, double& s, double& c) { ::sincos(x, &s, &c); }
  static double sqrt(double x) { return std::sqrt(x); }
  static double exp(double x) { return std::exp(x); }
  static double expm1(double x) { return std::expm1(x); }
  static double hypot(double x, double y) { return std::hypot(x, y); }
  static double atan2(double y, double x) { return std::atan2(y, x); }
  static double floor(double x) { return std::floor(x); }
  static double fmod(double x, double y) { return std::fmod(x, y); }
  static double abs(double x) { return std::abs(x); }
  static double copysign(double x, double y) { return std::copysign(x, y); }
  static bool isfinite(double x) { return std::isfinite(x); }
  static double pi() { return M_PI; }
  static double to_double(double x) { return x; }
};

// Relative rounding unit of S.
template <class S>
S Eps() {
  return std::numeric_limits<S>::epsilon();
}

}  // namespace vibro::detail
