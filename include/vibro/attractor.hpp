// Attractor classification of a simulated run (docs/cli.md, docs/output.md `attractor` block): from the
// stroboscopic section and the event log of the final periods.
#pragma once

#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vibro/block_recycler.hpp"
#include "vibro/observer.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro {

// Whether an attractor kind holds a contact over a phase of each period: "sticking-periodic" (a
// rigid stop's sticking) or "contact-periodic" (compliant stops' contact phases). The orbit solver's
// OrbitKind::kSticking finds both.
inline bool HoldsContact(const std::string& kind) { return kind == "sticking-periodic" || kind == "contact-periodic"; }

struct Attractor {
  // "sticking-periodic" | "contact-periodic" | "impact-periodic" | "no-contact-periodic" |
  // "permanent-contact" | "not-periodic". "contact-periodic": every phase held on a contact is a
  // contact phase of a compliant stop (docs/compliant.md), which is neither an impact nor sticking;
  // stick_phases then lists the contact phases and sticking_fraction is the fraction of time in
  // contact.
  std::string kind = "not-periodic";
  std::optional<int> period;                   // forcing periods; none when not periodic
  std::optional<long long> impacts_per_period;  // none when a period holds a chattering sequence
  // Time on the stop per period / period length. For "not-periodic": the average over the
  // analysed window (the last max_period periods).
  std::optional<double> sticking_fraction;
  // "not-periodic" on a scene whose every contact is a compliant stop: sticking_fraction is then
  // the fraction of time in a contact phase (there is no sticking), as for "contact-periodic".
  bool contact_fraction = false;
  // Sticking phases [start, end] as ωt mod 2π·period (start = accumulation point or plastic
  // impact, end = release); end = start + ω·duration, so end may exceed 2π·period when a phase
  // wraps. Sorted by start.
  std::vector<std::pair<double, double>> stick_phases;
  // The contact (0-based [[contact]] index; 0 for the [stop]) of each sticking phase.
  std::vector<int> stick_contacts;
  // Contact velocity just before each impact of one period (several contacts: the gap velocity
  // ġ_j), the phases of the impacts and their contacts, in the order they happen (impact-periodic
  // orbits).
  std::vector<double> impact_phases, impact_velocities;
  std::vector<int> impact_contacts;
  // "not-periodic" from a recorder: the longest period p the classification tried (run.max_period,
  // or less on a record shorter than 3p + 1 periods), so that no period is claimed beyond it.
  std::optional<int> searched_period;
  // "not-periodic", when the record allows: the stroboscopic section repeats with this period,
  // longer than searched_period (every one of the last two windows of p section points within
  // run.period_tolerance of the window before, not decaying), to the relative distance below.
  // The kind stays "not-periodic": the events of so long a window are not kept, and a run with
  // run.max_period ≥ recurrence_period classifies the orbit.
  std::optional<int> recurrence_period;
  std::optional<double> recurrence_distance;
};

// Observer that keeps the last 4·max_period + 2 periods of section points and events, and the
// section points alone of the last 3·kRecurrenceMax + 1 periods (a period longer than max_period
// is then found by recurrence of the section, Attractor::recurrence_period).
class AttractorRecorder final : public Observer {
 public:
  AttractorRecorder(const System& system, const Scene& scene);
  void OnEvent(const Event& e) override;
  void OnSection(const Sample& s) override;
  bool WantsResets() const override { return false; }

  // Classification of the motion over the final periods recorded.
  Attractor Classify() const;

  // Whether the motion has settled on the periodic attractor Classify() finds, so that a run can
  // stop here without changing its classification: Classify() finds a period p, and the
  // differences δ1, δ2 of the last two windows of p section points (relative, as in Classify)
  // either vanish or fall geometrically (λ = δ1/δ2 < 0.95) with a remaining distance to the
  // orbit, estimated as δ1·λ/(1 − λ), below `remainder`. Cheap when the last section point
  // repeats no earlier one within run.period_tolerance (most calls during a transient).
  bool Settled(double remainder) const;

  // The event log is bounded (memory for any input, e.g. a tiny clearance with 10⁹ impacts per
  // time unit): past `max_events` the oldest events are dropped, and with them every section
  // point whose windows they belonged to, so that the classification looks only at periods whose
  // events are all kept (a record of fewer periods: "not-periodic" when not even one is whole).
  // The default is what fits in 256 MB; counts and loads are not the recorder's and stay whole.
  static constexpr size_t kDefaultMaxEvents = (size_t{256} << 20) / sizeof(Event);
  void set_max_events(size_t n) { max_events_ = n < 1 ? 1 : n; }
  // Events dropped so far by the bound (0 on every run whose record fits).
  long long events_dropped() const { return events_dropped_; }

 private:
  struct Section {
    long long k;
    Eigen::VectorXd z;  // (X, Ẋ)
    double amax;        // |z|∞
    Mode mode;
    int held;  // contacts held at the section point
  };
  // Classify(); `check_decay` false (for Settled) skips the decay test of the period (Settled
  // makes its own, stricter one on the same windows) and returns no description without a period.
  Attractor ClassifyRecord(bool check_decay) const;
  double Phase(const Clock& c, int p) const;  // ωt mod 2π p
  double Difference(size_t i, size_t j) const;  // |z_i − z_j|∞ / (1 + max |z|∞); ∞ if modes differ

  // The recurrence search of a not-periodic record (Attractor::recurrence_period).
  void FindRecurrence(Attractor& a) const;

  const System& sys_;
  double phase0_;
  int max_period_;
  double tolerance_;
  std::deque<Section> sections_;
  // Its nodes recycled (block_recycler.hpp): the window slides by a period at a time.
  std::deque<Event, BlockRecycler<Event>> events_;
  size_t max_events_ = kDefaultMaxEvents;
  long long events_dropped_ = 0;
  // Ring of the last section points (2n values and the mode each), oldest at ring_next_ once full;
  // it grows with the record, so a short run allocates only what it records.
  std::vector<double> ring_;
  std::vector<Mode> ring_mode_;
  size_t ring_next_ = 0;

 public:
  // Longest period the recurrence of the section can find.
  static constexpr int kRecurrenceMax = 1024;
};

}  // namespace vibro
