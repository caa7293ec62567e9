// What continuation watches on a periodic orbit between two branch points (docs/model.md §5.7,
// docs/contacts.md for several contacts): the sequence of events over one period (its
// "signature": a change means a non-smooth bifurcation was crossed) and the quantities that
// vanish at each kind of non-smooth bifurcation, on every contact:
//
//   sticking-lost   the shortest sticking phase                       (→ 0, docs/model.md §6.3)
//   rising          the interior minima of R inside a sticking phase  (→ 0, docs/model.md §5.7), or,
//                   seen from the other side, the time from a release to the next stick; with
//                   several contacts also the interior minima of another contact's gap while one
//                   sticks (a new contact closes during sticking)
//   sticking-entry  R at the start of a sticking phase                (→ 0, e.g. f_sticking)
//   grazing         interior minima of the gap in a free flight, and the speed of an impact that
//                   is not part of a chattering tail                  (→ 0)
//   simultaneous    the time between two consecutive events on different contacts (→ 0): two
//                   impacts, or an impact on one at the moment another releases
//
// each made dimensionless by the orbit's own scale (R, gap and gap-velocity ranges of the contact,
// the period). Each quantity keeps the contact where it is smallest. The probe also finds where a
// section can sit (the middle of the longest free flight) so continuation can move its section
// when an event comes near it.
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
  // Several contacts: each token is followed by its contact's index ("I0I1C0R0").
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
  double entry_reaction_raw = kNone;  // the same R, not scaled (smooth along a branch: a root to fit)
  double flight_gap = kNone;          // min interior local minimum of x_B − x0 / range of x_B
  double release_to_stick = kNone;    // shortest time from a release to the next stick / (qT)
  double impact_speed = kNone;        // min |ẋ_B⁻| of isolated impacts / max |ẋ_B|
  // Several contacts: the interior minima of a gap while another contact sticks / its range, and
  // the shortest time between consecutive events on two different contacts / (qT).
  double closing_gap = kNone;
  double simultaneous = kNone;
  // The contact where each quantity above is smallest (for simultaneous and closing_gap: the
  // later / the closing contact), and for closing_gap the contact that sticks meanwhile.
  struct Where {
    int shortest_stick = 0, interior_reaction = 0, entry_reaction = 0, flight_gap = 0,
        release_to_stick = 0, impact_speed = 0, closing_gap = 0, closing_held = 0,
        simultaneous = 0, simultaneous_other = 0;
    int simultaneous_kind = 1, simultaneous_other_kind = 1;  // their EventKinds (1: impact)
  } at;
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
