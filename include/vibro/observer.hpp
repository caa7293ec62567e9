// What a simulation reports as it goes: events, dense samples, stroboscopic section points and
// checkpoints (states from which a run can be resumed bit for bit). Observers are called from the
// simulating thread, in time order; they must not throw through the simulator unless they want
// the run to end with that exception.
#pragma once

#include <limits>

#include <cstdint>

#include <vector>

#include <Eigen/Dense>

namespace vibro {

enum class Mode : std::int8_t { kFree = 0, kSticking = 1 };

// docs/output.md enum values.
enum class EventKind : std::int8_t {
  kImpact = 1,        // x_B reaches x0 moving in; restitution (or plastic) reset
  kAccumulation = 2,  // predicted accumulation point of a chattering sequence (docs/model.md §5.4)
  kStick = 3,         // start of a sticking phase (after a plastic impact or an accumulation)
  kRelease = 4,       // R crosses zero going negative: the body leaves the stop
  kGrazing = 5,       // tangential touch of the stop (ẋ_B⁻ = 0): no impact
};

const char* ToString(EventKind kind);

// Time is kept as whole forcing periods since the start plus the time within the period, so that
// an event at period 10⁶ is located as accurately as one at period 1: t = t0 + period·T + offset.
struct Clock {
  long long period = 0;  // whole forcing periods since the start of the run
  double offset = 0.0;   // time since the start of that period, in [0, T)
};

struct EventCounts {
  long long impacts = 0, accumulations = 0, sticks = 0, releases = 0, grazings = 0;
  long long simultaneous = 0;  // impacts of two or more contacts at one instant (docs/contacts.md)
};

// Work done by a numerical integrator (CVODE engine; zero for the exact engine).
struct SolverStats {
  long long steps = 0, rhs_evals = 0, root_evals = 0, jac_evals = 0, error_test_failures = 0,
            reinits = 0;
};

struct Event {
  EventKind kind;
  Clock clock;
  double t;         // absolute time t0 + period·T + offset (for output; less accurate)
  double x_B;       // contact displacement at the event
  double v_before;  // ẋ_B just before (several contacts: the gap velocity ġ_j of the contact)
  double v_after;   // ẋ_B just after
  int contact = 0;  // 0-based index of the [[contact]] table (0 for the [stop])
  bool simultaneous = false;  // an impact of this contact together with another (impact LCP)
  // What the contact endures (docs/loads.md), in the physical units of the contact (the gap's
  // momentum: the effective mass m_j = 1/W_jj times a gap velocity; the paper's eq. (10)-(11) for
  // one stop, docs/contacts.md for several). impulse: P ≥ 0 of an impact (each contact's P_j of the impact LCP), the
  // summed tail of a chattering sequence for an accumulation, 0 otherwise. energy_dissipated:
  // ½(1 − r)P|v⁻| of an impact ((1 − r²) m v⁻²/2 for a single one), the tail's ½ m (v⁺)² for an
  // accumulation, 0 otherwise.
  double impulse = 0;
  double energy_dissipated = 0;
  // A release: the sticking phase it ends: its duration, ∫R dt over it (impulsive reactions the
  // held contact received from impacts elsewhere included) and max R (the paper's eq. (5)). NaN
  // for every other event, and for a phase begun before a resumed run without its loads; max R is
  // NaN for a phase held together with other contacts for a while (docs/loads.md).
  double stick_duration = std::numeric_limits<double>::quiet_NaN();
  double reaction_integral = std::numeric_limits<double>::quiet_NaN();
  double reaction_max = std::numeric_limits<double>::quiet_NaN();
  // A release that ends the contact phase of a compliant stop (docs/compliant.md): stick_duration is
  // the phase's duration, reaction_integral its impulse ∫λ dt, reaction_max its peak force, at
  // absolute time peak_time; penetration_max its largest penetration −g; energy_dissipated the
  // energy its dashpot dissipated (with the spring's ½k g² left at a force-rule exit). NaN otherwise.
  double peak_time = std::numeric_limits<double>::quiet_NaN();
  double penetration_max = std::numeric_limits<double>::quiet_NaN();
};

struct Sample {
  Clock clock;
  double t;
  const Eigen::VectorXd& X;  // modal displacements, (n)
  const Eigen::VectorXd& V;  // modal velocities, (n)
  double x_B;
  Mode mode;
  int held;  // how many contacts are held (0 in free flight; 1 sticking on one contact; −1: not known,
            // counted from the state by whoever needs it)
};

// Everything the automaton needs to continue a run exactly where it was (taken at period
// boundaries reached by the flow).
struct Checkpoint {
  Clock clock;
  Eigen::VectorXd X, V;
  Mode mode;
  double gap;                  // x_B − x0 as carried by the automaton (0 on the stop)
  int start_kind;              // how the next free flight starts (trivial roots to divide out)
  double chatter_first_speed;  // |ẋ_B⁻| of the first impact of the current sequence (0: none)
  double chatter_last_speed;   // |ẋ_B⁻| of the last impact
  long long sample_index;      // next dense-sample index
  EventCounts counts;          // events so far
  // The chattering treatment so far (RunResult::chatter), so that a resumed run reports the
  // whole run: sequences ended by a prediction, impacts followed, largest estimated error / T.
  long long chatter_predicted = 0, chatter_followed = 0;
  double chatter_max_error = 0;
  // Several contacts (docs/contacts.md): the contact of `mode`/`gap`/`start_kind` (held, or the
  // flight's start contact), every contact's gap and flight start, and the counts per contact.
  int contact = 0;
  std::vector<double> gaps;
  std::vector<int> start_kinds;
  std::vector<EventCounts> contact_counts;
  // Sticking on two or more contacts at once: the held contacts, ascending (empty otherwise).
  std::vector<int> held;
  // The open sticking phase of each contact (docs/loads.md): time held, ∫R dt and max R so far
  // (0, 0, NaN when not held), so that its release reports the whole phase after a resume and a
  // per-period account sees the reaction of a phase still open at a period boundary.
  std::vector<double> stick_duration, reaction_integral, reaction_max;
  // Compliant stops (docs/compliant.md), so that a resumed run goes on as the run that went through:
  // the open contact phase's account, 4 per contact (peak force, its time, largest penetration,
  // dissipated energy so far; empty when the scene has no compliant stop), and the relaxing flight
  // after a force-rule exit (its contact, −1: none, and the surface's offset y at the checkpoint).
  std::vector<double> compliant_account;
  int relax_contact = -1;
  double relax_surface = 0;
};

// For analyses that differentiate the hybrid flow (the Poincaré solver): every smooth stretch and
// every reset of the trajectory, in time order. States are modal (X, Ẋ); phase = ωt at the reset.
struct Stretch {
  Mode mode;
  double duration;
  int contact = 0;  // sticking: the held contact (0-based [[contact]] order; 0 for the [stop])
  // Sticking on two or more contacts at once: the held set (sorted); null or empty otherwise.
  const std::vector<int>* held = nullptr;
};
enum class ResetKind {
  kImpact,         // restitution law (12), free → free
  kPlasticStick,   // plastic impact (or tangential arrival) into sticking: Ẋ ← ΠẊ
  kPlasticLeave,   // r = 0 impact with R < 0: Ẋ ← ΠẊ, free → free (departure at zero velocity)
  kRelease,        // sticking → free at R = 0 (no jump: the saltation is the identity)
  kAccumulation,   // docs/model.md §5.4: free flight over `delta` from the post-impact state, projection
  kGrazing,        // tangential touch that stays free (the maps are singular there)
  kHeldSet,        // two or more contacts held at once, entered or left (docs/contacts.md): see HeldSetCause
  // A compliant stop (docs/compliant.md): no jump at either (the state is continuous), the flow
  // changes. Entry: the gap to the stop's surface reaches 0 closing (contact_velocity_before is its
  // rate ḋ = ġ − ẏ; `surface` the surface's offset y there, 0 unless it still relaxed, `relaxing`
  // whether it did). Exit: the separation rule's surface (rule "gap": g = 0; rule "force": λ = 0);
  // `relaxing`: a force-rule exit inside the stop, the surface left at `surface` = g < 0.
  kCompliantEntry,
  kCompliantExit,
};
// What a kHeldSet reset is (docs/contacts.md, "Periodic orbits"): the entry into the acceleration
// LCP after a plastic landing beside a held contact (no jump: the impact was its own kImpact
// reset), a release from a held set (no jump), an impact while a set is held (the impact LCP:
// V_before → V_after, `contact` the impacting one), a chattering tail's accumulation onto a set,
// a tangential arrival beside held contacts, or contacts left at rest by a simultaneous impact.
enum class HeldSetCause { kEntry, kRelease, kImpact, kAccumulation, kGrazing, kSimultaneous };
struct Reset {
  ResetKind kind;
  double phase;
  const Eigen::VectorXd& X_before;  // kAccumulation: the state just after the last impact
  const Eigen::VectorXd& V_before;
  const Eigen::VectorXd& X_after;
  const Eigen::VectorXd& V_after;
  double delta;                     // kAccumulation: Δ∞
  double reaction;                  // kAccumulation: R used in Δ∞
  // kAccumulation: ∂Δ∞/∂(X, Ẋ) at the post-impact state (2n), and the free state at t∞⁻ before
  // the projection onto the stop, so that the Jacobian of the jump is that of the jump taken.
  const Eigen::VectorXd* delta_gradient = nullptr;
  const Eigen::VectorXd* X_end = nullptr;
  const Eigen::VectorXd* V_end = nullptr;
  // ẋ_B just before the reset, computed in the run's precision (a quad run's chattering impacts
  // reach speeds that the double state V_before cannot resolve); NaN when not given.
  double contact_velocity_before = std::numeric_limits<double>::quiet_NaN();
  // Several contacts (docs/contacts.md): the contact of the reset (the impacting one, also while
  // another sticks; the one entering or leaving sticking; the released one), and whether it is an
  // impact of two or more contacts at one instant (impact LCP; `contact` is then the first of them).
  int contact = 0;
  bool simultaneous = false;
  HeldSetCause cause = HeldSetCause::kEntry;  // kHeldSet only
  double surface = 0;     // kCompliantEntry / kCompliantExit: the relaxing surface's offset y
  bool relaxing = false;  // kCompliantEntry: a re-contact of a relaxing surface; exit: it relaxes after
};

class Observer {
 public:
  virtual ~Observer() = default;
  virtual void OnEvent(const Event& /*event*/) {}
  virtual void OnSample(const Sample& /*sample*/) {}
  // Stroboscopic section: t = t0 + k T, k = 0, 1, ... (the initial state is row 0).
  virtual void OnSection(const Sample& /*sample*/) {}
  virtual void OnCheckpoint(const Checkpoint& /*checkpoint*/) {}
  virtual void OnStretch(const Stretch& /*stretch*/) {}
  virtual void OnReset(const Reset& /*reset*/) {}
  // Whether this observer reads OnReset. The automaton builds a reset (copies of the states, and
  // for a predicted accumulation the gradient of its jump time, docs/model.md §5.6) only when at
  // least one of its observers wants it: an observer that ignores resets says false.
  virtual bool WantsResets() const { return true; }
};

}  // namespace vibro
