// Studies over many independent simulations (basins of attraction, coexisting attractors):
// cells are simulated in parallel with oneTBB, each from its own initial state, and labelled
// afterwards in cell order, so that the result is bitwise identical for any thread count.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "vibro/attractor.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro {

// An initial-state coordinate: "x_B" or "v_B" (contact displacement / velocity: the rest of the
// state is the static shape scaled to x_B and the impulse direction T_B scaled to ẋ_B), or "X<i>" /
// "V<i>" (1-based modal coordinate i, the others from the scene's initial state).
struct Coordinate {
  std::string name;
  double from = 0, to = 1;
};

// A distinct attractor found by a study.
struct FoundAttractor {
  Attractor attractor;
  long long cells = 0;              // cells (or samples) that reached it
  double basin_fraction = 0;        // cells / all resolved-or-not cells
  double basin_fraction_error = 0;  // binomial standard error √(p(1−p)/N)
  std::vector<double> example;      // the first initial state (coordinate values) that reached it
};

struct StudyResult {
  std::vector<FoundAttractor> attractors;  // label k ↔ attractors[k]
  std::vector<int> labels;                 // per cell; −1 unresolved (not periodic), −2 inadmissible
  double unresolved_fraction = 0;
  double inadmissible_fraction = 0;
  long long cells = 0;
};

struct StudyOptions {
  int threads = 0;                                  // 0: all cores
  std::function<void(long long done, long long total)> progress;  // called from worker threads
  const std::atomic<bool>* stop_requested = nullptr;
};

// Simulates the scene from each initial state (values of the two coordinates), classifies the
// final periods and groups equal attractors (same kind and period, sticking fraction and stick
// phases within 1e-6).
StudyResult RunStudy(const System& system, const Scene& scene, const Coordinate& a,
                     const Coordinate& b, const std::vector<std::pair<double, double>>& points,
                     const StudyOptions& options);

// Grid of nx × ny cell centres over the two coordinates (row-major: index = iy·nx + ix).
std::vector<std::pair<double, double>> GridPoints(const Coordinate& a, const Coordinate& b, int nx,
                                                  int ny);
// N points drawn uniformly over the two ranges from a fixed seed (reproducible).
std::vector<std::pair<double, double>> RandomPoints(const Coordinate& a, const Coordinate& b,
                                                    long long n, unsigned long long seed);

// Brute-force bifurcation diagram: the parameter is stepped up from `from` to `to` and back down,
// each run starting from the final state of the previous one (so hysteresis shows), and the last
// `record` stroboscopic points and the attractor of each run are kept.
struct SweepPoint {
  double value;
  bool upward;
  Attractor attractor;
  std::vector<double> x_B, v_B;  // contact displacement and velocity at the last section points
};
struct SweepRequest {
  std::function<Scene(double)> scene_at;
  double from = 0, to = 1;
  int steps = 50;
  int record = 16;
  bool both_ways = true;
};
std::vector<SweepPoint> Sweep(const SweepRequest& request, const std::atomic<bool>* stop = nullptr);

// Checks a coordinate name against the system ("" when valid, else the problem).
std::string CheckCoordinate(const System& system, const std::string& name);

}  // namespace vibro
