// The options of a diagram (see diagram.hpp).
#include "frontend/diagram.hpp"

#include <cmath>
#include <vector>

#include <fmt/format.h>

namespace vibro::frontend {

DiagramRequest PrepareDiagram(const SceneOrigin& origin, const DiagramSpec& s, Naming naming) {
  std::vector<std::string> problems;
  CheckFinite(naming, naming == Naming::kPython ? "from_" : "--from", s.from, problems);
  CheckFinite(naming, "--to", s.to, problems);
  if (std::isfinite(s.from) && s.from == s.to)
    problems.push_back(fmt::format("{} {} and {} {}: expected two different values", OptionName(naming, "--from"),
                                   s.from, OptionName(naming, "--to"), s.to));
  CheckInteger(naming, "--steps", s.steps, {2, 1 << 16}, problems);
  CheckInteger(naming, "--record", s.record, kRecordLimit, problems);
  CheckInteger(naming, "--searches", s.searches, {0, 64}, problems);
  CheckInteger(naming, "--grid", s.grid, {1, 64}, problems);
  CheckInteger(naming, "--max-period", s.max_period, {1, 64}, problems);
  CheckInteger(naming, "--max-branches", s.max_branches, {1, 1000}, problems);
  CheckInteger(naming, "--max-points", s.max_points, {2, 100000}, problems);
  CheckInteger(naming, "--threads", s.threads, {0, 4096}, problems);
  if (!(s.coverage_tolerance > 0 && s.coverage_tolerance < 1))
    problems.push_back(fmt::format("{} {}: expected a relative distance in (0, 1)",
                                   OptionName(naming, "--coverage-tolerance"), s.coverage_tolerance));
  ThrowIfAny(problems);
  // Both ends must be valid values of the key (bad input before any computation).
  SceneAtOption(origin, s.key, s.from, naming == Naming::kPython ? "from_" : "--from");
  SceneAtOption(origin, s.key, s.to, "--to");
  DiagramRequest r;
  r.scene_at = [origin, key = s.key](double v) { return SceneWith(origin, key, v); };
  r.param = s.key;
  r.from = s.from;
  r.to = s.to;
  r.sweep_steps = static_cast<int>(s.steps);
  r.record = static_cast<int>(s.record);
  r.searches = static_cast<int>(s.searches);
  r.search_grid = static_cast<int>(s.grid);
  r.max_period = static_cast<int>(s.max_period);
  r.max_branches = static_cast<int>(s.max_branches);
  r.max_points = static_cast<int>(s.max_points);
  r.coverage_tolerance = s.coverage_tolerance;
  r.threads = static_cast<int>(s.threads);
  return r;
}

}  // namespace vibro::frontend
