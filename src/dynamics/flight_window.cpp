#include "dynamics/flight_window.hpp"

namespace vibro::detail {

FlightJet StartJet(const System& sys, const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                   double phase, double H) {
  return StartJet<double>(ModelT<double>(sys), X, V, phase, H);
}

double StepCap(const System& sys) { return StepCap<double>(ModelT<double>(sys)); }

}  // namespace vibro::detail
