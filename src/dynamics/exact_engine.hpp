// The exact engine: free flight and sticking advanced with the closed forms of MODEL §2, §4.2
// and §7, guards located by certified stepping on the trigonometric sums (MODEL §2.1).
#pragma once

#include <vector>

#include "dynamics/damped_sticking.hpp"
#include "dynamics/oscillator.hpp"
#include "dynamics/propagator.hpp"
#include "dynamics/root_finder.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

class ExactEngine final : public Propagator {
 public:
  explicit ExactEngine(const System& system);

  void Begin(const SegmentStart& start) override;
  SegmentResult Advance(double sigma_max, bool detect_events,
                        const StretchCallback& on_stretch) override;
  void Evaluate(double sigma, Eigen::VectorXd& X, Eigen::VectorXd& V) const override;
  double Gap(double sigma) const override;

  // Gap g = x_B − x0 and its derivatives at local time sigma, with a bound on |g'''| over
  // [sigma, sigma + H] (free flight). Public for tests.
  Probe GapProbe(double sigma, double H) const;
  // Reaction R and its derivatives, with a bound on |R'''| (sticking, n ≥ 2).
  Probe ReactionProbe(double sigma, double H) const;

 private:
  SegmentResult AdvanceFree(double sigma_max, bool detect_events);
  SegmentResult AdvanceSticking(double sigma_max, bool detect_events);
  // Start of the certified search: the end of the window free of the trivial root at σ = 0.
  double FlightWindow() const;

  const System& sys_;
  double omega_;
  double h_cap_;  // largest root-search step (the bounds grow with the step)
  std::vector<Oscillator> free_modes_;   // ω_i, ζ_i, T_A,i f
  std::vector<Oscillator> stick_modes_;  // ω'_k, 0, l_kᵀF_c f
  double reaction_forcing_;              // (s_A/s_B) f
  bool damped_sticking_ = false;         // non-proportional damping in the constrained modes
  DampedSticking damped_;                // its closed form (MODEL §7)

  // Current segment.
  Mode mode_ = Mode::kFree;
  double phase_ = 0;
  PhaseTrig trig_{0.0};
  Eigen::VectorXd X0_, V0_;    // free flight start
  Eigen::VectorXd xi0_, dxi0_; // sticking start, constrained modal coordinates
  double gap0_ = 0;
  double static_reaction_ = 0;  // x0 / flexibility
  FlightStart flight_start_ = FlightStart::kGeneric;
  StickStart stick_start_ = StickStart::kGeneric;
};

}  // namespace vibro::detail
