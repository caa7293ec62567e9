// Scoring another simulator's trajectory against vibro's run of the same scene
// (docs/validation.md): events matched kind by kind, errors relative to the forcing period T,
// and the first divergence over both lists.
#pragma once

#include <functional>
#include <limits>
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
  int line = 0;                    // where it came from (messages): a CSV line, or a table's row
  // Several contacts (docs/contacts.md): the contact (0-based [[contact]] order) of the event,
  // matched only with vibro's events at that contact; none: matched with vibro's events of its
  // kind at any contact.
  std::optional<int> contact;
};

// The problems of another simulator's event table before anything is run, each named by
// where(event) (for a CSV: "FILE:LINE"): a time or velocity that is not finite; a time before
// t_begin − window·T or after t_end + window·T (t_begin = initial.time, t_end = initial.time +
// run.periods·T: vibro runs the whole scene and nothing else); a time earlier than the previous
// row's; the same time and kind as the previous row (a repeated event: two events may share a
// time only when they are of different kinds, as an accumulation point and the stick that starts
// there). At most `limit` problems are listed.
std::vector<std::string> EventTableProblems(const std::vector<TheirEvent>& theirs, double t_begin, double t_end,
                                            double T, double window,
                                            const std::function<std::string(const TheirEvent&)>& where,
                                            size_t limit = 20);

struct ScoreOptions {
  double window = 0.05;      // events further apart than window·T are not matched
  double tolerance = 1e-6;   // a matched event differing by more than tolerance·T diverges
  // The end of vibro's run: an event of either list within tolerance·T of it may lack its partner
  // (the other run may have stopped just before it).
  double t_end = std::numeric_limits<double>::infinity();
};

struct KindScore {
  EventKind kind;
  long long theirs = 0, ours = 0, matched = 0;
  // Their impacts left unmatched between the last impact vibro resolves and vibro's predicted
  // accumulation point (+ tolerance·T): the tail of a chattering sequence vibro sums up
  // (docs/model.md §5.4), not a divergence.
  long long in_accumulation = 0;
  // The same the other way: vibro's impacts left unmatched inside their accumulation intervals
  // (from their last impact to their accumulation point, + tolerance·T).
  long long ours_in_accumulation = 0;
  // Unmatched and not excused: each is a divergence.
  long long unmatched_theirs = 0, unmatched_ours = 0;
  // false for vibro's accumulation points when their list has none (a simulator that resolves
  // impacts to a threshold reports no accumulation points; the stick or release that starts at
  // each is scored instead).
  bool scored = true;
  double max_time_error = 0;   // max |t_theirs − t_ours| / T over matched events (0 when none)
  double mean_time_error = 0;  // mean of the same
  std::optional<double> max_velocity_error;  // max |Δẋ_B⁻| / max |ẋ_B⁻| (ours), when given
  // matched / max(theirs − in_accumulation, ours − ours_in_accumulation): 1 when every event of
  // both lists is matched or excused; empty when the kind is not scored or has no event to match.
  std::optional<double> matched_fraction;
};

struct Divergence {
  double t;                     // time of the diverging event (theirs, or vibro's when side = "vibro")
  EventKind kind;
  // "theirs": their event is unmatched or off; "vibro": vibro has an event they missed.
  std::string side;
  std::string why;              // "unmatched: …", "missed: …" or "time error 3.2e-05 T"
  std::optional<double> ours_t; // vibro's event, if any
};

struct ScoreReport {
  double period = 0;  // T
  std::vector<KindScore> kinds;  // kinds present in either list
  double max_time_error = 0;     // over every matched event, / T
  std::optional<double> max_velocity_error;
  long long matched = 0, unmatched = 0;  // over every scored kind, both lists
  // The earliest event of either list that is unmatched (and not excused) or off by more than
  // tolerance·T. The two runs agree when there is none.
  std::optional<Divergence> divergence;
  bool agrees() const { return !divergence; }
};

// `ours` and `theirs` in time order; ours is vibro's run of the whole scene.
ScoreReport ScoreEvents(const std::vector<Event>& ours, const std::vector<TheirEvent>& theirs, double T,
                        const ScoreOptions& options);

}  // namespace vibro
