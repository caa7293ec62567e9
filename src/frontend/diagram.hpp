// `vibro diagram` and Python's `vibro.diagram` (docs/diagram.md): the options checked the same
// way for both (every problem located, nothing computed or created before), and the request.
#pragma once

#include <string>

#include "frontend/frontend.hpp"
#include "frontend/limits.hpp"
#include "vibro/diagram.hpp"

namespace vibro::frontend {

// The defaults are the library's (DiagramDefaults, include/vibro/diagram.hpp), the one place
// they are set for the library, the CLI and Python.
struct DiagramSpec {
  using D = DiagramDefaults;
  std::string key;
  double from = 0, to = 0;
  long long steps = D::sweep_steps, record = D::record, searches = D::searches, grid = D::search_grid,
            max_period = D::max_period, max_branches = D::max_branches, max_points = D::max_points;
  double coverage_tolerance = D::coverage_tolerance;
  long long threads = D::threads;
};

// The request for `spec` on the scene of `origin`: both ends valid values of the key (the scene
// is loaded at each), the ranges of every option. Throws InputError naming each problem.
DiagramRequest PrepareDiagram(const SceneOrigin& origin, const DiagramSpec& spec, Naming naming);

}  // namespace vibro::frontend
