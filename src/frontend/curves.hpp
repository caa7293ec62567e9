// `vibro curve` and vibro.curve (docs/diagram.md, "Two-parameter curves"): the checks, the start of
// each curve (a bifurcation stored by `vibro continue --out`, or the first one met on a segment of
// the parameter plane from the scene's values) and the tracing, shared by the command line and Python.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "frontend/frontend.hpp"
#include "frontend/limits.hpp"
#include "vibro/two_parameter.hpp"

namespace vibro::frontend {

struct CurveSpec {
  std::vector<std::string> params;             // KEY1, KEY2
  std::vector<std::string> kinds;              // CurveKinds(); empty with --from: the stored bifurcation's kind
  long long contact = -1;                      // non-smooth kinds, several contacts (−1: any)
  std::vector<double> range1, range2;          // the box
  // A,B: search the segment from the scene's (KEY1, KEY2) to (A, B); or A1,B1,A2,B2,...: one end per kind
  std::vector<double> toward;
  std::string from;                            // or: the bifurcation `point` of this stored branch
  long long point = -1;
  double step = 0.02, max_step = 0.1;          // in units of the box scaled to (0, 1)²
  long long max_points = 200, period = 0, transient = 200;
};

// What to trace: the request (box, steps, the start orbit and the search segment) and the kinds.
struct CurvePlan {
  CurveRequest request;
  std::vector<std::string> kinds;
  std::vector<std::pair<double, double>> directions;  // the search segment of each kind (request.dir1, dir2)
  std::string param1, param2;
};
// Checks the spec against the scene (InputError with every problem) and finds the start: the stored
// bifurcation's nearest branch point, or the orbit of the scene (a transient and Newton).
CurvePlan PlanCurves(const SceneOrigin& origin, const LoadedScene& loaded, const CurveSpec& spec, Naming naming);
// One curve per kind. on_point(curve index, points, v1, v2) after each point.
std::vector<Curve> TraceCurves(const CurvePlan& plan, const std::atomic<bool>* stop,
                               const std::function<void(size_t, size_t, double, double)>& on_point = {});

}  // namespace vibro::frontend
