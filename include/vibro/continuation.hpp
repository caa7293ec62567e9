// One-parameter continuation of periodic orbits (paper §5, docs/model.md §5.6–§5.7): pseudo-arclength
// predictor–corrector on G(z, λ) = F(z; λ) − z, F the stroboscopic map of the Poincaré solver
// (analytic ∂F/∂z, central differences in λ since λ is any numeric scene key), with step-size
// control, so that folds are passed. The section sits at a fixed forcing phase inside a free
// flight and is moved to the middle of the longest flight when an event comes near it.
//
// Smooth bifurcations, located by bisection of the arclength on a test function (every trial
// point corrected onto the branch): fold (the λ-component of the tangent changes sign), flip (a
// real multiplier crosses −1), Neimark–Sacker (a complex pair crosses the unit circle).
// Non-smooth bifurcations (docs/model.md §5.7): the event sequence of the orbit over a period changes, or
// the orbit ceases to exist; the boundary is located by bisection of the arclength on "the
// corrected orbit has the same event sequence", and named by the quantity that vanishes there
// (orbit_probe.hpp): sticking-lost (a sticking phase shrinks to zero: the branch ends), rising
// (R gains a zero inside a sticking phase), sticking-entry (R vanishes at the landing), grazing
// (a free flight touches the stop tangentially), or "non-smooth" when none of them does. The
// branch goes on through the point when the orbit exists on the other side. A signature change
// that only regroups a chattering sequence is no bifurcation: it is kept in Branch::relabels.
#pragma once

#include <atomic>
#include <complex>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "vibro/loads.hpp"
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
  OrbitRequest orbit;        // how the first orbit is found (SolveOrbit, orbit_from_state.hpp)
  // Sticking fractions whose crossings along the branch are located (partitions, paper §5.4).
  std::vector<double> levels;
  const std::atomic<bool>* stop_requested = nullptr;  // polled between points
  std::function<void(size_t points, double value)> progress;
};

struct BranchPoint {
  double value = 0;
  Attractor summary;  // sticking fraction, stick phases, impacts per period
  std::vector<std::complex<double>> multipliers;
  bool stable = false;
  std::string signature;  // events over a period (orbit_probe.hpp: C, P, I, G, S, R)
  double x_B = 0;         // contact displacement at the section point
  double section_phase = 0;  // ωt0 of the section, mod 2π·period
  // The stroboscopic state: each contact's coordinate (w_jᵀq, the physical coordinate the
  // [[contact]] constrains; x_B for a [stop]) at t ≡ initial.time (mod period·T), the forcing
  // phase of a sweep's section points, whatever the section (docs/output.md). One per contact;
  // NaN when the period could not be simulated.
  std::vector<double> strobe;
  // The whole orbit, so that a point can be checked, restarted or plotted later:
  double section_time = 0;          // t0 of the section (a free state of the orbit)
  Eigen::VectorXd X, V;             // modal state at t0, (n)
  Eigen::VectorXd q, q_dot;         // physical DOFs at t0 (physical form; empty otherwise), (N)
  struct Impact {
    double phase;     // ωt mod 2π·period
    double v_before;  // contact velocity ẋ_B just before
    double v_after;   // and just after (−r·v_before)
    int contact = 0;  // the [[contact]] it hits (0 for the [stop])
  };
  std::vector<Impact> impacts;      // every impact of one period from t0, in time order
  // Several contacts (docs/contacts.md): the orbit's contact sequence ("0:impact 1:impact*3
  // 0:stick 0:release", OrbitResult::sequence); empty for one contact.
  std::string sequence;
  // The orbit's exact per-period contact loads (OrbitLoads, docs/loads.md), one entry per contact
  // in contact order (no intervals); empty, with loads_note saying why, when the period could not
  // be simulated. loads_note also names the contacts whose loads are unknown (NaN fields).
  std::vector<ContactLoads> loads;
  std::string loads_note;
  // A compliant stop (docs/compliant.md, "Along a continued branch"): every contact phase of the
  // orbit's period (q forcing periods) from its section, with its exact loads (certified peak force,
  // duration, penetration, impulse, dissipated energy; times absolute), as `vibro orbit` gives them;
  // empty for a rigid scene.
  std::vector<OrbitResult::ContactPhase> contact_phases;
  // The rigid model's orbit beside it (vibro/rigid_model.hpp, CompareOrbitWithRigid, filled by
  // AddRigidModelAlongBranch): the largest distance between the two orbits over the period; NaN when
  // not computed (a rigid scene) or when the rigid model's map has no orbit there.
  double rigid_distance = std::numeric_limits<double>::quiet_NaN();
};

// Per contact j < contacts, over a point's contact phases: the largest peak force, the longest
// duration (NaN where the contact has no phase) and the number of phases (docs/compliant.md).
struct ContactPhaseExtremes {
  std::vector<double> peak_force, duration;
  std::vector<int> phases;
};
ContactPhaseExtremes ExtremesOf(const std::vector<OrbitResult::ContactPhase>& phases, int contacts);

struct Bifurcation {
  // "fold" | "flip" | "neimark-sacker" | "branch-point" (a real multiplier crosses +1 where the
  // branch does not turn back: a pitchfork, e.g. where a symmetric orbit loses its symmetry) |
  // "rising" | "grazing" | "sticking-entry" | "sticking-lost" | "simultaneous" (two impacts on
  // different contacts meet) | "non-smooth" | "no-jacobian" (the orbit past it runs through an
  // event the map has no derivative at, e.g. a simultaneous impact of coupled contacts) |
  // "undetermined" (past it the precision cannot decide a chattering sequence, so where the
  // motion changes is not known; CVODE, or beyond quad)
  std::string kind;
  double value;
  std::string detail;
  double bracket = 0;  // width of the final λ bracket (the location's uncertainty)
  int contact = -1;    // the contact where a non-smooth point happens (several contacts), −1: none
  // A Neimark–Sacker point: θ/2π of its multipliers e^{±iθ}, θ ∈ (0, π), per period of the orbit
  // (`period` forcing periods); NaN for other kinds.
  double rotation_number = std::numeric_limits<double>::quiet_NaN();
  // A non-smooth point (grazing, sticking-lost, rising, …): the orbit's events per period
  // (orbit_probe.hpp signature) and, with several contacts, its contact sequence (the canonical
  // rotation, contact_sequence.hpp) before the point and past it; "after" is empty where no orbit
  // goes on. Empty for the smooth kinds.
  std::string events_before{}, events_after{}, sequence_before{}, sequence_after{};
  // How the branch went on through a non-smooth point: "" (it ended there), "past" (onto the
  // orbit on the other side), or "back" (a grazing fold: the orbit with the new impact exists on
  // the same side as the old one, and the branch turns back along it; docs/orbits.md).
  std::string through{};
  // A grazing the branch went through onto an orbit with a new low-velocity impact: that impact's
  // speed |ẋ⁻| at the first point past it, and that point's distance |λ − λ_g|. A grazing met from
  // the side of its slow impact (the impact dies out there): that impact's speed at the branch's
  // orbit nearest to the grazing, followed by the speed itself, and that orbit's distance |λ − λ_g|
  // (docs/orbits.md, "Through a grazing"). NaN otherwise.
  double new_impact_speed = std::numeric_limits<double>::quiet_NaN();
  double new_impact_distance = std::numeric_limits<double>::quiet_NaN();
  // The index in Branch::points of the branch's point next to it on the side the branch came from
  // (the orbit before it; −1: unknown). A branch that goes on through a grazing, or round a loop,
  // passes the same λ again on other orbits: the orbit of the bifurcation is this point's, not the
  // stored point nearest in λ (vibro prove --bifurcation BRANCH.h5 --point K, docs/prove.md).
  long long point = -1;
};

// A change of the branch's event signature that is bookkeeping, not a bifurcation: a chattering
// sequence regrouped (the impact where its tail of decreasing speeds starts moved by one, e.g.
// CR → CRI), the same events in the same order and no test quantity vanishing. Located like a
// non-smooth point; the branch goes on through it.
struct Relabel {
  double value;
  std::string from, to;  // the signatures before and after (orbit_probe.hpp)
  std::string detail;
  double bracket = 0;
};

// Where the sticking fraction crosses a requested level (located by bisection like the
// smooth bifurcations).
struct LevelCrossing {
  double level, value, bracket;
};

struct Branch {
  std::string status = "ok";  // "ok" | "no-orbit" | "interrupted"
  std::string param;          // the continued key (set by the caller, for output)
  int period = 0;
  std::vector<BranchPoint> points;
  std::vector<Bifurcation> bifurcations;
  std::vector<Relabel> relabels;  // signature changes that are no bifurcation
  std::vector<LevelCrossing> crossings;
  std::string end;  // why the branch stopped
  // The branch came back to its first point (the same orbit at the same λ, after it had gone
  // 1e-3 away from it): a closed loop, stored once; `end` starts with "closed loop".
  bool closed_loop = false;
  // Map evaluations done in quad precision because the double engine left a chattering sequence
  // undetermined there (near the end of a sticking branch; docs/chattering.md).
  int quad_evaluations = 0;
  // The branch met a corner of the map (TangentTracker::corner(): a simultaneous impact whose orders
  // of closing give different Jacobians, docs/contacts.md "Periodic orbits"): where (the first one
  // met, with its λ), and that the Newton steps, multipliers and bifurcations follow the first
  // order's piece. Empty when none was met.
  std::string corner;
};

Branch Continue(const ContinuationRequest& request);


// Two-parameter partition (paper §5.4, Figs. 9, 13, 17): for each value of the first parameter, the
// sticking branch is continued in the second, both ways from `start2`, over [lo2, hi2]; the
// crossings of the requested sticking-fraction levels and the bifurcations (its ends: the
// existence boundaries f_free-flight, f_sticking and their r > 0 counterparts, docs/model.md §6.3) are
// reported per column. Columns are independent and computed in parallel.
struct PartitionRequest {
  std::function<Scene(double, double)> scene_at;
  std::vector<double> values1;
  double start2 = 0, lo2 = 0, hi2 = 1;
  std::vector<double> levels;
  OrbitRequest orbit;
  double step = 0;
  int max_points = 2000;
  int threads = 0;
  const std::atomic<bool>* stop_requested = nullptr;
};
// A point of a column's branch (a cell of the partition plane): where it is, its orbit's
// sticking fraction and stability, and its exact per-period contact loads (as BranchPoint).
struct PartitionPoint {
  double value2 = 0;
  double sticking_fraction = 0;  // 0 for an orbit without sticking
  bool stable = false;
  std::vector<ContactLoads> loads;
  std::string loads_note;
};
struct PartitionColumn {
  double value1;
  // "ok" | "no-orbit" (no orbit of the kind at start2) | "invalid-scene" (the scene is not valid
  // there; end_down says why) | "interrupted"
  std::string status = "ok";
  std::vector<LevelCrossing> crossings;
  std::vector<Bifurcation> bifurcations;
  std::string end_down, end_up;  // why each half of the branch stopped
  // The branch points of the column in increasing arclength from the lower end (the down half
  // reversed, then the up half without its repeated start point).
  std::vector<PartitionPoint> points;
  // Several contacts (docs/contacts.md): the column's orbits classified by their contact sequence,
  // in increasing KEY2: each span [from, to] holds the branch points (from and to among them) whose
  // orbits have one sequence (contact_sequence.hpp: the same cyclic word); the change between two
  // spans lies between their ends. Empty for one contact.
  struct SequenceSpan {
    double from = 0, to = 0;
    std::string sequence;  // OrbitResult::sequence's format, from the section of the span's first point
  };
  std::vector<SequenceSpan> sequences;
};
std::vector<PartitionColumn> Partition(const PartitionRequest& request);

}  // namespace vibro
