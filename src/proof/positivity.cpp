// Certified positivity by subdivision and the mean-value form (positivity.hpp).
#include "proof/positivity.hpp"

#include <cmath>

#include <fmt/format.h>

namespace vibro::proof {
namespace {

struct Search {
  int max_depth;
  const Budget& budget;
  const std::function<Interval(double)>& value;
  const std::function<Interval(const Interval&)>& slope;
  Positivity& out;

  // Pieces are appended left to right; false on the first failure.
  bool Piece(double lo, double hi, int depth) {
    if (budget.passed()) {
      out.reason = budget.interrupted() ? "interrupted" : "time limit reached";
      out.failed_at = lo;
      return false;
    }
    const double c = lo + (hi - lo) / 2;
    const Interval piece = Interval::Hull(lo, hi);
    const Interval f = value(c) + slope(piece) * (piece - Interval(c));
    if (f.Positive()) {
      if (!budget.TakePieces(1)) {
        out.failed_at = c;
        out.failed_value = f;
        out.reason = fmt::format("more than {} subdivision pieces (the prover's bound, docs/prove.md)", kMaxPieces);
        return false;
      }
      out.pieces.emplace_back(lo, hi);
      return true;
    }
    if (depth >= max_depth || !(lo < c && c < hi)) {
      out.failed_at = c;
      out.failed_value = f;
      out.reason = fmt::format("not positive on [{:.17g}, {:.17g}]: enclosure {}", lo, hi, f.ToString());
      return false;
    }
    return Piece(lo, c, depth + 1) && Piece(c, hi, depth + 1);
  }
};

}  // namespace

Positivity ProvePositive(double a, double b, double step, int max_depth, const Budget& budget,
                         const std::function<Interval(double)>& value,
                         const std::function<Interval(const Interval&)>& slope) {
  Positivity out;
  const double pieces = std::ceil((b - a) / step);
  if (!(pieces <= static_cast<double>(kMaxPieces))) {
    out.failed_at = a;
    out.reason = fmt::format("[{:.17g}, {:.17g}] needs more than {} subdivision pieces (the prover's bound, "
                             "docs/prove.md)", a, b, kMaxPieces);
    return out;
  }
  const int count = pieces < 1 ? 1 : static_cast<int>(pieces);
  Search search{max_depth, budget, value, slope, out};
  double lo = a;
  for (int k = 1; k <= count; ++k) {
    const double hi = k == count ? b : a + (b - a) * k / count;
    if (!search.Piece(lo, hi, 0)) return out;
    lo = hi;
  }
  out.proven = true;
  return out;
}

}  // namespace vibro::proof
