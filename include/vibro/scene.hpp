// Scene: the plain description of one system, its initial state and how to run it
// (docs/scenes.md). Parsing from TOML lives in io/scene_file; this header knows no file format.
//
// Validate() checks every physical constraint and returns *all* problems found, each tied to
// the key path it concerns, so that the file layer can attach file:line:col to each.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "vibro/harmonics.hpp"

namespace vibro {

// One problem of a scene: the key it concerns (e.g. "stop.restitution", "structure.mass"),
// the offending value as the user wrote it (may be empty) and the violated constraint.
struct InputIssue {
  std::string key;
  std::string value;
  std::string constraint;
};

// Modal form of the structure (the paper's eigenbase, docs/model.md §1.2).
struct ModalStructureSpec {
  Eigen::VectorXd frequencies;  // ω_i > 0 [rad/time], shape (n)
  Eigen::VectorXd forcing;      // T_A,i, shape (n)
  Eigen::VectorXd contact;      // T_B,i > 0, shape (n)
};

// Physical form: M q̈ + K q = e_A F sin ωt + e_B R (docs/model.md §1.3).
struct PhysicalStructureSpec {
  Eigen::MatrixXd mass;       // symmetric positive definite, (N, N)
  Eigen::MatrixXd stiffness;  // symmetric positive definite, (N, N)
  int forcing_dof = 0;        // index of A in [0, N)
  int contact_dof = 0;        // index of B in [0, N)
};

// One rigid unilateral contact (docs/contacts.md): the gap g = σ (wᵀq − d) ≥ 0, σ = +1 for a stop
// below (wᵀq ≥ d), −1 above (wᵀq ≤ d). Physical form: w = e_dof (a stop on one DOF) or
// e_dof − e_partner (an impact pair: the gap is on q_dof − q_partner). Modal form: wᵀq = Σ_i a_i X_i
// with a = `modal` (docs/contacts_reference.md, "the modal form"); contact 0 has no `modal`: its
// components are σ_0 on every mode (the scaling, c_0 = σ_0 a_0 = 1).
enum class Side { kBelow, kAbove };
// When the body leaves a compliant stop (docs/compliant.md): "force" when the contact force
// λ = −k g − c ġ returns to zero (no pulling; the massless surface then relaxes back,
// y = y₀ e^(−kt/c)), "gap" when the gap returns to zero (the dashpot may pull).
enum class Separation { kForce, kGap };
// A compliant stop (docs/compliant.md): a linear spring–dashpot of stiffness k > 0 and damping
// c ≥ 0 on the gap: while in contact the contact carries λ = −k g − c ġ. stiffness = 0: rigid
// (the restitution law), the default.
struct Compliance {
  double stiffness = 0;  // k [force/length of the gap]; 0 = a rigid stop
  double damping = 0;    // c [force·time/length]
  Separation separation = Separation::kForce;
  bool compliant() const { return stiffness > 0; }
};
struct ContactSpec {
  int dof = 0;
  int partner = -1;  // −1: a stop on `dof`; else the other DOF of an impact pair
  Side side = Side::kBelow;
  double position = 0;     // d
  double restitution = 0;  // r ∈ [0, 1]
  // Modal form, contacts j ≥ 1: a_j,i = w_jᵀψ_i, one per listed mode (before truncation), shape (n);
  // empty for contact 0 and in the physical form.
  Eigen::VectorXd modal = {};
  Compliance compliance = {};  // rigid unless a stiffness is given
};

enum class Engine { kExact, kCvode };
enum class ChatterTreatment { kAccumulation, kThreshold, kNone };
enum class CvodeMethod { kAdams, kBdf };
// Scalar of the exact engine: double, or 113-bit quad (the reference engine).
enum class Precision { kDouble, kQuad };

struct RunSpec {
  long long periods = 200;          // forcing periods to simulate (≥ 1)
  Engine engine = Engine::kExact;
  double rtol = 1e-10;              // CVODE relative tolerance
  double atol = 1e-12;              // CVODE absolute tolerance
  CvodeMethod method = CvodeMethod::kAdams;
  double max_step = 0;              // CVODE maximum step (0 = no limit)
  long max_steps = 10000000;        // CVODE maximum internal steps per segment (one period at most)
  ChatterTreatment chatter = ChatterTreatment::kAccumulation;
  // "threshold": impacts are made plastic once |ẋ_B⁻| < chatter_switch · |ẋ_B⁻ of the first
  // impact of the sequence| (docs/model.md §5.4). Not used by "accumulation".
  double chatter_switch = 1e-6;
  // "accumulation": the accumulation point is predicted only when the estimated error of its time
  // is at most chatter_tolerance · T (docs/model.md §5.4); otherwise the next impact is followed.
  // 0 = the default of the precision: 1e-12 (double), 1e-28 (quad).
  double chatter_tolerance = 0;
  Precision precision = Precision::kDouble;
  int samples_per_period = 64;      // dense samples per forcing period (0 = none)
  int max_period = 32;              // largest period searched by the attractor classification
  double period_tolerance = 1e-7;   // relative tolerance on section points for periodicity
  bool lyapunov = true;             // Lyapunov exponents of the run (simulate; docs/model.md §5.8)
};

struct Scene {
  std::string title;
  // Exactly one of the two structure forms is set.
  std::optional<ModalStructureSpec> modal;
  std::optional<PhysicalStructureSpec> physical;
  Eigen::VectorXd damping_ratios;  // ζ_i, empty = undamped; one per mode (before truncation)
  int modes = 0;                   // modes kept (0 = all)

  double stop_position = 1.0;  // x0
  double restitution = 0.75;   // r
  Compliance stop_compliance;  // [stop] stiffness, damping, separation (rigid by default)
  // The [[contact]] tables, in file order. Empty: the one-contact [stop] shorthand (stop_position,
  // restitution, physical->contact_dof), which Contacts() returns as m = 1 in the physical form.
  std::vector<ContactSpec> contacts;

  double amplitude = 0.0;  // f
  double frequency = 1.0;  // ω
  // A sum of harmonics (docs/harmonics.md): every harmonic as written, when [excitation] gives
  // lists, a phase or forcing vectors; empty for today's f sin ωt. With harmonics, `frequency` is the
  // base pulsation ω_b of the common period (ω_h = n_h ω_b, the multiples found from the written
  // frequencies) and `amplitude` f_0; a change of either (a continuation parameter, --set) scales
  // every harmonic's frequency, or amplitude, by the same factor.
  std::vector<HarmonicSpec> harmonics;

  double initial_time = 0.0;
  // Initial displacement and velocity: modal coordinates (modal form) or physical DOFs (physical
  // form). Empty = the default state (static preload equilibrium on the stop, or the origin).
  Eigen::VectorXd initial_displacement;
  Eigen::VectorXd initial_velocity;

  RunSpec run;
};

// Every violated constraint of the scene (empty when valid). Includes the checks that need the
// structural model (positive definiteness, T_B,i > 0, admissible initial state).
std::vector<InputIssue> Validate(const Scene& scene);

// The contacts of a scene: its [[contact]] tables, or the [stop] as one contact below at
// physical->contact_dof. Empty for the modal form with [stop] (one contact, given by its modal data).
std::vector<ContactSpec> Contacts(const Scene& scene);
const char* ToString(Side s);
const char* ToString(Separation s);  // "force", "gap"
// Whether any contact of the scene is compliant.
bool HasCompliantContact(const Scene& scene);

const char* ToString(Engine e);
const char* ToString(ChatterTreatment c);
const char* ToString(CvodeMethod m);
const char* ToString(Precision p);
// run.chatter_tolerance with its default resolved.
double ChatterTolerance(const RunSpec& run);

}  // namespace vibro
