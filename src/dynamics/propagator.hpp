// The interface between the hybrid automaton (simulator.cpp) and an engine: advance the smooth
// flow of one mode (free flight or sticking) from a start state to the first guard crossing or a
// time limit, and give dense output on what was advanced.
#pragma once

#include <atomic>
#include <functional>
#include <string>

#include <Eigen/Dense>

#include "vibro/observer.hpp"

namespace vibro::detail {

// How a free flight starts: which derivatives of the gap g = x_B − x0 vanish at σ = 0, so that the
// trivial root there is divided out (MODEL §2.1, §8.8) rather than skipped with a time offset.
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

struct SegmentStart {
  Mode mode;
  double phase;              // forcing phase ωt at σ = 0 (reduced)
  double offset;             // clock offset at σ = 0 (time since the start of the period)
  const Eigen::VectorXd& X;  // modal state at σ = 0
  const Eigen::VectorXd& V;
  double gap;                // x_B − x0 at σ = 0 (free flight; 0 on the stop)
  FlightStart flight_start;
  StickStart stick_start;
};

enum class SegmentEnd {
  kLimit,    // reached sigma_max without a guard
  kContact,  // free flight: g reached 0 (impact if ẋ_B⁻ < 0, else a touch)
  kRelease,  // sticking: R reached 0 (release if Ṙ < 0, else a tangency)
  kFailure,  // the engine could not advance (message says why)
};

struct SegmentResult {
  SegmentEnd end;
  double sigma;  // local time reached
  std::string message;
  // When the end is known in closed form as a clock offset in the same period (one-DOF release
  // phase), that offset exactly: the clock is set to it rather than to offset + sigma, so that
  // a one-DOF orbit repeats to the bit.
  double exact_offset = -1.0;
  // kFailure because a stop request (SIGINT/SIGTERM) was seen inside the segment: the run is
  // interrupted, not failed; everything up to sigma is valid.
  bool stopped = false;
};

// Called with local-time stretches [lo, hi] on which Evaluate() is valid (exact engine: the whole
// segment at once; CVODE: each internal step).
using StretchCallback = std::function<void(double lo, double hi)>;

class Propagator {
 public:
  virtual ~Propagator() = default;
  virtual void Begin(const SegmentStart& start) = 0;
  // Advance to the first guard crossing (if detect_events) or to sigma_max.
  virtual SegmentResult Advance(double sigma_max, bool detect_events,
                                const StretchCallback& on_stretch) = 0;
  // Dense output at local time sigma within the last stretch reported.
  virtual void Evaluate(double sigma, Eigen::VectorXd& X, Eigen::VectorXd& V) const = 0;
  // Free flight: x_B − x0 at sigma without cancellation (increments from the start).
  virtual double Gap(double sigma) const = 0;
  // Integrator work so far (zero for closed forms).
  virtual SolverStats stats() const { return {}; }

  // A stop request polled inside Advance's loops (null: never stopped). A segment that sees it
  // ends as kFailure with `stopped` set, so that a segment that would never end still stops.
  void set_stop_flag(const std::atomic<bool>* flag) { stop_flag_ = flag; }

 protected:
  bool StopRequested() const { return stop_flag_ && stop_flag_->load(std::memory_order_relaxed); }

 private:
  const std::atomic<bool>* stop_flag_ = nullptr;
};

}  // namespace vibro::detail
