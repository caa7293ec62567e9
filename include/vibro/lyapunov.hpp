// Lyapunov exponents of a simulated run (docs/model.md §5.8): Benettin's method on the exact tangent
// map of the hybrid flow. The TangentTracker carries an orthonormal frame through every flight,
// impact, sticking phase and accumulation point (the same closed-form Jacobians and saltation
// matrices as the orbit solver's DF); once per forcing period the frame is re-orthonormalised by
// QR and log|R_ii| is summed. Over the second half of the run the sums are taken in blocks, whose
// spread gives a batch-means confidence interval.
//
// Sticking collapses two directions (x_B and ẋ_B are fixed on the stop, docs/model.md §5.6): once
// a sticking phase is entered in the measured window, the two smallest exponents are −∞ (all of
// them for one DOF, whose sticking motions are superstable); with several contacts, two per
// independent contact shape c_j among the contacts that stuck (docs/contacts.md).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "vibro/observer.hpp"
#include "vibro/poincare.hpp"
#include "vibro/scene.hpp"
#include "vibro/system.hpp"

namespace vibro {

struct LyapunovSpectrum {
  // Per unit time, largest first, 2n of them; −∞ for directions collapsed by sticking.
  std::vector<double> exponents;
  // 95 % interval of each exponent (docs/model.md §5.8): the larger of the batch-means interval
  // of the block means (Student's t) and the bound of the boundary term (the deviation of the
  // running sum from its chord: a periodic or quasi-periodic motion), widened by the rounding of
  // the tangent maps; equal to (−∞, −∞) for a collapsed direction, empty when there are fewer
  // than two blocks.
  std::vector<std::pair<double, double>> ci;
  long long periods = 0;  // forcing periods measured (the second half of the run)
  int blocks = 0;         // blocks of periods behind the interval
  long long singular_periods = 0;  // periods left out: a grazing contact made the map singular
  std::string undefined;           // why there are no exponents; empty when there are
  // The run passed through a corner of the map (TangentTracker::corner(): a simultaneous impact whose
  // orders of closing give different Jacobians, docs/contacts.md "Periodic orbits"): where, and that
  // the exponents follow the first order's piece (the gaps closing in ascending contact order).
  // Empty when no corner was met.
  std::string corner;
  // The largest exponent is positive beyond its confidence interval.
  bool chaotic() const { return undefined.empty() && !ci.empty() && ci.front().first > 0; }
};

class LyapunovObserver final : public Observer {
 public:
  // Measures the periods after the first half of scene.run.periods (at least one).
  LyapunovObserver(const System& system, const Scene& scene);
  void OnStretch(const Stretch& s) override;
  void OnReset(const Reset& r) override;
  void OnSection(const Sample& s) override;
  LyapunovSpectrum Spectrum() const;

 private:
  static constexpr int kBlocks = 10;
  static constexpr double kRoundingMargin = 4;
  void EndPeriod(long long k);
  TangentTracker tangent_;
  double period_;            // T
  long long first_measured_;  // first period (section index k, the period ending at k) measured
  long long window_;          // periods in the measured window
  long long last_k_ = -1;     // section index of the frame's start, −1 before the first section
  // A section point is reported while the flight that reaches it is still being located: the
  // period it ends is closed by the OnStretch that follows (−1: none pending).
  long long pending_ = -1;
  bool stuck_ = false;        // a sticking entry since the last section
  bool collapsed_ = false;    // a sticking entry in the measured window
  // Several contacts: the contacts entered into sticking since the last section, and those of the
  // measured window; each independent contact shape c_j collapses two directions.
  std::vector<int> period_stuck_, window_stuck_;
  Eigen::MatrixXd shapes_;    // c_j as columns, (n, m)
  Eigen::MatrixXd frame_;     // orthonormal frame Q, (2n, 2n)
  // Householder QR of the period's tangent map (Orthonormalize): R's diagonal and the reflectors,
  // storage reused every period.
  void Orthonormalize(const Eigen::MatrixXd& J);
  Eigen::MatrixXd qr_;      // J reduced in place: R on and above the diagonal, (2n, 2n)
  Eigen::VectorXd tau_;     // the reflectors' coefficients, (2n)
  Eigen::MatrixXd block_sums_;  // Σ log|R_ii| per block, (2n, kBlocks)
  Eigen::VectorXi block_periods_;
  long long measured_ = 0, singular_ = 0;

  // The boundary term (docs/model.md §5.8): per exponent, the upper and lower convex hulls of the
  // points (n, S_n), S_n = Σ log|R_ii| over the first n periods measured, so that the largest
  // and smallest deviation of S_n from the chord S_N·n/N are known for the final N without
  // keeping every S_n. At most kHullCap vertices each (beyond, every other interior vertex is
  // dropped: the deviation is then found among the vertices kept).
  static constexpr size_t kHullCap = 256;
  struct Hull {
    std::vector<std::pair<double, double>> upper, lower;  // (n, S_n), n increasing
    double sum = 0, abs_sum = 0;                          // S_n and Σ|log|R_ii|| so far
  };
  void AddToHulls(Eigen::Index i, double log_r);
  std::vector<Hull> hulls_;
  // Rounding: Σ over the periods measured of ‖J‖_F·(factors + 1) / |R_ii|, per exponent: a
  // perturbation δJ of the period's tangent map moves log|R_ii| by at most ‖δJ‖ / |R_ii| (first
  // order), and δJ grows with the number of factors of the map.
  Eigen::VectorXd rounding_;
  long long factors_ = 0;  // stretches and resets applied to the frame since the period began
};

}  // namespace vibro
