// Lyapunov exponents by QR re-orthonormalisation of the exact tangent map (docs/model.md §5.8).
#include "vibro/lyapunov.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vibro {
namespace {

// Two-sided 97.5 % quantile of Student's t with `dof` degrees of freedom (1 to 9).
double StudentT975(int dof) {
  static const double t[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262};
  return t[std::clamp(dof, 1, 9) - 1];
}

// Applies the Householder reflector I − τ v vᵀ (v_k = 1 implied, v_i for i > k, rows k..m−1) to
// the column y in place.
inline void Reflect(const double* v, double tau, Eigen::Index k, Eigen::Index m, double* y) {
  double w = y[k];
  for (Eigen::Index i = k + 1; i < m; ++i) w += v[i] * y[i];
  w *= tau;
  y[k] -= w;
  for (Eigen::Index i = k + 1; i < m; ++i) y[i] -= w * v[i];
}

}  // namespace

LyapunovObserver::LyapunovObserver(const System& sys, const Scene& scene)
    : tangent_(sys), period_(sys.period()) {
  const long long total = std::max<long long>(1, scene.run.periods);
  window_ = std::max<long long>(1, total / 2);
  first_measured_ = total - window_ + 1;
  const auto m = 2 * sys.dof();
  frame_ = Eigen::MatrixXd::Identity(m, m);
  block_sums_ = Eigen::MatrixXd::Zero(m, kBlocks);
  block_periods_ = Eigen::VectorXi::Zero(kBlocks);
  hulls_.resize(static_cast<size_t>(m));
  rounding_ = Eigen::VectorXd::Zero(m);
  shapes_.resize(sys.dof(), sys.contact_count());
  for (int j = 0; j < sys.contact_count(); ++j) shapes_.col(j) = sys.contacts()[static_cast<size_t>(j)].shape;
}

void LyapunovObserver::OnReset(const Reset& r) {
  tangent_.OnReset(r);
  ++factors_;
  if (r.kind == ResetKind::kPlasticStick || r.kind == ResetKind::kAccumulation) {
    stuck_ = true;
    if (std::find(period_stuck_.begin(), period_stuck_.end(), r.contact) == period_stuck_.end())
      period_stuck_.push_back(r.contact);
  }
}

void LyapunovObserver::OnSection(const Sample& s) {
  const long long k = s.clock.period;
  if (last_k_ >= 0 && k == last_k_ + 1) {
    pending_ = k;
    return;
  }
  // The first section point (the start, or a resumed run), or a gap: a new frame from here.
  frame_.setIdentity();
  last_k_ = k;
  stuck_ = false;
  period_stuck_.clear();
  factors_ = 0;
  tangent_.Restart(frame_);
}

void LyapunovObserver::OnStretch(const Stretch& s) {
  tangent_.OnStretch(s);
  ++factors_;
  if (pending_ >= 0) {
    EndPeriod(pending_);
    pending_ = -1;
  }
}

void LyapunovObserver::EndPeriod(long long k) {
  if (tangent_.singular()) {
    // A grazing contact: the tangent map is unbounded there (docs/model.md §5.7). The period is
    // left out and the frame goes on unchanged.
    if (k >= first_measured_) ++singular_;
  } else {
    Orthonormalize(tangent_.jacobian());
    const Eigen::MatrixXd& packed = qr_;
    if (k >= first_measured_) {
      const auto b = static_cast<int>(
          std::min<long long>(kBlocks - 1, (k - first_measured_) * kBlocks / std::max<long long>(1, window_)));
      // The period's map is a product of `factors_` flights, impacts and phases (and the QR): a
      // relative error of about dim·ε each (see Spectrum).
      const double norm = tangent_.jacobian().norm() * static_cast<double>(factors_ + 1);
      for (Eigen::Index i = 0; i < packed.cols(); ++i) {
        const double r = std::abs(packed(i, i));
        const double log_r = std::log(r);
        block_sums_(i, b) += log_r;
        AddToHulls(i, log_r);
        rounding_[i] += norm / r;
      }
      ++block_periods_[b];
      ++measured_;
      collapsed_ = collapsed_ || stuck_;
      for (int j : period_stuck_)
        if (std::find(window_stuck_.begin(), window_stuck_.end(), j) == window_stuck_.end()) window_stuck_.push_back(j);
    }
  }
  last_k_ = k;
  stuck_ = false;
  period_stuck_.clear();
  factors_ = 0;
  tangent_.Restart(frame_);
}

void LyapunovObserver::AddToHulls(Eigen::Index i, double log_r) {
  Hull& h = hulls_[static_cast<size_t>(i)];
  if (h.upper.empty()) {
    h.upper.emplace_back(0.0, 0.0);
    h.lower.emplace_back(0.0, 0.0);
  }
  const double n = h.upper.back().first + 1;
  h.sum += log_r;
  h.abs_sum += std::abs(log_r);
  const std::pair<double, double> p{n, h.sum};
  // Monotone chain: a vertex goes when it lies on the wrong side of the line from the one before
  // it to the new point.
  const auto cross = [](const auto& o, const auto& a, const auto& b) {
    return (a.first - o.first) * (b.second - o.second) - (a.second - o.second) * (b.first - o.first);
  };
  while (h.upper.size() >= 2 && cross(h.upper[h.upper.size() - 2], h.upper.back(), p) >= 0) h.upper.pop_back();
  while (h.lower.size() >= 2 && cross(h.lower[h.lower.size() - 2], h.lower.back(), p) <= 0) h.lower.pop_back();
  h.upper.push_back(p);
  h.lower.push_back(p);
  for (auto* v : {&h.upper, &h.lower}) {
    if (v->size() <= kHullCap) continue;
    size_t kept = 1;
    for (size_t j = 1; j + 1 < v->size(); ++j)
      if (j % 2 == 0) (*v)[kept++] = (*v)[j];
    (*v)[kept++] = v->back();
    v->resize(kept);
  }
}

// J = Q R by Householder reflections (Eigen's householder_qr_inplace_unblocked and householderQ,
// written out for these small sizes, where the generic code's dispatch outweighs the arithmetic):
// column k's reflector H_k = I − τ_k v_k v_kᵀ, v_k = (1, x_{k+1..}/(x_k − β)), maps it onto β e_k,
// β = −sign(x_k)‖x‖ (τ = 0 and β = x_k when the column below the diagonal is zero); R_kk = β.
// frame_ ← Q = H_0 H_1 ⋯ H_{m−1}.
void LyapunovObserver::Orthonormalize(const Eigen::MatrixXd& J) {
  const Eigen::Index m = J.rows(), cols = J.cols();
  qr_ = J;
  tau_.resize(cols);
  for (Eigen::Index k = 0; k < cols && k < m; ++k) {
    double* x = qr_.col(k).data();
    const double c0 = x[k];
    double tail = 0;
    for (Eigen::Index i = k + 1; i < m; ++i) tail += x[i] * x[i];
    if (tail <= std::numeric_limits<double>::min()) {
      tau_[k] = 0;
      for (Eigen::Index i = k + 1; i < m; ++i) x[i] = 0;
      continue;
    }
    double beta = std::sqrt(c0 * c0 + tail);
    if (c0 >= 0) beta = -beta;
    const double scale = 1.0 / (c0 - beta);
    for (Eigen::Index i = k + 1; i < m; ++i) x[i] *= scale;  // v_k below the diagonal
    tau_[k] = (beta - c0) / beta;
    x[k] = beta;
    for (Eigen::Index j = k + 1; j < cols; ++j) Reflect(x, tau_[k], k, m, qr_.col(j).data());
  }
  frame_.setIdentity(m, m);
  for (Eigen::Index k = std::min(cols, m) - 1; k >= 0; --k) {
    if (tau_[k] == 0) continue;
    const double* v = qr_.col(k).data();
    for (Eigen::Index j = 0; j < m; ++j) Reflect(v, tau_[k], k, m, frame_.col(j).data());
  }
}

LyapunovSpectrum LyapunovObserver::Spectrum() const {
  LyapunovSpectrum out;
  out.periods = measured_;
  out.singular_periods = singular_;
  // A corner of the map met on the way: the frame followed piece 0 (the tracker's default).
  if (!tangent_.corner().empty())
    out.corner = tangent_.corner() + ": the exponents follow the first order's piece (the gaps closing in "
                                     "ascending contact order); the other orders' pieces may give other exponents";
  if (measured_ == 0) {
    out.undefined = "no period of the second half of the run was measured";
    return out;
  }
  // Several contacts: an event whose Jacobian does not exist, or is not implemented, on the way.
  if (!tangent_.undefined().empty()) {
    out.undefined = "the tangent map does not cover the run: " + tangent_.undefined();
    return out;
  }
  const auto m = static_cast<int>(block_sums_.rows());
  // Directions kept: all, or 2n − 2 when sticking collapsed two of them. QR orders the frame by
  // decreasing growth, so the collapsed directions are the last ones.
  int collapsed = collapsed_ ? 2 : 0;
  if (collapsed_ && shapes_.cols() > 1 && !window_stuck_.empty()) {
    Eigen::MatrixXd C(shapes_.rows(), static_cast<Eigen::Index>(window_stuck_.size()));
    for (size_t k = 0; k < window_stuck_.size(); ++k) C.col(static_cast<Eigen::Index>(k)) = shapes_.col(window_stuck_[k]);
    Eigen::FullPivLU<Eigen::MatrixXd> lu(C);
    lu.setThreshold(1e-10);
    collapsed = 2 * static_cast<int>(lu.rank());
  }
  const int kept = std::max(0, m - collapsed);
  const double ninf = -std::numeric_limits<double>::infinity();
  const double time = static_cast<double>(measured_) * period_;
  std::vector<int> full;  // blocks holding periods
  for (int b = 0; b < kBlocks; ++b)
    if (block_periods_[b] > 0) full.push_back(b);
  out.blocks = static_cast<int>(full.size());
  std::vector<std::pair<double, std::pair<double, double>>> rows;
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  const auto n = static_cast<double>(measured_);
  const auto dim = static_cast<double>(m);
  for (int i = 0; i < kept; ++i) {
    const double mean = block_sums_.row(i).sum() / time;
    std::pair<double, double> ci{mean, mean};
    if (full.size() >= 2) {
      double ss = 0;
      for (int b : full) {
        const double x = block_sums_(i, b) / (block_periods_[b] * period_) - mean;
        ss += x * x;
      }
      const double batch = StudentT975(static_cast<int>(full.size()) - 1) *
                           std::sqrt(ss / static_cast<double>(full.size() - 1) / static_cast<double>(full.size()));
      // The boundary term: on a periodic or quasi-periodic motion S_n = n·λT + g_n − g_0 with g
      // bounded, so the estimate is off by (g_N − g_0)/(NT), which the spread of S_n about its
      // chord bounds once the window has seen g's range (the oscillation of a complex pair's
      // two exponents, a frame still turning towards its limit).
      const Hull& h = hulls_[static_cast<size_t>(i)];
      const double slope = h.sum / n;
      double above = 0, below = 0;
      for (const auto& [x, y] : h.upper) above = std::max(above, y - slope * x);
      for (const auto& [x, y] : h.lower) below = std::min(below, y - slope * x);
      const double boundary = (above - below) / time;
      // Rounding: each factor of a period's tangent map (and its QR) is computed to a relative
      // accuracy of about dim·ε, which moves log|R_ii| by up to that times ‖J‖/|R_ii| (first
      // order; rounding_ sums ‖J‖_F·(factors + 1)/|R_ii| over the periods), taken kRoundingMargin
      // times; the orbit followed is itself off its exact self by the rounding of the state,
      // which this margin covers too. The sums of log|R_ii| are exact to n·ε·Σ|log|R_ii||.
      const double rounding =
          (kRoundingMargin * dim * kEps * rounding_[i] + n * kEps * h.abs_sum) / time;
      const double half = std::max(batch, boundary) + rounding;
      ci = {mean - half, mean + half};
    }
    rows.push_back({mean, ci});
  }
  std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [e, ci] : rows) {
    out.exponents.push_back(e);
    if (full.size() >= 2) out.ci.push_back(ci);
  }
  for (int i = kept; i < m; ++i) {
    out.exponents.push_back(ninf);
    if (full.size() >= 2) out.ci.push_back({ninf, ninf});
  }
  return out;
}

}  // namespace vibro
