// Periodic orbits from a given state (docs/validation.md): Newton on the stroboscopic map of
// poincare.hpp started at a state the user brings (another tool's orbit, a branch point, the
// scene's [initial] table) instead of the end of a long transient.
//
// The start may sit exactly on an event: just after an impact (x_B = x0, ẋ_B > 0, the state after
// the restitution law), at a release (x_B = x0, ẋ_B = 0, R = 0), inside a sticking phase, or at any
// forcing phase. The simulator classifies it as it classifies any initial state, and the Newton
// section is then moved, along the start's own trajectory, to the middle of the longest free flight
// of the first period(s): t1 = t_start + j·T/1024. Newton's unknown is the free state at t1, so an
// impact of the orbit never falls on the section's period boundary.
//
// distance_from_start = |φ(t1; z_start) − z*(t1)|∞ / (1 + |z*(t1)|∞), with φ the hybrid flow from the
// start and z* the converged orbit: both at the same time t1, so a start ε away from the orbit is
// reported O(ε) away (the flow over less than q periods is Lipschitz away from grazing).
#pragma once

#include "vibro/poincare.hpp"
#include "vibro/scene.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace vibro {

// Newton from `start` (modal state, admissible: x_B ≥ x0, and ẋ_B ≥ 0 on the stop) with the
// request's kind, period and tolerance (transient_periods, guess_* and start are ignored).
// request.period = 0: the smallest q ≤ run.max_period whose return F^q(start) comes back within
// 10× the closest return (and within 1e-6 when some return does), 1 when none does.
// The result's message says so when the orbit lies farther than `far` from the start.
OrbitResult OrbitFromState(const System& system, const Scene& scene, const InitialOverride& start,
                           const OrbitRequest& request, double far = 1e-6);

// The search behind `vibro orbit` and the first point of `vibro continue`:
// - transient_periods = 0: OrbitFromState from request.start, or the scene's initial state;
// - otherwise FindOrbit (poincare.hpp) after that transient, with kAuto resolved to the kind of
//   the attractor the transient reaches (sticking, then impact, when it is not periodic), and
//   distance_from_start measured in the start's stroboscopic section (between the start and the
//   nearest of the last q section points of the transient, which lie on the attractor).
// Messages never name command-line options (the CLI adds the hints that apply to its command).
OrbitResult SolveOrbit(const System& system, const Scene& scene, const OrbitRequest& request);

}  // namespace vibro
