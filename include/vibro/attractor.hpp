// Attractor classification of a simulated run (docs/cli.md, docs/output.md `attractor` block): from the
// stroboscopic section and the event log of the final periods.
#pragma once

#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vibro/observer.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro {

struct Attractor {
  // "sticking-periodic" | "impact-periodic" | "no-contact-periodic" | "permanent-contact" |
  // "not-periodic"
  std::string kind = "not-periodic";
  std::optional<int> period;                   // forcing periods; none when not periodic
  std::optional<long long> impacts_per_period;  // none when a period holds a chattering sequence
  // Time on the stop per period / period length. For "not-periodic": the average over the
  // analysed window (the last max_period periods).
  std::optional<double> sticking_fraction;
  // Sticking phases [start, end] as ωt mod 2π·period (start = accumulation point or plastic
  // impact, end = release); end = start + ω·duration, so end may exceed 2π·period when a phase
  // wraps. Sorted by start.
  std::vector<std::pair<double, double>> stick_phases;
  // Contact velocity just before each impact of one period, and the phases of the impacts
  // (impact-periodic orbits).
  std::vector<double> impact_phases, impact_velocities;
};

// Observer that keeps the last 2·max_period + 2 periods of section points and events.
class AttractorRecorder final : public Observer {
 public:
  AttractorRecorder(const System& system, const Scene& scene);
  void OnEvent(const Event& e) override;
  void OnSection(const Sample& s) override;

  // Classification of the motion over the final periods recorded.
  Attractor Classify() const;

  // Whether the motion has settled on the periodic attractor Classify() finds, so that a run can
  // stop here without changing its classification: Classify() finds a period p, and the
  // differences δ1, δ2 of the last two windows of p section points (relative, as in Classify)
  // either vanish or fall geometrically (λ = δ1/δ2 < 0.95) with a remaining distance to the
  // orbit, estimated as δ1·λ/(1 − λ), below `remainder`. Cheap when the last section point
  // repeats no earlier one within run.period_tolerance (most calls during a transient).
  bool Settled(double remainder) const;

 private:
  struct Section {
    long long k;
    Eigen::VectorXd z;  // (X, Ẋ)
    double amax;        // |z|∞
    Mode mode;
  };
  // Classify(); `check_decay` false (for Settled) skips the decay test of the period (Settled
  // makes its own, stricter one on the same windows) and returns no description without a period.
  Attractor ClassifyRecord(bool check_decay) const;
  double Phase(const Clock& c, int p) const;  // ωt mod 2π p
  double Difference(size_t i, size_t j) const;  // |z_i − z_j|∞ / (1 + max |z|∞); ∞ if modes differ

  const System& sys_;
  double phase0_;
  int max_period_;
  double tolerance_;
  std::deque<Section> sections_;
  std::deque<Event> events_;
};

}  // namespace vibro
