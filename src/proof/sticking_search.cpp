// The sticking orbit a proof starts from (sticking_search.hpp).
#include "proof/sticking_search.hpp"

namespace vibro::proof {

StickingSearch FollowStickingOrbit(const System& sys, const Scene& scene, const ProofRequest& request,
                                   const Budget& budget, Observer& recorder) {
  StickingSearch s;
  OrbitRequest req;
  req.kind = OrbitKind::kSticking;
  req.period = request.period;
  req.transient_periods = request.start ? 0 : request.transient_periods;
  req.start = request.start;
  budget.Watch([&] {
    s.orbit = SolveOrbit(sys, scene, req);
    if (s.orbit.status != "converged" || s.orbit.summary.kind != "sticking-periodic" || budget.passed()) return;
    Scene two = scene;
    two.run.periods = 2 * s.orbit.period + 1;
    two.run.samples_per_period = 0;
    two.run.lyapunov = false;
    const InitialOverride start{s.orbit.section_time, s.orbit.X, s.orbit.V};
    SimulationOptions opt;
    opt.observers = {&recorder};
    opt.initial = &start;
    s.run = Simulate(sys, two, opt);
  });
  if (budget.passed()) {
    s.stopped = true;
  } else if (s.orbit.status != "converged") {
    s.failure = "the Poincaré solver found no orbit to prove (" + s.orbit.status +
                (s.orbit.message.empty() ? "" : ": " + s.orbit.message) + ")";
  } else if (s.orbit.summary.kind != "sticking-periodic") {
    s.failure = "the orbit found does not stick (try --kind impact)";
  } else if (s.run.status != RunStatus::kOk) {
    s.failure = "the orbit found could not be followed over its period: " + s.run.message;
  }
  return s;
}

}  // namespace vibro::proof
