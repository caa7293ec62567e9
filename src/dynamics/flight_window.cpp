#include "dynamics/flight_window.hpp"

#include <algorithm>
#include <cmath>

#include "dynamics/oscillator.hpp"

namespace vibro::detail {

FlightJet StartJet(const System& sys, const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                   double phase, double H) {
  const double w = sys.frequency(), f = sys.amplitude();
  const double sp = std::sin(phase), cp = std::cos(phase);
  FlightJet j{0, 0, 0, 0, 0};
  for (int i = 0; i < sys.dof(); ++i) {
    if (sys.contact_shape()[i] == 0.0) continue;
    const Oscillator o{sys.omega()[i], sys.damping()[i], sys.forcing()[i] * f};
    const double tz = 2.0 * o.zeta * o.nu;
    const double acc = -o.nu * o.nu * X[i] - tz * V[i] + o.F * sp;
    j.g1 += V[i];
    j.g2 += acc;
    j.g3 += -o.nu * o.nu * V[i] - tz * acc + o.F * w * cp;
    const auto b = Bounds(o, w, Amplitude(o, X[i], V[i]) + std::abs(o.F) * H);
    j.M3 += b.d3;
    j.M4 += b.d4;
  }
  constexpr double kMargin = 1.0 + 1e-9;  // rounding of the evaluated jets
  j.M3 *= kMargin;
  j.M4 *= kMargin;
  return j;
}

double CertifiedWindow(FlightStart start, const FlightJet& j, double H) {
  switch (start) {
    case FlightStart::kGeneric:
      return 0.0;
    case FlightStart::kAfterImpact: {
      const double v = j.g1, a = j.g2, M = j.M3;
      if (!(v > 0)) return 0.0;
      const double w = M > 0 ? (0.5 * a + std::sqrt(0.25 * a * a + 2.0 * M * v / 3.0)) / (M / 3.0)
                             : (a < 0 ? 2.0 * v / -a : H);
      return std::min(w, H);
    }
    case FlightStart::kDeparture:
      if (!(j.g2 > 0)) return 0.0;
      return j.M3 > 0 ? std::min(3.0 * j.g2 / j.M3, H) : H;
    case FlightStart::kAfterRelease:
      if (!(j.g3 > 0)) return 0.0;
      return j.M4 > 0 ? std::min(4.0 * j.g3 / j.M4, H) : H;
  }
  return 0.0;
}

double StepCap(const System& sys) {
  double fastest = sys.frequency();
  for (int i = 0; i < sys.dof(); ++i) fastest = std::max(fastest, sys.omega()[i]);
  for (Eigen::Index k = 0; k < sys.constrained().frequencies.size(); ++k)
    fastest = std::max(fastest, sys.constrained().frequencies[k]);
  return 0.25 * 2.0 * M_PI / fastest;
}

}  // namespace vibro::detail
