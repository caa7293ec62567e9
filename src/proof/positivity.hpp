// Certified positivity of a function on a whole interval (docs/prove.md "exclusions"): the gap of
// a flight, the reaction of a sticking phase. The interval is cut into pieces; on a piece
// I = [lo, hi] with midpoint c the mean-value form f(I) ⊂ f(c) + f'(I)(I − c) must lie above 0,
// else the piece is halved, up to a depth. The accepted pieces go into the certificate, where the
// checker evaluates the same form again.
#pragma once

#include <chrono>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "proof/interval.hpp"

namespace vibro::proof {

// A wall-clock limit: a proof never hangs.
class Deadline {
 public:
  explicit Deadline(double seconds)
      : end_(std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                    std::chrono::duration<double>(seconds))) {}
  bool passed() const { return std::chrono::steady_clock::now() > end_; }

 private:
  std::chrono::steady_clock::time_point end_;
};

struct Positivity {
  bool proven = false;
  std::vector<std::pair<double, double>> pieces;  // contiguous, covering [a, b], when proven
  double failed_at = 0;   // midpoint of the piece that could not be proven positive
  Interval failed_value;  // its enclosure there
  std::string reason;     // "" when proven
};

// f > 0 on [a, b] (a ≤ b): value(c) encloses f at the point c, slope(I) encloses f' on I.
// The first cut uses pieces of at most `step`; a piece is halved at most `max_depth` times.
Positivity ProvePositive(double a, double b, double step, int max_depth, const Deadline& deadline,
                         const std::function<Interval(double)>& value,
                         const std::function<Interval(const Interval&)>& slope);

}  // namespace vibro::proof
