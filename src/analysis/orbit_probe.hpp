// What continuation watches on a periodic orbit between two branch points (docs/model.md §5.7): the
// sequence of events over one period (its "signature": a change means a non-smooth bifurcation
// was crossed) and the quantities that vanish at each kind of non-smooth bifurcation:
//
//   sticking-lost   the shortest sticking phase                       (→ 0, docs/model.md §6.3)
//   rising          the interior minima of R inside a sticking phase  (→ 0, docs/model.md §5.7), or,
//                   seen from the other side, the time from a release to the next stick
//   sticking-entry  R at the start of a sticking phase                (→ 0, e.g. f_sticking)
//   grazing         interior minima of the gap x_B − x0 in a free flight, and the speed of an
//                   impact that is not part of a chattering tail     (→ 0)
//
// each made dimensionless by the orbit's own scale (R, x_B and ẋ_B ranges). The probe also finds
// where a section can sit (the middle of the longest free flight) so continuation can move its
// section when an event comes near it.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro {

struct OrbitProbe {
  bool ok = false;  // the simulation ran through the q periods
  // Event tokens over one period from the section, rotated to a canonical start:
  // C chattering sequence ending on the stop (impacts + accumulation + stick), P plastic impact
  // into sticking, I isolated impact, G grazing touch, S other start of sticking, R release.
  std::string signature;
  // The signature with every isolated impact that leads into a chattering sequence counted in the
  // sequence (each "IC" read as "C", cyclically). Where a sequence's tail starts (its first impact
  // of a run of decreasing speeds) is bookkeeping: an impact appears or vanishes only at a grazing,
  // whose test quantity vanishes. Two signatures with the same coarse signature are one sequence
  // of events, grouped differently.
  std::string coarse_signature;
  int sticking_phases = 0;
  static constexpr double kNone = std::numeric_limits<double>::infinity();
  double shortest_stick = kNone;      // duration / (qT)
  double interior_reaction = kNone;   // min interior local minimum of R / max R
  double entry_reaction = kNone;      // min R at the start of a sticking phase / max R
  double flight_gap = kNone;          // min interior local minimum of x_B − x0 / range of x_B
  double release_to_stick = kNone;    // shortest time from a release to the next stick / (qT)
  double impact_speed = kNone;        // min |ẋ_B⁻| of isolated impacts / max |ẋ_B|
  // The section: distance from t0 to the nearest event over the length of the free flight it
  // lies in (0 when it is not in a free flight), and a better section: a dense sample near the
  // middle of the longest free flight (offset from t0, state).
  double section_margin = 0;
  double best_offset = 0;
  Eigen::VectorXd best_X, best_V;
};

// Simulates q periods of the orbit from the free state (X, V) at t0 with `samples` dense samples
// per period.
OrbitProbe ProbeOrbit(const System& system, const Scene& scene, double t0, const Eigen::VectorXd& X,
                      const Eigen::VectorXd& V, int q, int samples = 512);

}  // namespace vibro
