// The rigid model beside a compliant one (docs/compliant.md, "The rigid model beside it"): the
// same scene with every compliant stop made rigid, of the restitution its damping gives an
// isolated impact under its separation rule, run beside it; the distance between the two
// trajectories and between their loads. The distance falls like k^(−1/2) with the stiffness
// (docs/loads.md, "The distance to the rigid model").
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "vibro/continuation.hpp"
#include "vibro/loads.hpp"
#include "vibro/poincare.hpp"
#include "vibro/scene.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace vibro {

// The restitution of an isolated impact on a spring–dashpot of damping ratio ζ = c/(2√(k m)):
// rule "gap" e = exp(−ζπ/√(1−ζ²)); rule "force" (Schwager & Pöschel) e = exp(−ζω₀ t_c) with
// ω_d t_c = π − atan2(2ζ√(1−ζ²), 1 − 2ζ²). ζ ≥ 1: 0 under "gap" (the body never comes back
// above the stop's surface with the dashpot holding it), and, under "force", the overdamped closed
// form's force zero (std::nan when there is none: the body stays).
double EquivalentRestitution(double zeta, Separation rule);

// Per contact: its damping ratio ζ_j = c_j/(2√(k_j m_j)), m_j = 1/W_jj the contact's effective
// mass (NaN for a rigid contact), and the restitution the rigid model gives it.
struct RigidEquivalent {
  Scene scene;                      // the rigid scene
  std::vector<double> zeta, restitution;
};
// Throws std::invalid_argument when the scene has no compliant stop.
RigidEquivalent RigidModelOf(const Scene& scene, const System& system);

struct RigidComparison {
  RigidEquivalent rigid;
  RunResult compliant_result, rigid_result;
  LoadsSummary compliant_loads, rigid_loads;
  // The largest distance between the two trajectories over the dense samples of the run (the
  // physical DOFs in the physical form, the modal coordinates in the modal form, max norm), the
  // time where it is reached, and the distance at the end of the run.
  double distance = 0, distance_time = 0, end_distance = 0;
  long long samples = 0;
  // Per contact of the compliant scene: its phases' largest peak force, mean peak force, mean
  // duration (over the phases ended in the run; NaN without any), count of phases.
  std::vector<double> peak_force_max, peak_force_mean, duration_mean;
  std::vector<long long> phases;
};
// Runs both (scene.run as given; dense samples at run.samples_per_period, at least 64).
RigidComparison CompareWithRigid(const Scene& scene, int blocks);
// The comparison as JSON (docs/compliant.md lists its keys).
std::string RigidComparisonJson(const RigidComparison& c);

// The rigid model's orbit beside a compliant orbit (docs/compliant.md, "Periodic orbits"): Newton on
// the rigid scene's stroboscopic map at the compliant orbit's section time, from its section state,
// over the same q periods; its multipliers, both orbits' exact per-period loads, and the largest
// distance between the two orbits over the q periods (dense samples at the same instants; physical
// DOFs in the physical form, modal coordinates in the modal form, max norm).
struct RigidOrbitComparison {
  RigidEquivalent rigid;
  OrbitResult orbit;  // the rigid model's orbit (status "converged" or not, and why)
  LoadsSummary compliant_loads, rigid_loads;
  double distance = std::numeric_limits<double>::quiet_NaN();       // over the q periods
  double distance_time = std::numeric_limits<double>::quiet_NaN();  // where it is reached
  double section_distance = std::numeric_limits<double>::quiet_NaN();  // at the section
};
// Newton on the rigid model's map starts from the compliant orbit's section state, or from `start`
// (positions then velocities at orbit.section_time) when given.
RigidOrbitComparison CompareOrbitWithRigid(const Scene& scene, const System& system, const OrbitResult& orbit,
                                           const OrbitRequest& request, const Eigen::VectorXd* start = nullptr);
std::string RigidOrbitJson(const RigidOrbitComparison& c);

// Along a continued branch of a compliant scene (docs/compliant.md, "Along a continued branch"): at
// every point the rigid model's orbit beside the point's orbit (CompareOrbitWithRigid, the scene at
// the point's value from `scene_at`), its largest distance in BranchPoint::rigid_distance. Beside:
// an impact orbit with one impact per contact phase of the point's orbit on each contact, each
// impact within its phase widened by the phase's duration on either side, in time over the orbit's
// q periods (not modulo one forcing period: the orbit's images under the one-period map, a period
// away, have their impacts at the same forcing phases). Newton starts from the point's section
// state and, from the second point on, also from the rigid orbit beside the last point that had one
// (followed along the branch: the rigid map may have several orbits that pass, and Newton from the
// compliant state alone may reach another one); an impact orbit reached that is not beside is also
// taken at the section 1, …, q − 1 periods later (its images, fixed points of the q-period map too);
// of the orbits beside the point the nearest is taken. NaN where neither start reaches one beside it (no orbit from there, or
// another orbit, near a bifurcation of either model). Polls
// `stop_requested` between points (the points not reached keep NaN). A rigid scene: nothing done.
void AddRigidModelAlongBranch(Branch& branch, const std::function<Scene(double)>& scene_at,
                              const OrbitRequest& request, const std::atomic<bool>* stop_requested = nullptr);

}  // namespace vibro
