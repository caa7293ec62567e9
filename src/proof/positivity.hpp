// Certified positivity of a function on a whole interval (docs/prove.md "exclusions"): the gap of
// a flight, the reaction of a sticking phase. The interval is cut into pieces; on a piece
// I = [lo, hi] with midpoint c the mean-value form f(I) ⊂ f(c) + f'(I)(I − c) must lie above 0,
// else the piece is halved, up to a depth. The accepted pieces go into the certificate, where the
// checker evaluates the same form again.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "proof/budget.hpp"
#include "proof/interval.hpp"

namespace vibro::proof {

struct Positivity {
  bool proven = false;
  std::vector<std::pair<double, double>> pieces;  // contiguous, covering [a, b], when proven
  double failed_at = 0;   // midpoint of the piece that could not be proven positive
  Interval failed_value;  // its enclosure there
  std::string reason;     // "" when proven
};

// f > 0 on [a, b] (a ≤ b): value(c) encloses f at the point c, slope(I) encloses f' on I.
// The first cut uses pieces of at most `step`; a piece is halved at most `max_depth` times; the
// pieces accepted are taken from the budget, which also ends the search past its time.
Positivity ProvePositive(double a, double b, double step, int max_depth, const Budget& budget,
                         const std::function<Interval(double)>& value,
                         const std::function<Interval(const Interval&)>& slope);

}  // namespace vibro::proof
