// `vibro diagram` and Python's `vibro.diagram` (docs/diagram.md): the options checked the same
// way for both (every problem located, nothing computed or created before), and the request.
#pragma once

#include <string>

#include "frontend/frontend.hpp"
#include "frontend/limits.hpp"
#include "vibro/diagram.hpp"

namespace vibro::frontend {

struct DiagramSpec {
  std::string key;
  double from = 0, to = 0;
  long long steps = 40, record = 16, searches = 3, grid = 6, max_period = 4, max_branches = 24, max_points = 400;
  double coverage_tolerance = 1e-3;
  long long threads = 0;
};

// The request for `spec` on the scene of `origin`: both ends valid values of the key (the scene
// is loaded at each), the ranges of every option. Throws InputError naming each problem.
DiagramRequest PrepareDiagram(const SceneOrigin& origin, const DiagramSpec& spec, Naming naming);

}  // namespace vibro::frontend
