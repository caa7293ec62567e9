// Scoring another simulator's trajectory against vibro's run of the same scene
// (docs/validation.md): events matched kind by kind, errors relative to the forcing period T,
// and the first divergence.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "vibro/observer.hpp"

namespace vibro {

// One event of the other simulator.
struct TheirEvent {
  double t = 0;
  EventKind kind = EventKind::kImpact;
  std::optional<double> velocity;  // contact velocity ẋ_B just before the event
  int line = 0;
};

struct ScoreOptions {
  double window = 0.05;      // events further apart than window·T are not matched
  double tolerance = 1e-6;   // a matched event differing by more than tolerance·T diverges
};

struct KindScore {
  EventKind kind;
  long long theirs = 0, ours = 0, matched = 0;
  // Their impacts left unmatched between the last impact vibro resolves and vibro's predicted
  // accumulation point (+ tolerance·T): the tail of a chattering sequence vibro sums up (MODEL §5.4), not a
  // divergence.
  long long in_accumulation = 0;
  double max_time_error = 0;   // max |t_theirs − t_ours| / T over matched events
  double mean_time_error = 0;  // mean of the same
  std::optional<double> max_velocity_error;  // max |Δẋ_B⁻| / max |ẋ_B⁻| (ours), when given
};

struct Divergence {
  double t;                     // time of their event
  EventKind kind;
  std::string why;              // "unmatched" or "time error 3.2e-05 T"
  std::optional<double> ours_t; // the matched event of vibro, if any
};

struct ScoreReport {
  double period = 0;  // T
  std::vector<KindScore> kinds;  // kinds present in either list
  double max_time_error = 0;     // over every matched event, / T
  std::optional<double> max_velocity_error;
  std::optional<Divergence> divergence;  // the first of their events that is unmatched or off
};

// `ours` and `theirs` in time order. Ours past the last of theirs (+ window·T) are not counted.
ScoreReport ScoreEvents(const std::vector<Event>& ours, const std::vector<TheirEvent>& theirs, double T,
                        const ScoreOptions& options);

}  // namespace vibro
