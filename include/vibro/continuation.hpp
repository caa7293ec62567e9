// One-parameter continuation of periodic orbits (paper §5, MODEL §5.6–§5.7): pseudo-arclength
// predictor–corrector on G(z, λ) = F(z; λ) − z, F the stroboscopic map of the Poincaré solver
// (analytic ∂F/∂z, central differences in λ since λ is any numeric scene key), with step-size
// control, so that folds are passed. Along the branch: stability, folds (the λ-component of the
// tangent changes sign), flips and Neimark–Sacker points (a multiplier leaves the unit circle at
// −1, or as a complex pair), and the end of sticking (the sticking fraction reaches 0: located
// by secant iterations on SP(λ) = 0, which vanishes linearly, MODEL §6.3).
#pragma once

#include <complex>
#include <functional>
#include <string>
#include <vector>

#include "vibro/poincare.hpp"
#include "vibro/scene.hpp"

namespace vibro {

struct ContinuationRequest {
  // The scene with the continued parameter set to λ (throws on a value outside its valid range).
  std::function<Scene(double)> scene_at;
  double from = 0, to = 1;   // λ range; the branch starts at `from`
  double step = 0;           // initial arclength step (0: |to − from|/50)
  double max_step = 0;       // (0: |to − from|/10)
  int max_points = 1000;
  OrbitRequest orbit;        // how the first orbit is found
};

struct BranchPoint {
  double value;
  Attractor summary;  // sticking fraction, stick phases, impacts per period
  std::vector<std::complex<double>> multipliers;
  bool stable;
};

struct Bifurcation {
  std::string kind;  // "fold" | "flip" | "neimark-sacker" | "sticking-lost"
  double value;
  std::string detail;
};

struct Branch {
  std::string status = "ok";  // "ok" | "no-orbit"
  std::vector<BranchPoint> points;
  std::vector<Bifurcation> bifurcations;
  std::string end;  // why the branch stopped
};

Branch Continue(const ContinuationRequest& request);

}  // namespace vibro
