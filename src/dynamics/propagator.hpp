// The interface between the hybrid automaton (simulator.cpp) and an engine: advance the smooth
// flow of one mode (free flight or sticking) from a start state to the first guard crossing or a
// time limit, and give dense output on what was advanced.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "vibro/observer.hpp"

namespace vibro::detail {

// How a free flight starts: which derivatives of the gap g = x_B − x0 vanish at σ = 0, so that the
// trivial root there is divided out (docs/model.md §2.1, §8.8) rather than skipped with a time offset.
enum class FlightStart : int {
  kGeneric = 0,    // g > 0 (or g = 0 with ẋ_B > 0 and no known structure)
  kAfterImpact,    // g = 0, g' = ẋ_B⁺ > 0
  kDeparture,      // g = g' = 0, g'' > 0 (r = 0 impact with R < 0, tangential touch)
  kAfterRelease,   // g = g' = g'' = 0, g''' > 0
};

// How a sticking phase starts, for the root search on R (release).
enum class StickStart : int {
  kGeneric = 0,  // R > 0
  kRising,       // R = 0, Ṙ > 0 (plastic impact exactly where R vanishes)
  kTangent,      // R = Ṙ = 0, R̈ > 0 (a release tangency that did not cross)
};

template <class S>
struct SegmentStartT {
  using Vec = Eigen::Matrix<S, Eigen::Dynamic, 1>;
  Mode mode;
  S phase;       // forcing phase ωt at σ = 0 (reduced)
  S offset;      // clock offset at σ = 0 (time since the start of the period)
  const Vec& X;  // modal state at σ = 0
  const Vec& V;
  S gap;         // x_B − x0 at σ = 0 (free flight; 0 on the stop) of contact `contact`
  FlightStart flight_start;  // of contact `contact`; every other contact starts generic
  StickStart stick_start;
  // Several contacts (docs/contacts.md): sticking, the held contact; free flight, the contact the
  // flight starts from (flight_start and gap are its own).
  int contact = 0;
  // Free flight with several contacts: every contact's gap c_jᵀX − e_j at σ = 0 (gap[contact] is
  // `gap`); null with one contact.
  const std::vector<S>* gaps = nullptr;
  // ... and every contact's flight start (the same kinds; `flight_start` is starts[contact]).
  // While sticking, the start of the other contacts' gaps under the held flow.
  const std::vector<FlightStart>* starts = nullptr;
  // A contact left out of the search (the contact of a chattering tail: its flow dips below).
  int skip = -1;
  // sin φ and cos φ of `phase` when the caller has them (Real<S>::sin and cos of the same phase,
  // so the same values): the engine does not evaluate them again.
  const S* phase_sincos = nullptr;
};

enum class SegmentEnd {
  kLimit,    // reached sigma_max without a guard
  kContact,  // free flight: g reached 0 (impact if ẋ_B⁻ < 0, else a touch)
  kRelease,  // sticking: R reached 0 (release if Ṙ < 0, else a tangency)
  kFailure,  // the engine could not advance (message says why)
};

template <class S>
struct SegmentResultT {
  SegmentEnd end;
  S sigma;  // local time reached
  std::string message;
  // When the end is known in closed form as a clock offset in the same period (one-DOF release
  // phase), that offset exactly: the clock is set to it rather than to offset + sigma, so that
  // a one-DOF orbit repeats to the bit.
  S exact_offset = S(-1);
  // kFailure because a stop request (SIGINT/SIGTERM) was seen inside the segment: the run is
  // interrupted, not failed; everything up to sigma is valid.
  bool stopped = false;
  // Which contact's guard ended the segment (kContact: its gap reached 0; kRelease: its reaction).
  int contact = 0;
  // kFailure because the contact cannot be resolved at the engine's precision (CVODE: the gap
  // vanishes at and very near the start of a flight, a chattering tail at its resolution floor):
  // the run is undetermined there (docs/chattering.md), not a numerical failure.
  bool undetermined = false;
};

// Called with local-time stretches [lo, hi] on which Evaluate() is valid (exact engine: the whole
// segment at once; CVODE: each internal step).
template <class S>
using StretchCallbackT = std::function<void(S lo, S hi)>;

// The engine's scalar S is double, or quad for the reference engine (dynamics/quad.hpp).
template <class S>
class PropagatorT {
 public:
  using Vec = Eigen::Matrix<S, Eigen::Dynamic, 1>;
  virtual ~PropagatorT() = default;
  virtual void Begin(const SegmentStartT<S>& start) = 0;
  // Advance to the first guard crossing (if detect_events) or to sigma_max.
  virtual SegmentResultT<S> Advance(S sigma_max, bool detect_events,
                                    const StretchCallbackT<S>& on_stretch) = 0;
  // Dense output at local time sigma within the last stretch reported.
  virtual void Evaluate(S sigma, Vec& X, Vec& V) const = 0;
  // Free flight: x_B − x0 at sigma without cancellation (increments from the start).
  virtual S Gap(S sigma) const = 0;
  // Evaluate and Gap at once (free flight; the exact engine evaluates each mode's flow once for
  // both, with the same values as the two calls).
  virtual S EvaluateWithGap(S sigma, Vec& X, Vec& V) const {
    Evaluate(sigma, X, V);
    return Gap(sigma);
  }
  // The gap of contact j at sigma (free flight: without cancellation from its start value;
  // sticking: of a contact that is not held). Gap(σ) is GapOf(start contact, σ).
  virtual S GapOf(int j, S sigma) const { return j == 0 ? Gap(sigma) : S(0); }
  // Sticking on one contact: its reaction R (the paper's eq. (5)) and Ṙ at sigma of the last
  // segment, from the engine's own closed form of the held flow (the one its release search
  // uses); false when the engine has none, and the caller evaluates the state instead.
  virtual bool HeldReaction(const S& /*sigma*/, S& /*R*/, S& /*rate*/) const { return false; }
  // The same with R̈ (the max R search's Newton steps, docs/loads.md §3); false when the engine
  // has no closed form.
  virtual bool HeldReactionJet(const S& /*sigma*/, S& /*R*/, S& /*rate*/, S& /*accel*/) const { return false; }
  // A bound M ≥ |R'''| over [0, H] of the last segment's held flow, from the engine's closed form
  // (the bound its release search steps with): the max R search certifies its cells with it
  // (docs/loads.md §3). False when the engine has none.
  // With M5 ≥ |R⁽⁵⁾| there too when m5 is given (0 when the engine has none).
  virtual bool HeldReactionBound(const S& /*H*/, S& /*M*/, S* /*m5*/ = nullptr) const { return false; }
  // R and its first four derivatives at sigma (d[0..4]), from the engine's closed form; false when
  // it has none (the max R search then steps with HeldReactionJet).
  virtual bool HeldReactionTaylor(const S& /*sigma*/, S* /*d*/) const { return false; }
  // Integrator work so far (zero for closed forms).
  virtual SolverStats stats() const { return {}; }
  // Polled inside long root searches and stepping loops: true stops the segment with a failure
  // (a stop request, or the per-segment work limit). Set by the automaton.
  void SetStopPoll(std::function<bool()> poll) { stop_poll_ = std::move(poll); }

 protected:
  bool StopRequested() const { return stop_poll_ && stop_poll_(); }

 private:
  std::function<bool()> stop_poll_;
};

using SegmentStart = SegmentStartT<double>;
using SegmentResult = SegmentResultT<double>;
using StretchCallback = StretchCallbackT<double>;
using Propagator = PropagatorT<double>;

}  // namespace vibro::detail
