// Two-parameter curves of codimension-one points (docs/diagram.md, "Two-parameter curves"): the
// curve in a plane of two scene parameters (λ1, λ2) along which periodic orbits of one family meet
// one kind of bifurcation of vibro continue (continuation.hpp): fold, flip, Neimark–Sacker,
// branch point, and the non-smooth ones, grazing (per contact), sticking-lost, sticking-entry,
// rising, simultaneous.
//
// Method: pseudo-arclength in the parameter plane, in the scaled coordinates u = (λ − lo)/(hi − lo)
// of the box. From a point B_k of the curve with unit tangent τ_k the predictor is P = B_k + h τ_k;
// the corrector solves the augmented system {orbit: F(z; λ) = z, test quantity of the kind = 0} on
// the hyperplane τ_k·(u − P) = 0 (the arclength condition; in the plane, the line through P along
// the normal ν_k). On that line the orbit is continued (Continue) from the family's side, started by
// Newton from the orbit next to B_k, and its test quantity's root is located as vibro continue
// locates it (bisection or the root fit of the arclength on the test function, to ~1e-13 of the
// line). The test quantities of the non-smooth kinds are not differentiable at their root (the
// sticking fraction vanishes like (f_max − f)^0.6 at the end of sticking; an impact speed like a
// square root past a grazing), so the root on the line is bracketed, not found by Newton. The step
// h adapts (halved on a failed corrector, on a turn of more than 30°; grown by 1.5 up to the
// maximum).
//
// Codimension-two points are located where another test quantity changes sign between two curve
// points (evaluated on the orbit next to each point, then refined by bisection of the step):
// a real multiplier through −1 on a fold or a non-smooth curve (fold–flip, "grazing meets flip"),
// through +1 on a flip or non-smooth curve, a complex pair through the unit circle, the rotation
// number of a Neimark–Sacker curve through 1/2 (1:2 resonance, the pair meeting at −1) or 0 (1:1).
#pragma once

#include <atomic>
#include <complex>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "vibro/continuation.hpp"
#include "vibro/scene.hpp"

namespace vibro {

// The kinds a curve can follow (Bifurcation::kind).
const std::vector<std::string>& CurveKinds();

struct CurveRequest {
  std::function<Scene(double, double)> scene_at;  // the scene at (λ1, λ2); throws outside the valid range
  std::string kind;                                // one of CurveKinds()
  int contact = -1;                                // a non-smooth kind with several contacts: only this contact (−1: any)
  // The start: a periodic orbit of the family at (start1, start2) (its section time, modal state and
  // period), and the direction (dir1, dir2) in the parameter plane along which the bifurcation lies
  // within `reach` (in parameter units along that direction).
  double start1 = 0, start2 = 0;
  int period = 1;
  double section_time = 0;
  Eigen::VectorXd X, V;
  double dir1 = 1, dir2 = 0, reach = 1;
  double lo1 = 0, hi1 = 1, lo2 = 0, hi2 = 1;  // the box: the curve ends where it leaves it
  double step = 0.02;                         // initial step, in units of the scaled box (0, 1)²
  double max_step = 0.1;
  int max_points = 200;                       // per direction from the start
  bool both_ways = true;
  const std::atomic<bool>* stop_requested = nullptr;
  std::function<void(size_t points, double v1, double v2)> progress;
};

// A point of the curve and the orbit of the family next to it (on the corrector line, the last
// orbit before the bifurcation).
struct CurvePoint {
  double value1 = 0, value2 = 0;
  double bracket = 0;  // the location's uncertainty along the corrector line, in scaled units
  std::string detail;  // vibro continue's description of the bifurcation there
  int contact = -1;
  double rotation_number = std::numeric_limits<double>::quiet_NaN();  // Neimark–Sacker
  // The orbit next to it: where it is, its section time and modal state, multipliers, stability,
  // events per period and (several contacts) contact sequence.
  double orbit1 = 0, orbit2 = 0, section_time = 0;
  Eigen::VectorXd X, V;
  std::vector<std::complex<double>> multipliers;
  bool stable = false;
  std::string signature, sequence;
};

struct CodimTwoPoint {
  std::string kind;    // "fold-flip", "flip-neimark-sacker", "grazing-flip", "resonance-1:2", …
  double value1 = 0, value2 = 0;
  double bracket = 0;  // distance between the two curve points around it, in scaled units
  size_t after = 0;    // between points `after` and `after + 1` of Curve::points
  std::string detail;
};

struct Curve {
  std::string status = "ok";  // "ok" | "no-start" (the bifurcation was not found from the start) | "interrupted"
  std::string kind, param1, param2;
  int contact = -1, period = 1;
  std::vector<CurvePoint> points;  // in order along the curve
  std::vector<CodimTwoPoint> special;
  std::string end_start, end_finish;  // why each end of the curve stopped (the start's side first)
  int corrections = 0;                // corrector lines run
};

Curve TraceCurve(const CurveRequest& request);

}  // namespace vibro
