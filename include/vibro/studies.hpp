// Studies over many independent simulations (basins of attraction, coexisting attractors):
// cells are simulated in parallel with oneTBB, each from its own initial state, and labelled
// afterwards in cell order, so that the result is bitwise identical for any thread count.
#pragma once

#include <atomic>
#include <complex>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vibro/attractor.hpp"
#include "vibro/lyapunov.hpp"
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

// What one cell of a study gave (independent of the thread count and of the process that
// computed it).
struct CellResult {
  enum class State : std::int8_t {
    kPending = 0,       // not computed (yet): an interrupted study
    kInadmissible = 1,  // the initial state is inside the stop, or on it moving in
    kFailed = 2,        // the simulation ended with a numerical failure
    kClassified = 3,    // `attractor` holds the classification (kind may be "not-periodic")
  };
  State state = State::kPending;
  Attractor attractor;
  long long periods = 0;  // periods simulated (fewer than run.periods when the cell settled)
  // Why the run ended: 0 after run.periods periods, 1 settled on a periodic attractor
  // (AttractorRecorder::Settled), 2 reached a known stable orbit (StudyOptions::known).
  std::int8_t stop = 0;
  Eigen::VectorXd z;      // final section point (X, Ẋ) at t0 + periods·T, (2n)
};

// Serialisation of cell results as doubles (bit exact; for MPI and the HDF5 cell table).
void PackCell(const CellResult& cell, std::vector<double>& out);
CellResult UnpackCell(const double*& p);
// Attractor kinds as small codes (0 not-periodic, 1 sticking-periodic, 2 impact-periodic,
// 3 no-contact-periodic, 4 permanent-contact) and back.
int KindCode(const std::string& kind);
std::string KindName(int code);

// The periodic orbit the Poincaré solver finds from a section point of an attractor class.
struct ClassOrbit {
  std::string status = "not-solved";  // FindOrbit's status, or "not-solved" (kind without a solver)
  std::vector<std::complex<double>> multipliers;  // Floquet multipliers (eigenvalues of DP)
  std::optional<bool> stable;                     // none when not converged
  double residual = 0;
  int merged = 1;  // classes of the cell classification that share this orbit
};

// A distinct attractor found by a study.
struct FoundAttractor {
  Attractor attractor;
  long long cells = 0;              // cells (or samples) that reached it
  double basin_fraction = 0;        // cells / all resolved-or-not cells
  double basin_fraction_error = 0;  // binomial standard error √(p(1−p)/N)
  std::vector<double> example;      // the first initial state (coordinate values) that reached it
  ClassOrbit orbit;                 // the solved orbit (when StudyOptions::solve_orbits)
  // Lyapunov exponents of a run of run.periods periods from the final state of the class's first
  // cell (StudyOptions::lyapunov and run.lyapunov; none otherwise).
  std::optional<LyapunovSpectrum> lyapunov;
};

struct StudyResult {
  std::vector<FoundAttractor> attractors;  // label k ↔ attractors[k]
  // Per cell: −1 unresolved (not periodic, or a numerical failure), −2 inadmissible, −3 not
  // computed (interrupted study).
  std::vector<int> labels;
  double unresolved_fraction = 0;
  double inadmissible_fraction = 0;
  double pending_fraction = 0;
  long long cells = 0;
  // The exponents of the motion of the first cell that settled on no periodic attractor (a run of
  // run.periods periods from its final state), and that cell's initial state: whether what the
  // unresolved cells reach is chaotic. None when no cell is not-periodic (or exponents are off).
  std::optional<LyapunovSpectrum> unresolved_lyapunov;
  std::vector<double> unresolved_example;
};

// A stable periodic orbit known before a study starts: a cell whose section point comes within
// `radius` (relative, as AttractorRecorder) of one of its section points at two consecutive
// periods is taken to have reached it and stops, with `attractor` as its classification.
struct KnownOrbit {
  Attractor attractor;
  std::vector<Eigen::VectorXd> points;  // the orbit's section points (X, Ẋ) at t0 + kT, (2n) each
  std::vector<Mode> modes;
  double radius = 1e-4;
};

struct StudyOptions {
  int threads = 0;                                  // 0: all cores
  std::function<void(long long done, long long total)> progress;  // called from worker threads
  const std::atomic<bool>* stop_requested = nullptr;
  // Each cell stops as soon as its motion has settled on a periodic attractor
  // (AttractorRecorder::Settled with this remaining distance, relative); 0: always run
  // run.periods periods.
  double settle_remainder = 1e-9;
  // Labelling: solve each class's periodic orbit with the Poincaré solver, report its
  // multipliers and merge classes whose solved orbits coincide.
  bool solve_orbits = true;
  // Stable orbits a cell may stop at (see KnownOrbit); empty: none. Must be the same for every
  // cell, thread and process (e.g. from KnownOrbits below), so that the answer is too.
  std::vector<KnownOrbit> known;
  // Labelling: the Lyapunov exponents of each attractor and of the first not-periodic cell
  // (FoundAttractor::lyapunov, StudyResult::unresolved_lyapunov), when the scene's run.lyapunov
  // is on too and no stop is requested (an interrupted study has none).
  bool lyapunov = true;
};

// The stable orbits found by a pilot study on an 8 × 8 grid over the two coordinates (cells run
// until they settle; classes solved with the Poincaré solver): those whose solved orbit
// converged with all multipliers of modulus < 0.9, with the section points of their first cell's
// class over one period. Deterministic.
std::vector<KnownOrbit> KnownOrbits(const System& system, const Scene& scene, const Coordinate& a,
                                    const Coordinate& b, const StudyOptions& options);

// Simulates cells[i] for each i of `indices` (parallel over the indices; other cells untouched).
// A stop request leaves the cells not finished pending.
void RunCells(const System& system, const Scene& scene, const Coordinate& a, const Coordinate& b,
              const std::vector<std::pair<double, double>>& points,
              const std::vector<size_t>& indices, std::vector<CellResult>& cells,
              const StudyOptions& options);

// Groups the cells' attractors in cell order (equal attractors: same kind and period, sticking
// fraction and stick or impact phases within 1e-6), then (options.solve_orbits) solves each
// class's orbit from its first cell's final section point and merges classes whose solved
// orbits are equal attractors. Deterministic: depends only on `cells`.
StudyResult LabelCells(const System& system, const Scene& scene,
                       const std::vector<std::pair<double, double>>& points,
                       const std::vector<CellResult>& cells, const StudyOptions& options);

// KnownOrbits (unless options.known is given or settle_remainder is 0), RunCells over every
// point, then LabelCells.
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
// `record` stroboscopic points and the attractor of each run are kept. A run that fails
// (numerical failure, undetermined chattering) is the sweep's last point, with its status and
// message and no attractor; a run cut short by a stop request is not kept.
struct SweepPoint {
  double value;
  bool upward;
  Attractor attractor;
  std::vector<double> x_B, v_B;  // contact displacement and velocity at the last section points
  std::string status = "ok";     // the run's status (ToString(RunStatus))
  std::string message;           // why the run failed (status other than "ok")
  std::optional<LyapunovSpectrum> lyapunov;  // of the run (run.lyapunov), none for a failed run
  // The run's final modal state (the next run's start), at the forcing phase of initial.time;
  // empty for a failed run. A periodic attractor's orbit can be solved from it (`vibro diagram`).
  Eigen::VectorXd X, V;
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
