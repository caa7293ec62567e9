// Computer-assisted proofs of periodic orbits (docs/prove.md): `vibro prove`.
//
// For an impacting orbit (no sticking) the prover takes the orbit that the Poincaré solver finds
// (poincare.hpp, orbit_from_state.hpp), builds a box around its impacts (time, modal displacement
// and velocity after each impact) and proves with Krawczyk's test, in interval arithmetic on the
// closed forms, that the box holds exactly one zero of the multiple-shooting map whose zeros are the
// orbits with that impact sequence. It then proves that no other contact happens between the impacts
// (the gap is positive on every flight, with windows at both ends), encloses the monodromy
// matrix and the Floquet multipliers, and says "stable" or "unstable" only when the enclosures are
// separated from the unit circle.
//
// For a one-DOF sticking orbit with plastic impacts (r = 0) the release phase is a certified root
// of the reaction, the landing a certified root of the gap (interval Newton), and the reaction is
// proven positive over the whole sticking phase.
//
// The result is a verdict, a reason, a summary (JSON) and a certificate (JSON) that
// scripts/vibro_check_proof.py re-verifies with no code in common with the prover.
#pragma once

#include <atomic>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vibro/poincare.hpp"
#include "vibro/scene.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace vibro {

struct ProofRequest {
  OrbitKind kind = OrbitKind::kAuto;  // kAuto: the kind of the orbit found
  int period = 0;                     // forcing periods q; 0: the orbit's own
  int transient_periods = 200;        // before the Poincaré solver, as `vibro orbit --transient`
  std::optional<InitialOverride> start;  // a state on (or near) the orbit to start from instead
  // Half-width of the box around each unknown, relative to 1 + |value| (impacting orbits); the
  // prover widens it at most 3 times ×4 (boxes stay ≤ 1e-10 wide at the default).
  double box_radius = 1e-12;
  int max_depth = 40;         // bisections of a flight before a positivity test fails
  // Seconds for the whole call: the transient, the orbit search and the proof; past it the result
  // is "not proven" with that reason.
  double time_limit = 60.0;
  // A stop request (besides the process's, vibro/stop_request.hpp): the call ends within a second
  // with `interrupted` and no verdict. nullptr: none.
  const std::atomic<bool>* stop_requested = nullptr;
};

// A closed interval [lo, hi] with outward-rounded ends.
struct Enclosure {
  double lo = 0, hi = 0;
};

struct ProvenEvent {
  std::string kind;          // "impact", "release", "departure", "accumulation", "stick"
  Enclosure phase;           // ωt mod 2π
  Enclosure velocity_before; // ẋ_B just before
  int contact = 0;           // the contact it happens at (0: the model has one)
};

struct ProofResult {
  bool proven = false;
  // A stop request ended the call: no verdict, nothing proven, no certificate (summary_json says
  // "not-proven" with reason "interrupted"); callers report an interruption (exit 130).
  bool interrupted = false;
  std::string reason;            // not proven: which inequality failed, where; proven: what holds
  std::string kind;              // "impact" or "sticking" ("" when no proof was attempted)
  int period = 0;                // forcing periods (0 when unknown): the orbit's least period
  // --period Q of an orbit whose least period `period` divides Q: Q (the orbit is proven, and is
  // also the period-Q orbit); 0 otherwise.
  int requested_period = 0;
  std::vector<ProvenEvent> events;                      // one period, in time order
  std::vector<std::pair<Enclosure, Enclosure>> multipliers;  // (re, im) of each Floquet multiplier
  std::string stability = "undecided";  // "stable" | "unstable" | "undecided"
  // "enclosed": a physical scene's modal data, enclosed from its mass and stiffness matrices (the
  // theorem is about the scene as written, docs/prove.md); "given": the modal form's numbers.
  std::string modal_data = "given";
  double box_width = 0;          // widest side of the box, and of every enclosure of a time or the section
  std::string summary_json;      // the `vibro prove --json` object (docs/prove.md)
  std::string certificate_json;  // the certificate (docs/prove.md), empty when nothing was attempted
};

// Throws std::invalid_argument for a request the prover cannot take (bad input).
// Bounded in time (request.time_limit) and memory (docs/prove.md "Bounds") for every request.
ProofResult ProveOrbit(const System& system, const Scene& scene, const ProofRequest& request);

// Validated continuation of an impacting orbit (docs/prove.md "Along a branch"): for EVERY value of
// one scalar parameter between two scenes that differ in it alone (the amplitude, the forcing
// frequency, the stop position or the restitution), exactly one orbit with the impact sequence of
// the orbits found at both ends lies in one box. `lo` and `hi` are the requests at the two ends
// (their start states and period). The interval is proven whole or halved up to 5 times: one proven
// result per piece, covering it; or one result, not proven, with the reason (also when the scenes
// differ otherwise).
std::vector<ProofResult> ProveOrbitOverInterval(const System& system_lo, const Scene& scene_lo, const ProofRequest& lo,
                                                const System& system_hi, const Scene& scene_hi, const ProofRequest& hi);

// A bifurcation point to prove (docs/prove.md "Bifurcation points"): the point located by
// `vibro continue` (its kind and value) on a branch in `parameter`.
struct BifurcationRequest {
  std::string kind;       // as `vibro continue` names it: "branch-point" (a pitchfork), "fold", ...
  std::string parameter;  // the scene key varied: "excitation.amplitude" or "excitation.frequency"
  double value = 0;       // the located value
  // Its uncertainty (`continue`'s bracket): the value is refined by Newton within it before the
  // proof; 0 (a value given directly): the interval is centred on `value` itself.
  double bracket = 0;
  // A grazing: a state on (or near) the orbit that grazes, at the parameter `start_value` near
  // `value` (e.g. a stored branch point just before the grazing), and its period; none: the orbit is searched from the scene's initial
  // state, as `vibro orbit` does.
  std::optional<InitialOverride> start;
  int period = 0;
  double start_value = 0;  // the parameter at which `start` lies (the orbit is found there, then followed)
  double time_limit = 60.0;
  const std::atomic<bool>* stop_requested = nullptr;
};

// Encloses the parameter of the bifurcation in an interval at most 1e-10 wide around `value`, and
// proves that exactly one such point lies there and that the crossing is transversal. This version
// proves the symmetry-breaking pitchfork ("branch-point") and the fold of the symmetric orbit of the
// symmetric two-sided one-DOF oscillator (undamped), and the grazing ("grazing") of any impacting
// orbit (damped, several contacts and modes);
// any other is "not proven" with the reason. The result's kind is "bifurcation"; its summary and
// certificate carry the interval; scripts/vibro_check_proof.py re-verifies it.
ProofResult ProveBifurcation(const System& system, const Scene& scene, const BifurcationRequest& request);

}  // namespace vibro
