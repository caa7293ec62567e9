// Checking orbits computed elsewhere, point by point (docs/validation.md): each claimed point (a
// parameter value, a state on the orbit and optional claims of period, stability and sticking
// fraction) is confirmed or refuted by Newton from that state (orbit_from_state.hpp) and, for a
// stable orbit, by simulating from it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "vibro/poincare.hpp"
#include "vibro/scene.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace vibro {

// One row of a branch from another tool, in the scene's [initial] convention (physical DOFs for
// the physical form, the listed modes for the modal form).
struct ClaimedPoint {
  double value = 0;                           // the parameter
  double time = 0;                            // t of the state
  Eigen::VectorXd displacement, velocity;     // (n listed)
  std::optional<int> period;                  // forcing periods
  std::optional<bool> stable;
  std::optional<double> sticking_fraction;
  int line = 0;                               // where it came from (messages)
  // Several contacts: the claimed contact sequence over the orbit (OrbitResult::sequence's
  // format, read by ParseContactSequence); empty: no claim.
  std::string sequence;
};

struct CheckTolerances {
  double distance = 1e-6;           // |z_claimed − z_orbit|∞ / (1 + |z_orbit|∞), at one time
  double sticking_fraction = 1e-6;  // absolute
  int simulate_periods = 50;        // periods of orbit simulated from a stable point
};

struct PointCheck {
  double value = 0;
  // "confirmed" | "no-orbit-near" | "undetermined" | "period-differs" | "sequence-differs" |
  // "stability-differs" | "sticking-fraction-differs". "undetermined": the simulation that checks a stable orbit ended
  // undetermined or in a numerical failure (detail: its message), so nothing is claimed.
  std::string verdict;
  std::string detail;
  OrbitResult orbit;                       // vibro's orbit (status, period, multipliers, summary)
  // |z_claimed(t) − z_orbit(t)|∞ / (1 + |z_orbit(t)|∞) at the claim's own time t (and never less
  // than orbit.distance_from_start): the distance of the state as given, not of where the motion
  // from it goes.
  std::optional<double> distance;
  std::optional<double> simulated_distance;  // stable orbits: distance after simulate_periods·q
};

// The modal start state of a claimed point in `scene` (the scene at the point's value). A state
// below the stop by at most 1e-9·max(1, |x0|) (another tool's rounding) is put on the stop, and a
// state on the stop moving into it is taken as the one just before an impact: the restitution law
// is applied. Several contacts: the same for each contact j (its gap g_j, |e_j| for |x0|, its own
// restitution law); a state on two coupled contacts (W_jk ≠ 0) moving into both is refused (its
// simultaneous impact is not one contact's law: give the state after it). Returns an empty `problem` or why the state is not admissible, or not a state of the
// scene at all (an entry beyond the bound of [initial], |value| ≤ 1e100, or |time|/T > 1e12).
InitialOverride ClaimedStart(const System& system, const Scene& scene, const ClaimedPoint& point,
                             std::string& problem);

// The verdict on one claimed point (precondition: ClaimedStart found no problem). `kind` is the
// kind asked for (kAuto: any), `period` > 0 the period when the row claims none.
PointCheck CheckPoint(const Scene& scene, const ClaimedPoint& point, OrbitKind kind, int period,
                      const CheckTolerances& tolerances);

}  // namespace vibro
