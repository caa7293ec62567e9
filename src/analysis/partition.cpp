// Two-parameter partitions by families of one-parameter branches (include/vibro/continuation.hpp).
#include <algorithm>
#include <cstddef>
#include <exception>

#include "analysis/parallel_for.hpp"
#include "vibro/contact_sequence.hpp"
#include "vibro/continuation.hpp"

namespace vibro {
namespace {

// The spans of one sequence along a column's branch points (value, sequence), sorted by value.
std::vector<PartitionColumn::SequenceSpan> Spans(
    std::vector<std::pair<double, std::vector<std::string>>> points) {
  std::sort(points.begin(), points.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<PartitionColumn::SequenceSpan> out;
  std::vector<std::string> current;
  for (const auto& [value, sequence] : points) {
    if (!out.empty() && SameContactSequence(current, sequence)) {
      out.back().to = value;
      continue;
    }
    out.push_back({value, value, ContactSequenceText(sequence)});
    current = sequence;
  }
  return out;
}

}  // namespace

std::vector<PartitionColumn> Partition(const PartitionRequest& req) {
  std::vector<PartitionColumn> columns(req.values1.size());
  const auto one = [&](size_t i) {
    PartitionColumn& col = columns[i];
    col.value1 = req.values1[i];
    std::vector<std::pair<double, std::vector<std::string>>> sequences;  // several contacts
    for (double to : {req.lo2, req.hi2}) {
      if (req.stop_requested && req.stop_requested->load()) {
        col.status = "interrupted";
        return;
      }
      ContinuationRequest c;
      c.scene_at = [&, v1 = col.value1](double v2) { return req.scene_at(v1, v2); };
      c.from = req.start2;
      c.to = to;
      c.step = req.step;
      c.max_points = req.max_points;
      c.orbit = req.orbit;
      c.levels = req.levels;
      c.stop_requested = req.stop_requested;
      Branch b;
      try {
        b = Continue(c);
      } catch (const std::exception& e) {  // the scene is not valid at this column's start
        col.status = "invalid-scene";
        (to == req.lo2 ? col.end_down : col.end_up) = e.what();
        return;
      }
      (to == req.lo2 ? col.end_down : col.end_up) = b.end;
      if (b.status == "no-orbit") {
        col.status = "no-orbit";
        return;
      }
      if (b.status == "interrupted") col.status = "interrupted";
      // The cells: the down half reversed, then the up half without its start (the same point).
      std::vector<PartitionPoint> cells;
      for (const auto& pt : b.points)
        cells.push_back({pt.value, pt.summary.sticking_fraction.value_or(0.0), pt.stable, pt.loads, pt.loads_note});
      if (to == req.lo2) {
        col.points.assign(cells.rbegin(), cells.rend());
      } else {
        const size_t skip = col.points.empty() || cells.empty() ? 0 : 1;
        col.points.insert(col.points.end(), cells.begin() + static_cast<std::ptrdiff_t>(skip), cells.end());
      }
      // Several contacts: each point's contact sequence, as the continuation found it (empty for
      // one contact).
      for (const BranchPoint& p : b.points) {
        if (p.sequence.empty()) continue;
        std::string unused;
        if (auto entries = ParseContactSequence(p.sequence, -1, unused))
          sequences.emplace_back(p.value, std::move(*entries));
      }
      col.crossings.insert(col.crossings.end(), b.crossings.begin(), b.crossings.end());
      col.bifurcations.insert(col.bifurcations.end(), b.bifurcations.begin(), b.bifurcations.end());
    }
    std::sort(col.crossings.begin(), col.crossings.end(),
              [](const auto& a, const auto& b) { return a.value < b.value; });
    std::sort(col.bifurcations.begin(), col.bifurcations.end(),
              [](const auto& a, const auto& b) { return a.value < b.value; });
    col.sequences = Spans(std::move(sequences));
  };
  detail::ParallelFor(columns.size(), req.threads > 0 ? req.threads : 0, [&](size_t begin, size_t end) {
    for (size_t k = begin; k != end; ++k) one(k);
  });
  return columns;
}

}  // namespace vibro
