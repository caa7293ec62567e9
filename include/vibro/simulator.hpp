// The hybrid automaton of an impact oscillator with sticking (docs/model.md §1-§5), written once and
// driven by either engine (exact closed forms, or CVODE), in double or, for the exact engine, in
// 113-bit quad precision (run.precision = "quad", the reference).
//
// State: time t = t0 + kT + s (whole periods k, offset s ∈ [0, T)), modal X, Ẋ, the mode
// (free | sticking) and, during chattering, the speeds of the sequence's first and last impacts.
// With m contacts (docs/contacts.md) also: the active contact a (the held one while sticking, the
// one the flight left, or is chattering at, while free), every gap g_j = c_jᵀX − e_j and how each
// gap starts its flight. Below, x_B, g, T_B, s_B, R are those of the contact concerned; m = 1 (a
// [stop]) is the same code with no other gap. The laws of several contacts (the impact LCP, the
// acceleration LCP, held sets: their entry and release) are in src/dynamics/contact_laws.hpp.
// x⁻ / x⁺ denote the state just before / after a reset at the same t.
//
//   loop until k = periods, an interruption, or a failure:
//     free flight:   advance the free flow (1) until the first gap g_j reaches 0 (the first
//                    certified root over all gaps) or t hits the period boundary (the engine never
//                    skips a root; trivial roots at the start of a flight are divided out per gap,
//                    docs/model.md §2.1)
//                    A gap's start kind holds while the gap is 0: a segment that opens it makes
//                    it generic (a zero divided out where there is none would skip the next root)
//       impacts alternating between two contacts, each closing slower, flights < 1e-9 T, more
//                    than three in a row → undetermined (two contacts chattering to one point)
//       several gaps 0 at one instant (within rounding), closing → the impact LCP on them
//                    (docs/contacts.md): emit an impact per contact, flagged simultaneous; the
//                    contacts left at rest → the acceleration LCP (rest) below
//       boundary     → section point, checkpoint, k ← k+1 (the flow restarts from the same state)
//       g = 0, ẋ_B⁻ < 0 (impact):
//           R⁻ = reaction of the state (the paper's eq. (5))
//           r = 0, or "threshold" with |ẋ_B⁻| < v_switch:
//               Ẋ⁺ = Π Ẋ⁻ (plastic projection, docs/model.md §4.4); emit impact
//               R⁻ > 0, or R⁻ = 0 and Ṙ > 0 → emit stick, mode ← sticking
//               otherwise                   → leave at zero velocity (g = g' = 0, g'' > 0)
//           else Ẋ⁺ = Ẋ⁻ − (1+r) T_B ẋ_B⁻/s_B (eq. 12); emit impact
//               "accumulation", 0 < r < 1, R > 0 on the stuck state (docs/model.md §5.4, §5.4):
//                   Δ0 = 2ẋ_B⁺/((1−r) s_B R), ε = −ṘΔ0/R, Δ∞ = Δ0(1 + ε/3) with an estimated
//                   error E (dynamics/chatter_tail.hpp); if |ε| ≤ 0.1 and E ≤ chatter_tolerance·T:
//                   flow freely over Δ∞ (no guards of this contact; every other gap must stay
//                   open over it, certified), project onto the stop; if R(t∞) > 0 → emit
//                   accumulation and stick, mode ← sticking; otherwise follow the next impact
//                   (counted as an impact followed)
//               "none": impacts are followed one by one; when the next flight is shorter than
//                   the time resolution the run stops with status numerical-failure
//       g = 0, |ẋ_B⁻| below the rounding floor (or, CVODE, below √rtol of the sequence's first
//                    speed) inside a chattering sequence with R > 0 → status undetermined: the
//                    accumulation point could not be predicted within the target (never guessed)
//       g = 0, ẋ_B⁻ ≥ 0 (tangential touch, docs/model.md §2.1): emit grazing; R > 0 → stick (docs/model.md
//                    §4.4 iii), else keep flying (g = g' = 0, g'' > 0 divided out)
//     sticking:      advance the constrained flow (6) of the held contact a until R reaches 0,
//                    another gap g_k reaches 0 under that flow, or the period boundary (one DOF:
//                    the body rests and the release phase is closed form, docs/model.md §4.4).
//                    Held on a set S of two or more contacts: the flow on {g_j = ġ_j = 0, j ∈ S}
//                    in closed form, until a force λ_j (j ∈ S) or another gap reaches 0
//       g_k = 0, closing → the impact LCP on S ∪ {k}: a held contact pushed off (liftoff) →
//                    emit its release; emit the impact at k; contacts at rest after it (k if
//                    plastic) → the acceleration LCP (rest); k bouncing while S stays held: a
//                    chattering sequence beside S, its accumulation point predicted as above with
//                    k's deceleration A under the S-flow (flow over Δ∞, project onto S ∪ {k},
//                    emit accumulation, then rest); at the rounding floor first → undetermined
//       g_k = 0, tangential → emit grazing; the held flow pulls k off → keep going, else rest
//       λ_j = 0, λ̇_j < 0 (S of two or more) → emit release of j, S ← S \ {j}, its gap starts
//                    with g = g' = g'' = 0, g''' > 0 under the flow of the others
//       R = 0, Ṙ < 0 → emit release, mode ← free (g = g' = g'' = 0, g''' > 0)
//       R = 0, Ṙ ≥ 0 → tangency (rising-bifurcation boundary, docs/model.md §5.7): stay stuck
//     compliant stop j (docs/compliant.md; a stiffness k_j, damping c_j, rule "force" | "gap"; the
//                    law in src/dynamics/compliant_contact.hpp, these transitions in
//                    src/dynamics/compliant_transitions.hpp):
//       free flight reaches g_j = 0 closing (or touching with R > 0) → emit stick (entry), mode ←
//                    sticking on j as a contact phase: no reset, the flow of the structure plus
//                    k_j T_j c_jᵀ and c_j T_j c_jᵀ in closed form; touching with R ≤ 0 → emit grazing
//       contact phase: advance until the exit (rule "gap": g_j = 0; rule "force": λ_j = −k g − c ġ
//                    = 0), another gap reaching 0 (→ failure: not supported), or the period
//                    boundary; each segment adds its duration, ∫λ dt, peak force (certified max),
//                    penetration and dashpot energy to the phase's account
//       exit         → emit release (the phase's loads); rule "gap" (or c = 0): free flight from
//                    g = 0, ġ ≥ 0; rule "force" with g < 0: a relaxing flight, its gap g_j − y,
//                    y = g_exit e^(−kσ/c) the surface, until re-contact (→ entry) or the surface is
//                    back within the gap's rounding (→ an ordinary flight); another contact closing
//                    during it → failure (not supported)
//       start with g_j ≤ 0 and the body pushed in → a contact phase
//     start on several stops (gaps closed within double's rounding, whatever the precision):
//                    those moving away leave, the others → rest below
//     rest (contacts Z0 at zero gap and zero gap velocity): project onto them, solve the
//                    acceleration LCP a = a⁰ + Wλ, 0 ≤ λ ⊥ a ≥ 0: λ_j > 0 → stick (emit stick for
//                    the new ones), else leave at zero velocity (emit release if it was held);
//                    none held → free flight; λ_j = a_j = 0 → undetermined (degenerate entry); a
//                    held set with CVODE, or a defective damped held flow → undetermined
//
// Simultaneous events: a guard met exactly at a period boundary is handled after the section
// point is recorded (the section sees x⁻). Two guards at one instant are handled in the order
// contact → reset → the new mode's guards evaluated at the reset state: an impact whose reset
// state already satisfies the sticking condition goes straight to sticking, a release into a
// state moving into the stop is an immediate touch. v_switch ("threshold" only) =
// run.chatter_switch × |ẋ_B⁻| of the sequence's first impact, but never below the rounding floor
// of ẋ_B, 10³ ε Σ|Ẋ_i| (docs/model.md §5.4).
#pragma once

#include <atomic>
#include <optional>
#include <string>
#include <vector>

#include "vibro/observer.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro {

// kUndetermined: a chattering sequence whose accumulation point cannot be predicted within the
// run's accuracy target before its impact speeds fall below what the engine resolves.
enum class RunStatus { kOk, kNumericalFailure, kInterrupted, kUndetermined };
const char* ToString(RunStatus s);  // "ok", "numerical-failure", "interrupted", "undetermined"

// What the chattering treatment did over a run (docs/model.md §5.4).
struct ChatterStats {
  long long accumulations_predicted = 0;  // sequences ended by a predicted accumulation point
  long long impacts_followed = 0;         // impacts followed because a prediction was refused
  double max_estimated_error = 0;         // largest estimated error of a taken prediction, / T
};

struct RunResult {
  RunStatus status = RunStatus::kOk;
  std::string message;  // why the run stopped early, and what to change
  Clock end;            // time reached
  double t_end = 0;
  EventCounts counts;
  std::vector<EventCounts> contact_counts;  // per contact, in [[contact]] order (one for [stop])
  Eigen::VectorXd X, V;  // final state
  Mode mode = Mode::kFree;
  SolverStats solver;  // CVODE work (engine "cvode")
  ChatterStats chatter;
};

// A start other than the scene's [initial] table: modal state at time t (the Poincaré solver).
struct InitialOverride {
  double time;
  Eigen::VectorXd X, V;
};

struct SimulationOptions {
  std::vector<Observer*> observers;
  const InitialOverride* initial = nullptr;
  const std::atomic<bool>* stop_requested = nullptr;  // polled between events
  const Checkpoint* resume_from = nullptr;            // continue a run from this checkpoint
  // The sticking phases' ∫R dt and max R of the events (docs/loads.md), computed when observers are
  // given; false leaves them NaN (only to measure their cost, benchmarks/loads_bench.cpp).
  bool loads = true;
  // Section points at origin + kT (k ≥ 1) instead of start + kT: a start (`initial`, required)
  // inside the period [origin, origin + T) is no section point, and run.periods counts from
  // origin. The state at a fixed forcing phase whatever the start (the stroboscopic state of a
  // branch point, docs/output.md).
  std::optional<double> section_origin;
  // A budget of segments (the flights and held phases between two events, period boundaries
  // included): past it the run stops with kNumericalFailure and says so. 0: no budget. A map
  // evaluation inside a Newton or a continuation (StroboscopicMap) always has one, so that a trial
  // point whose motion chatters without end, or takes far more events than an orbit of the
  // family, is a failed evaluation rather than an endless run (docs/orbits.md).
  long long max_segments = 0;
};

// Runs the scene's initial state for scene.run.periods forcing periods with the scene's engine.
// A forcing frequency that is not finite and positive (a scene built in code, not validated by
// LoadScene: a continuation's Newton iterate, say) is refused: kNumericalFailure, nothing run.
RunResult Simulate(const System& system, const Scene& scene, const SimulationOptions& options);

}  // namespace vibro
