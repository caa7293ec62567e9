// Periodic orbits and their stability (docs/model.md §5): fixed points of the stroboscopic map
// F: z(t0) ↦ z(t0 + qT) of the hybrid flow, found by Newton with the analytic Jacobian DF.
//
// DF is the product, along the orbit, of the closed-form flow Jacobians exp(G s) (free flight:
// G = [[0, I], [−Ω, −D]]; sticking: G = [[0, I], [−A, −ΠD]], docs/model.md §4.2, §7) and the saltation
// matrices of the resets (docs/model.md §5.6): impacts, plastic entries and departures, releases
// (identity), and the accumulation map L of a chattering tail (docs/model.md §5.4, differentiated through
// Δ∞). Its non-zero spectrum is that of DP, the paper's Poincaré map P = G∘H2∘F^∞∘H1 (docs/model.md §5.6:
// sticking collapses x_B and ẋ_B, so DF has two zero eigenvalues on a sticking orbit): the Floquet
// multipliers. The section phase is taken inside a free flight of the orbit, so the unknowns are
// the 2n components of a free state and every Newton iterate stays admissible.
#pragma once

#include <complex>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "vibro/attractor.hpp"
#include "vibro/observer.hpp"
#include "vibro/scene.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace vibro {

// Accumulates DF along a simulated trajectory (an Observer of Simulate). Free flights and
// impacts, most of a run, are applied in closed form without allocating (per-mode 2 × 2 flow
// blocks, rank-one saltation updates), so that the Lyapunov observer can follow every period.
class TangentTracker final : public Observer {
 public:
  explicit TangentTracker(const System& system);
  void OnStretch(const Stretch& s) override;
  void OnReset(const Reset& r) override;
  const Eigen::MatrixXd& jacobian() const { return phi_; }  // ∂z(t)/∂z(t0) · start, (2n, k)
  bool singular() const { return singular_; }               // a grazing on the way
  // Starts the product again from `start` (2n rows; the identity for DF itself): the Lyapunov
  // observer carries its orthonormal frame this way.
  void Restart(const Eigen::MatrixXd& start);

 private:
  Eigen::VectorXd Field(Mode mode, const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                        double phase) const;
  void FreeFlight(double duration, Eigen::MatrixXd& m) const;
  void Impact(const Reset& r);
  const System& sys_;
  Eigen::MatrixXd G_free_, G_stick_, Pi_, phi_;
  Eigen::VectorXd w2_, D_;                  // ω_i², 2ζ_iω_i
  Eigen::VectorXd du_, dv_;                 // the impact saltation's column: work space, (n)
  bool singular_ = false;
};

// kAuto: the kind of the orbit found (of the attractor after a transient, or of the orbit through
// the start state); FindOrbit takes kSticking or kImpact only, SolveOrbit (orbit_from_state.hpp)
// all three.
enum class OrbitKind { kSticking, kImpact, kAuto };

struct OrbitRequest {
  OrbitKind kind = OrbitKind::kSticking;
  int period = 0;                 // forcing periods q; 0 = from the transient's attractor
  int impacts = 0;                // impact orbits: impacts per period (0 = any)
  std::optional<double> guess_phase;     // ωt of the release (sticking) or first impact
  std::optional<double> guess_velocity;  // contact velocity just after it
  std::optional<InitialOverride> start;  // or: the transient starts from this state (studies)
  int transient_periods = 200;
  int max_iterations = 40;
  double tolerance = 1e-12;       // on |F(z) − z|∞ relative to 1 + |z|∞
};

struct OrbitResult {
  std::string status = "not-converged";  // "converged" | "not-converged" | "no-orbit"
  std::string message;
  int period = 0;
  int newton_iterations = 0;
  double residual = 0;
  double section_time = 0;  // t0 of the section point below
  Eigen::VectorXd X, V;     // a point of the orbit (modal), in free flight
  Eigen::MatrixXd monodromy;                          // DF, (2n, 2n)
  std::vector<std::complex<double>> multipliers;      // eigenvalues of DP
  bool stable = false;
  Attractor summary;  // kind, sticking fraction, phases, impacts over one period of the orbit
  // |z_start − z_orbit|∞ / (1 + |z_orbit|∞) in the start's own time frame (orbit_from_state.hpp);
  // none when no orbit converged.
  std::optional<double> distance_from_start;
  std::string reached;  // no-orbit after a transient: the kind of attractor it reached
  // no-orbit because the simulation from the start was undetermined (a chattering sequence that
  // cannot be decided at the run's precision): nothing is known of an orbit there.
  bool undetermined = false;
  // Map evaluations and orbit simulations redone in quad precision because double left a
  // chattering sequence undetermined (exact engine, near the end of a sticking branch).
  int quad_evaluations = 0;
};

OrbitResult FindOrbit(const System& system, const Scene& scene, const OrbitRequest& request);

// Newton on the stroboscopic map F(z) − z from z = (X, Ẋ) at the section time t0 over q periods,
// with the analytic DF: fills status ("converged" or not), message, residual, newton_iterations,
// section_time, X, V and monodromy of `orbit`.
void NewtonOnStroboscopicMap(const System& system, const Scene& scene, double t0, Eigen::VectorXd z,
                             int q, const OrbitRequest& request, OrbitResult& orbit);

// Fills summary, multipliers and stability of `orbit` from its section point, period and
// monodromy matrix (simulates three periods of the orbit).
void Characterize(const System& system, const Scene& scene, OrbitResult& orbit);

// One evaluation of the stroboscopic map: z(t0) ↦ z(t0 + q T) and DF.
struct MapValue {
  Eigen::VectorXd X, V;
  Eigen::MatrixXd jacobian;
  bool singular = false;
  RunStatus status = RunStatus::kOk;
};
MapValue StroboscopicMap(const System& system, const Scene& scene, double t0,
                         const Eigen::VectorXd& X, const Eigen::VectorXd& V, int q);

}  // namespace vibro
