// The CVODE engine: free flight and sticking integrated by SUNDIALS CVODE (6.4) with root finding,
// behind the same automaton as the exact engine. The only file that includes SUNDIALS is
// cvode_engine.cpp; this header exposes no SUNDIALS type.
#pragma once

#include <memory>
#include <vector>

#include "dynamics/compliant_contact.hpp"
#include "dynamics/model_t.hpp"
#include "dynamics/propagator.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

class CvodeEngine final : public Propagator {
 public:
  CvodeEngine(const System& system, const RunSpec& run);
  ~CvodeEngine() override;
  CvodeEngine(const CvodeEngine&) = delete;
  CvodeEngine& operator=(const CvodeEngine&) = delete;

  void Begin(const SegmentStart& start) override;
  SegmentResult Advance(double sigma_max, bool detect_events,
                        const StretchCallback& on_stretch) override;
  void Evaluate(double sigma, Eigen::VectorXd& X, Eigen::VectorXd& V) const override;
  double Gap(double sigma) const override;
  double GapOf(int j, double sigma) const override;
  SolverStats stats() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A compliant contact's propagator integrated by CVODE (docs/compliant.md, "CVODE"): the contact
// phase as the structure with the spring–dashpot force λ = −k g − c ġ on contact `contact` (its
// exit by the separation rule, its peak force and largest penetration, every other gap, all by
// CVODE's root finding), and the relaxing flight after a force-rule exit (the gap to the surface
// y₀ e^(−kσ/c)). `models`: every contact's model, as the automaton holds them.
std::unique_ptr<CompliantPhase> MakeCvodeCompliant(const RunSpec& run, const std::vector<const ModelT<double>*>& models,
                                                   int contact);

}  // namespace vibro::detail
