// The start of a free flight (MODEL §2.1): derivatives of the gap g = x_B − x0 at σ = 0, rigorous
// bounds of its third and fourth derivatives, and the certified window (0, σ_w) free of roots once
// the known zero at σ = 0 is divided out. Shared by both engines.
#pragma once

#include <Eigen/Dense>

#include "dynamics/propagator.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

struct FlightJet {
  double g1, g2, g3;  // g', g'', g''' at σ = 0 (g(0) = 0 on the stop)
  double M3, M4;      // bounds of |g'''|, |g''''| over [0, H]
};

FlightJet StartJet(const System& system, const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                   double phase, double H);

// σ_w ≤ H with no root of g in (0, σ_w): after an impact g(σ)/σ ≥ g' + g''σ/2 − M3σ²/6; after a
// departure g(σ)/σ² ≥ g''/2 − M3σ/6; after a release g(σ)/σ³ ≥ g'''/6 − M4σ/24. 0 for a generic
// start or when the leading derivative is not positive.
double CertifiedWindow(FlightStart start, const FlightJet& jet, double H);

// Largest step of the certified searches: a quarter of the fastest period in the model.
double StepCap(const System& system);

}  // namespace vibro::detail
