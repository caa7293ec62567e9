// The CVODE engine: free flight and sticking integrated by SUNDIALS CVODE (6.4) with root finding,
// behind the same automaton as the exact engine. The only file that includes SUNDIALS is
// cvode_engine.cpp; this header exposes no SUNDIALS type.
#pragma once

#include <memory>

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

}  // namespace vibro::detail
