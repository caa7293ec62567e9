// Checking orbits computed elsewhere (see include/vibro/branch_check.hpp).
#include "vibro/branch_check.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "vibro/orbit_from_state.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace vibro {

InitialOverride ClaimedStart(const System& sys, const Scene& scene, const ClaimedPoint& p,
                             std::string& problem) {
  problem.clear();
  Scene at = scene;
  at.initial_time = p.time;
  at.initial_displacement = p.displacement;
  at.initial_velocity = p.velocity;
  const auto init = sys.Initial(at);
  InitialOverride start{init.time, init.X, init.V};

  // Admissibility, with the rounding of another tool's output forgiven.
  const double x0 = sys.stop(), gap = sys.ContactDisplacement(start.X) - x0;
  const double snap = 1e-9 * std::max(1.0, std::abs(x0));
  if (gap < -snap) {
    problem = fmt::format("the state is below the stop (x_B − x0 = {:.3g} < 0): not an admissible state "
                          "of the scene", gap);
  } else if (gap <= snap) {
    start.X += sys.contact() * (-gap / sys.s_B());  // onto the stop: x_B = x0
    if (sys.ContactVelocity(start.V) < 0) sys.ApplyImpact(start.V, sys.restitution());
  }
  return start;
}

PointCheck CheckPoint(const Scene& scene, const ClaimedPoint& p, OrbitKind kind, int period,
                      const CheckTolerances& tol) {
  PointCheck out;
  out.value = p.value;
  const System sys(scene);
  std::string problem;
  const InitialOverride start = ClaimedStart(sys, scene, p, problem);

  OrbitRequest req;
  req.kind = kind;
  req.period = p.period.value_or(period);
  req.transient_periods = 0;
  out.orbit = OrbitFromState(sys, scene, start, req, tol.distance);
  const OrbitResult& o = out.orbit;
  out.distance = o.distance_from_start;
  if (o.status != "converged") {
    out.verdict = "no-orbit-near";
    out.detail = o.message;
    return out;
  }
  if (*o.distance_from_start > tol.distance) {
    out.verdict = "no-orbit-near";
    out.detail = fmt::format("the nearest orbit Newton finds lies {:.3g} away (tolerance {:g})",
                             *o.distance_from_start, tol.distance);
    return out;
  }
  // A stable orbit is also confirmed by simulating from the orbit's section state (the claimed
  // state is within tolerance of it): the motion must stay on the orbit.
  if (o.stable) {
    Scene sc = scene;
    sc.initial_time = o.section_time;
    sc.run.periods = static_cast<long long>(tol.simulate_periods) * o.period;
    sc.run.samples_per_period = 0;
    const InitialOverride here{o.section_time, o.X, o.V};
    SimulationOptions opt;
    opt.initial = &here;
    const RunResult r = Simulate(sys, sc, opt);
    Eigen::VectorXd a(2 * o.X.size()), b(2 * o.X.size());
    a << r.X, r.V;
    b << o.X, o.V;
    out.simulated_distance = (a - b).cwiseAbs().maxCoeff() / (1.0 + b.cwiseAbs().maxCoeff());
    if (r.status != RunStatus::kOk || *out.simulated_distance > tol.distance) {
      out.verdict = "stability-differs";
      out.detail = fmt::format("Floquet multipliers say stable, but a simulation of {} periods from the "
                               "orbit ends {:.3g} away from it",
                               sc.run.periods, *out.simulated_distance);
      return out;
    }
  }
  const int vibro_period = o.summary.period.value_or(o.period);
  if (p.period && *p.period != vibro_period) {
    out.verdict = "period-differs";
    out.detail = fmt::format("claimed period {}, vibro's orbit has period {}", *p.period, vibro_period);
  } else if (p.stable && *p.stable != o.stable) {
    double lead = 0;
    for (const auto& m : o.multipliers) lead = std::max(lead, std::abs(m));
    out.verdict = "stability-differs";
    out.detail = fmt::format("claimed {}, vibro finds {} (largest |multiplier| {:.6g})",
                             *p.stable ? "stable" : "unstable", o.stable ? "stable" : "unstable", lead);
  } else if (p.sticking_fraction &&
             std::abs(*p.sticking_fraction - o.summary.sticking_fraction.value_or(0.0)) > tol.sticking_fraction) {
    out.verdict = "sticking-fraction-differs";
    out.detail = fmt::format("claimed {:.10g}, vibro finds {:.10g}", *p.sticking_fraction,
                             o.summary.sticking_fraction.value_or(0.0));
  } else {
    out.verdict = "confirmed";
  }
  return out;
}

}  // namespace vibro
