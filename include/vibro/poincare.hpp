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

// Why an orbit through a simultaneous impact of coupled contacts has no multipliers (the map is
// discontinuous there, docs/contacts.md "Periodic orbits"): TangentTracker::undefined() says
// this, after "the orbit passes through ".
inline constexpr char kCoupledSimultaneousImpact[] =
    "a simultaneous impact of coupled contacts: the map has no Jacobian there";

// Accumulates DF along a simulated trajectory (an Observer of Simulate). Free flights and
// impacts, most of a run, are applied in closed form without allocating (per-mode 2 × 2 flow
// blocks, rank-one saltation updates), so that the Lyapunov observer can follow every period.
//
// Several contacts (docs/contacts.md, "Periodic orbits"): each reset carries its contact j, and
// each of the single stop's saltations holds with that contact's c_j, T_j, W_jj, r_j (an impact:
// Π_j = I − (1 + r_j) T_j c_jᵀ/W_jj, det = r_j²); a sticking stretch follows the flow constrained
// by the held contact; an impact of contact k while contact h sticks uses the 2 × 2 impact law
// on {h, k} with its pattern fixed (h stays: both impulses; h pushed off: k's alone); impacts of
// contacts at one instant (in free flight or beside held contacts, plastic or not) are the product
// of their saltations taken one after the other when W_jk = 0 and every order gives the same product
// (else the map has a corner there: corner()), and leave the map without a Jacobian when W_jk ≠ 0
// (the map is discontinuous there).
class TangentTracker final : public Observer {
 public:
  explicit TangentTracker(const System& system);
  void OnStretch(const Stretch& s) override;
  void OnReset(const Reset& r) override;
  const Eigen::MatrixXd& jacobian() const { return phi_; }  // ∂z(t)/∂z(t0) · start, (2n, k)
  bool singular() const { return singular_; }               // a grazing on the way
  // Why the map has no Jacobian along the way (a simultaneous impact of coupled contacts, or an
  // event whose saltation is not implemented); empty when DF exists. Kept across Restart.
  const std::string& undefined() const { return undefined_; }
  // A simultaneous impact at a corner of the map (docs/contacts.md, "Periodic orbits"): the orders in
  // which a perturbation closes the gaps give different Jacobians, one piece each. The product follows
  // the first order (piece 0) or the last (piece 1); corner() says where (empty: no corner met).
  void SetCornerPiece(int piece) { piece_ = piece; }
  const std::string& corner() const { return corner_; }
  // A compliant stop's surface still relaxing at the end of the run (after a force-rule exit): its
  // contact (−1: none) and offset y; the map's state (X, Ẋ) does not hold it.
  int relaxing_contact() const { return relax_contact_; }
  double relaxing_surface() const { return relax_y_; }
  // Starts the product again from `start` (2n rows; the identity for DF itself): the Lyapunov
  // observer carries its orthonormal frame this way.
  void Restart(const Eigen::MatrixXd& start);

 private:
  // What the saltations of one contact need (docs/contacts.md notation: c_j, T_j, W_jj, r_j).
  struct ContactTangent {
    Eigen::VectorXd c, T;
    double e = 0, s = 0, r = 0;
    Eigen::MatrixXd Pi;       // plastic projection I − T_j c_jᵀ/W_jj, (n, n)
    Eigen::MatrixXd G_stick;  // first-order matrix of the flow with contact j held, (2n, 2n)
    // The held flow's exp(G s) in closed form (undamped: HeldFlight), from the constrained modes
    // of docs/model.md §4.2: v_0 = static_shape, V = [v_k] (n, n−1), L = [l_kᵀ] (n−1, n), ω'_k.
    bool closed_form = false;
    Eigen::VectorXd v0, nu;
    Eigen::MatrixXd V, L;
    // A compliant stop (docs/compliant.md, "Periodic orbits"): its stiffness k and damping c, whether
    // it leaves at g = 0 (rule "gap", or no dashpot) rather than at λ = 0, and the first-order matrix
    // of its contact phase's flow, G_c = [[0, I], [−(Ω + k T cᵀ), −(D + c T cᵀ)]].
    bool compliant = false, gap_exit = false;
    double stiffness = 0, damping = 0;
    // G_c balanced, D G_c D⁻¹ with D = diag(w I, I), w = √‖Ω + k T cᵀ‖∞: exp(G_c s) = D⁻¹ exp(D G_c D⁻¹ s) D,
    // so that the exponential's normwise accuracy holds entry by entry (a stiff stop: ω_c s ~ π
    // while the position-from-velocity entries are ~1/ω_c).
    Eigen::MatrixXd G_contact;
    double balance = 1;
  };
  // A compliant contact's entry and exit (docs/compliant.md, eqs. (C3)-(C6)), the relaxing
  // surface's variation, and the check that the crossing is transversal (else: a grazing).
  void CompliantEntry(const Reset& r);
  void CompliantExit(const Reset& r);
  Eigen::VectorXd Field(Mode mode, const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                        double phase, int contact = 0) const;
  void FreeFlight(double duration, Eigen::MatrixXd& m) const;
  void HeldFlight(const ContactTangent& ct, double duration);  // phi_ ← exp(G_stick s) phi_
  void Impact(const Reset& r, int contact);
  // S = ∂g + (f⁺ − ∂g f⁻) ∇hᵀ/(∇h·f⁻), ∂g = diag(I, dV), ∇h = (c_k, 0), applied to the product.
  void Saltation(const Eigen::MatrixXd& dV, const Eigen::VectorXd& f_minus,
                 const Eigen::VectorXd& f_plus, const Eigen::VectorXd& c, double denom);
  void ImpactWhileHeld(const Reset& r);
  // Contacts Z closing at one instant (in free flight, or while the contacts H are held): the
  // composite saltation, taken when the next stretch names the flow after (ResolveSimultaneous).
  void SimultaneousImpact(const Reset& r, std::vector<int> Z, std::vector<int> H);
  struct PendingSimultaneous {
    bool active = false;
    std::vector<int> Z, H;  // the contacts closing, the contacts held before
    Eigen::VectorXd X, V_before, V_after;
    double phase = 0;
  };
  PendingSimultaneous pending_sim_;
  int piece_ = 0;
  std::string corner_;
  void ResolveSimultaneous(const std::vector<int>& after);
  std::vector<int> HeldNow() const;  // the contacts the tracker follows held now
  std::vector<int> AtZeroGap(const Reset& r, const std::vector<int>& H) const;
  // The composite saltation of the impacts of `order` taken one after the other at one instant
  // from the held set H, ending on the flow held on `after`; false (with `why`) where the impact
  // law's pattern or the contact-force LCP between them is not the one the tangent map follows.
  bool SequenceSaltation(const std::vector<int>& order, const std::vector<int>& after, Eigen::MatrixXd& M,
                         Eigen::VectorXd& V_end, std::string& why) const;
  // Several contacts held at once (docs/contacts.md, "Periodic orbits"): the flow constrained to
  // the set S, G_S = [[0, I], [−P_S Ω, −P_S D]] with P_S = I − T_S W_SS⁻¹ C_S (cached per set).
  const Eigen::MatrixXd& SetFlow(const std::vector<int>& set);
  Eigen::MatrixXd SetProjection(const std::vector<int>& set) const;  // P_S, (n, n)
  void ImpactWhileSetHeld(const Reset& r);
  // phi_ ← diag(P, P) phi_ with P the plastic projection of the contact(s) held now: directions off
  // the held manifold collapse (a run or a Lyapunov frame that starts held, several contacts).
  void CollapseOffHeld();
  // A saltation whose flow after is the one the run follows next (the acceleration LCP decides it
  // after the reset): S is applied when the next stretch (or reset) says which flow that is.
  struct PendingSaltation {
    bool active = false;
    Eigen::MatrixXd dV;
    Eigen::VectorXd f_minus, c, X, V;
    double denom = 0, phase = 0;
    // The flow held before the impact (held_, and held_set_ when it is kSet): a chattering tail
    // beside it starts at this instant on that flow (HeldAccumulation).
    int held_before = -2;
    std::vector<int> set_before;
  };
  // A chattering tail at contact k accumulating beside the held set S (docs/contacts.md, "Periodic
  // orbits"): the jump L from the post-impact state, D L = diag(P_Z, P_Z)(Φ_S(Δ∞) + f_S(t∞⁻)∇Δ∞ᵀ)
  // − f⁺(t∞)∇Δ∞ᵀ on Z = S ∪ {k}; the last term waits for the flow after (the acceleration LCP's).
  void HeldAccumulation(const Reset& r);
  struct PendingJumpTime {
    bool active = false;
    Eigen::RowVectorXd grad_phi;  // ∇Δ∞ᵀ Φ at the post-impact state
    Eigen::VectorXd X, V;
    double phase = 0;
  };
  PendingJumpTime pending_jump_;
  // The flow held on `set` over `duration` (one contact: its closed form when it has one).
  void HeldSetFlight(const std::vector<int>& set, double duration);
  Eigen::VectorXd SetField(const std::vector<int>& set, const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                           double phase) const;
  void Defer(const Eigen::MatrixXd& dV, const Eigen::VectorXd& f_minus, const Eigen::VectorXd& c,
             double denom, const Eigen::VectorXd& X, const Eigen::VectorXd& V, double phase);
  void Resolve(Mode mode, int contact, const std::vector<int>* set);
  Eigen::VectorXd HeldField(const Eigen::VectorXd& X, const Eigen::VectorXd& V, double phase);
  double Coupling(int j, int k) const;  // W_jk, 0 within the rounding of the mode shapes
  void Undefined(std::string why);
  const System& sys_;
  std::vector<ContactTangent> contacts_;
  Eigen::MatrixXd phi_;
  Eigen::VectorXd w2_, D_;                  // ω_i², 2ζ_iω_i
  Eigen::VectorXd du_, dv_;                 // the impact saltation's column: work space, (n)
  Eigen::VectorXd xi_, eta_, held_c_, held_s_;  // HeldFlight's work space, (n − 1)
  Eigen::VectorXd salt_u_, salt_v_;         // Saltation's work space, (2n) and (n)
  bool singular_ = false;
  std::string undefined_;
  // Several contacts: the contact the run sticks on, −1 in free flight, −2 before the first stretch
  // (or after a change of held set, which the next stretch names), kSet while held_set_ is held.
  static constexpr int kSet = -3;
  int held_ = -2;
  std::vector<int> held_set_;
  std::vector<std::pair<std::vector<int>, Eigen::MatrixXd>> set_flows_;
  PendingSaltation pending_;
  // Compliant stops: the contact in a contact phase (−1: none); the contact whose surface relaxes
  // after a force-rule exit (−1: none), the surface's offset y and its variation δy = dy_ δz(t0).
  int compliant_ = -1, relax_contact_ = -1;
  double relax_y_ = 0;
  Eigen::RowVectorXd dy_;
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
  // A scene with [[contact]] tables (docs/contacts.md, "Periodic orbits"): the orbit's contact
  // sequence over its q periods, e.g. "0:impact 1:impact 0:stick 0:release" (a run of k equal
  // entries is written once with "*k"; "0+1:impact" is a simultaneous impact), in its canonical
  // rotation (contact_sequence.hpp), not necessarily from the section; empty for a [stop].
  std::string sequence;
  // Why the orbit has no Jacobian, so no multipliers (e.g. "the orbit passes through a
  // simultaneous impact of coupled contacts: the map has no Jacobian there"); empty when it has one.
  std::string no_jacobian;
  // The contact phases of compliant stops over the orbit's q periods (docs/compliant.md, "Periodic
  // orbits"), in order from the section: each phase's exact loads, as its release event carries
  // them (entry and exit in absolute time from the section time).
  struct ContactPhase {
    int contact = 0;
    double entry = 0, exit = 0, duration = 0;
    double entry_velocity = 0, exit_velocity = 0;  // ḋ at the entry, ġ at the exit
    double peak_force = 0, peak_time = 0, penetration = 0, impulse = 0, dissipated = 0;
  };
  std::vector<ContactPhase> contact_phases;
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

// The orbit reported from the start of its contact sequence's canonical rotation
// (contact_sequence.hpp; docs/orbits.md, "Where the orbit's listing starts"): when its events from
// its section do not read in that rotation, the section moves along the orbit to the middle of the
// free flight just before the rotation's first event, Newton
// polishes the point there (F(z) − z is evaluated anew, usually 0 iterations; newton_iterations
// adds them) and the orbit is characterized again, so that section_time, X, V, the monodromy, the
// summary's impacts, the contact phases and every listing of its events start there. Nothing
// changes when the orbit has no contact sequence (a [stop]), when its events already read in the
// canonical rotation (an orbit of one contact with impacts only), or when the move fails (a
// stretch shorter than 2^-14 T or not free, or Newton or the characterization differing there): the
// orbit is then kept as found. Called where an orbit is reported as such: `vibro orbit` and
// vibro.orbit (not by prove, continuation or check, which keep their own sections).
void StartAtCanonicalRotation(const System& system, const Scene& scene, const OrbitRequest& request,
                              OrbitResult& orbit);

// One evaluation of the stroboscopic map: z(t0) ↦ z(t0 + q T) and DF.
// The segment budget (SimulationOptions::max_segments) of the runs that evaluate an orbit over its
// periods — the map, the orbit's characterization and probes, the continuation's impacts and
// strobes: per forcing period, far above any orbit's events (a chattering sequence's followed
// impacts included), so that exhausting it is a failed evaluation, never an endless run.
inline constexpr long long kMapSegmentsPerPeriod = 100000;

struct MapValue {
  Eigen::VectorXd X, V;
  Eigen::MatrixXd jacobian;
  bool singular = false;
  std::string undefined;  // TangentTracker::undefined(): why DF does not exist (empty: it does)
  RunStatus status = RunStatus::kOk;
  std::string corner;     // TangentTracker::corner(): the map has pieces there, `jacobian` is piece `piece`'s
};
MapValue StroboscopicMap(const System& system, const Scene& scene, double t0,
                         const Eigen::VectorXd& X, const Eigen::VectorXd& V, int q, int piece = 0);
// The flow over half of q periods (q odd), from (X, V) at t0 to t0 + qT/2, with its derivative:
// for a mirror-symmetric model (mirror_symmetry.hpp) a symmetric orbit is a fixed point of
// z ↦ −Φ_{qT/2}(z), whose half period holds one impact of each mirror pair (docs/orbits.md,
// "Through a grazing").
MapValue HalfPeriodFlow(const System& system, const Scene& scene, double t0, const Eigen::VectorXd& X,
                        const Eigen::VectorXd& V, int q);

}  // namespace vibro
