// `vibro check`: the exact engine, the CVODE engine and the Poincaré solver on the same scene,
// and a table of their agreement (the way a user comes to trust a result); optionally the
// quad-precision exact engine as a fourth opinion, the reference for the others.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "vibro/poincare.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro {

struct CheckRow {
  std::string quantity;
  std::optional<double> exact, cvode, orbit;  // value per method (absent: not applicable)
  double difference = 0;                      // largest |method − exact|
  double tolerance = 0;
  bool ok = true;
  std::string note;
  std::optional<double> quad;  // the quad-precision exact engine (with_quad)
};

struct CheckReport {
  std::vector<CheckRow> rows;
  bool ok = true;
  std::string exact_kind, cvode_kind, orbit_status, quad_kind;  // quad_kind empty: not run
};

// The events of one kind of a periodic orbit as a cyclic list (a periodic orbit has no first
// event): each event's contact and two values (an impact: its phase and the contact velocity
// before it; a sticking phase: its start and end phases).
struct CyclicEvent {
  int contact;
  double a, b;
};

// The list in the canonical rotation of its contact word (contact_sequence.hpp,
// CanonicalRotation); of the rotations that give it (a word u^m), the one whose first event has
// the least phase `a` modulo 2π.
std::vector<CyclicEvent> CanonicalCyclic(const std::vector<CyclicEvent>& events);

// Another record of the same cyclic list rotated to match `ref` event by event: of the rotations
// whose contacts are those of `ref` in order, the one with the least largest difference (phases
// `a`, and `b` when b_is_phase, modulo 2π: each record counts phases from the forcing period it
// starts in). Unrotated when the lengths differ or no rotation has the contacts of `ref` in
// order (a different orbit: the comparison then shows the disagreement).
std::vector<CyclicEvent> AlignedCyclic(const std::vector<CyclicEvent>& ref, const std::vector<CyclicEvent>& other,
                                       bool b_is_phase);

// Impacts and sticking phases are compared as cyclic lists, contact by contact: the exact run's
// in CanonicalCyclic order, every other record AlignedCyclic to it.
// Tolerances: CVODE against exact, 100·rtol^(2/3) (the law of docs/engines.md, "What each rtol buys");
// Poincaré solver against exact, 1e-9; the leading multiplier against the decay rate observed in
// the exact transient, 10 % (+ 0.02); the exact engine against the quad engine (with_quad),
// 1e-9 (the double engine's claimed accuracy on periodic quantities, docs/chattering.md).
// A scene with a compliant stop (docs/compliant.md): the exact engine's closed forms against CVODE's
// integration of the same law; no Poincaré solver (it does not take a contact phase yet: "not
// attempted"); the first contact phase (entry and exit instants in periods, duration, peak force,
// largest penetration, impulse, exit velocity) and, on a periodic attractor, each contact phase of
// its last period, as relative differences within the CVODE tolerance. with_quad is refused
// before (the quad engine has no contact phase yet).
CheckReport CrossCheck(const System& system, const Scene& scene, bool with_quad = false);

}  // namespace vibro
