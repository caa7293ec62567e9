// Exact engine (MODEL §2, §2.1, §4.2, §7, §8).
#include "dynamics/exact_engine.hpp"

#include "dynamics/flight_window.hpp"

#include <algorithm>
#include <cmath>

namespace vibro::detail {
namespace {

// Relative margin on the derivative bounds, for the rounding of the evaluated jets.
constexpr double kBoundMargin = 1.0 + 1e-9;

}  // namespace

ExactEngine::ExactEngine(const System& sys)
    : sys_(sys),
      omega_(sys.frequency()),
      damped_sticking_(sys.constrained().damping.size() > 0 &&
                       sys.constrained().damping.cwiseAbs().maxCoeff() > 0),
      damped_(sys) {
  const double f = sys.amplitude();
  for (int i = 0; i < sys.dof(); ++i)
    free_modes_.push_back({sys.omega()[i], sys.damping()[i], sys.forcing()[i] * f});
  const auto& cm = sys.constrained();
  for (Eigen::Index k = 0; k < cm.frequencies.size(); ++k)
    stick_modes_.push_back({cm.frequencies[k], 0.0, cm.modal_forcing[k] * f});
  h_cap_ = StepCap(sys);
  reaction_forcing_ = sys.s_A() / sys.s_B() * f;
  static_reaction_ = sys.stop() / sys.flexibility();
}

void ExactEngine::Begin(const SegmentStart& s) {
  mode_ = s.mode;
  phase_ = s.phase;
  trig_ = PhaseTrig(s.phase);
  gap0_ = s.gap;
  flight_start_ = s.flight_start;
  stick_start_ = s.stick_start;
  if (mode_ == Mode::kFree) {
    X0_ = s.X;
    V0_ = s.V;
  } else {
    // ξ = L X (L v0 = 0), ξ̇ = L Ẋ (MODEL §4.2).
    xi0_ = sys_.constrained().left * s.X;
    dxi0_ = sys_.constrained().left * s.V;
    if (damped_sticking_) damped_.Begin(xi0_, dxi0_, phase_);
  }
}

Probe ExactEngine::GapProbe(double sigma, double H) const {
  const auto& c = sys_.contact_shape();
  const double s_forcing = trig_.s * std::cos(omega_ * sigma) + trig_.c * std::sin(omega_ * sigma);
  Probe p{{gap0_, 0.0, 0.0}, 0.0};
  double dq_sum = 0.0;
  for (size_t i = 0; i < free_modes_.size(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    if (c[ii] == 0.0) continue;
    const Oscillator& o = free_modes_[i];
    const auto st = Flow(o, omega_, trig_, X0_[ii], V0_[ii], sigma);
    const double x = X0_[ii] + st.dq;
    dq_sum += st.dq;
    p.jet.g1 += st.v;
    p.jet.g2 += -o.nu * o.nu * x - 2.0 * o.zeta * o.nu * st.v + o.F * s_forcing;
    p.M += Bounds(o, omega_, Amplitude(o, x, st.v) + std::abs(o.F) * H).d3;
  }
  p.jet.g += dq_sum;
  p.M *= kBoundMargin;
  return p;
}

Probe ExactEngine::ReactionProbe(double sigma, double H) const {
  const auto& rho = sys_.constrained().reaction;
  const double sf = std::sin(phase_ + omega_ * sigma), cf = std::cos(phase_ + omega_ * sigma);
  Probe p{{static_reaction_ - reaction_forcing_ * sf, -reaction_forcing_ * omega_ * cf,
           reaction_forcing_ * omega_ * omega_ * sf},
          std::abs(reaction_forcing_) * omega_ * omega_ * omega_};
  for (size_t k = 0; k < stick_modes_.size(); ++k) {
    const auto kk = static_cast<Eigen::Index>(k);
    const Oscillator& o = stick_modes_[k];
    const auto st = Flow(o, omega_, trig_, xi0_[kk], dxi0_[kk], sigma);
    const double xi = xi0_[kk] + st.dq;
    p.jet.g += rho[kk] * xi;
    p.jet.g1 += rho[kk] * st.v;
    p.jet.g2 += rho[kk] * (-o.nu * o.nu * xi + o.F * sf);
    p.M += std::abs(rho[kk]) * Bounds(o, omega_, Amplitude(o, xi, st.v) + std::abs(o.F) * H).d3;
  }
  p.M *= kBoundMargin;
  return p;
}

double ExactEngine::FlightWindow() const {
  // MODEL §2.1: divide out the known zero at σ = 0; no root in the certified window (0, σ_w).
  if (flight_start_ == FlightStart::kGeneric) return 0.0;
  return CertifiedWindow(flight_start_, StartJet(sys_, X0_, V0_, phase_, h_cap_), h_cap_);
}

SegmentResult ExactEngine::AdvanceFree(double sigma_max, bool detect_events) {
  if (!detect_events) return {SegmentEnd::kLimit, sigma_max, {}};
  const double w = FlightWindow();
  if (w >= sigma_max) return {SegmentEnd::kLimit, sigma_max, {}};
  const auto probe = [this](double u, double H) { return GapProbe(u, H); };
  const RootSearch rs = FirstRoot(probe, w, sigma_max, h_cap_);
  if (!rs.found) return {SegmentEnd::kLimit, sigma_max, {}};
  return {SegmentEnd::kContact, rs.sigma, {}};
}

SegmentResult ExactEngine::AdvanceSticking(double sigma_max, bool detect_events) {
  if (damped_sticking_ && !damped_.ok())
    return {SegmentEnd::kFailure, 0.0,
            "the damped constrained system is defective (critically damped constrained mode): "
            "no closed form; change structure.damping_ratios slightly, or use run.engine = "
            "\"cvode\""};
  if (!detect_events) return {SegmentEnd::kLimit, sigma_max, {}};
  const auto probe = [this](double u, double H) {
    return damped_sticking_ ? damped_.ReactionProbe(u) : ReactionProbe(u, H);
  };
  double w = 0.0;
  if (stick_start_ != StickStart::kGeneric) {
    const Probe p = probe(0.0, h_cap_);
    if (stick_start_ == StickStart::kRising) {
      const double v = p.jet.g1, a = p.jet.g2, M = p.M;
      if (v > 0)
        w = std::min(h_cap_, M > 0 ? (0.5 * a + std::sqrt(0.25 * a * a + 2.0 * M * v / 3.0)) / (M / 3.0)
                                   : (a < 0 ? 2.0 * v / -a : h_cap_));
    } else if (p.jet.g2 > 0) {
      w = p.M > 0 ? std::min(3.0 * p.jet.g2 / p.M, h_cap_) : h_cap_;
    }
  }
  if (w >= sigma_max) return {SegmentEnd::kLimit, sigma_max, {}};
  const RootSearch rs = FirstRoot(probe, w, sigma_max, h_cap_);
  if (!rs.found) return {SegmentEnd::kLimit, sigma_max, {}};
  return {SegmentEnd::kRelease, rs.sigma, {}};
}

SegmentResult ExactEngine::Advance(double sigma_max, bool detect_events,
                                   const StretchCallback& on_stretch) {
  SegmentResult r = mode_ == Mode::kFree ? AdvanceFree(sigma_max, detect_events)
                                         : AdvanceSticking(sigma_max, detect_events);
  if (r.end != SegmentEnd::kFailure && on_stretch) on_stretch(0.0, r.sigma);
  return r;
}

void ExactEngine::Evaluate(double sigma, Eigen::VectorXd& X, Eigen::VectorXd& V) const {
  const auto n = sys_.dof();
  X.resize(n);
  V.resize(n);
  if (mode_ == Mode::kFree) {
    for (int i = 0; i < n; ++i) {
      const auto st = Flow(free_modes_[static_cast<size_t>(i)], omega_, trig_, X0_[i], V0_[i], sigma);
      X[i] = X0_[i] + st.dq;
      V[i] = st.v;
    }
    return;
  }
  const auto m = static_cast<Eigen::Index>(stick_modes_.size());
  Eigen::VectorXd xi(m), dxi(m);
  if (damped_sticking_) damped_.Evaluate(sigma, xi, dxi);
  for (Eigen::Index k = 0; k < m && !damped_sticking_; ++k) {
    const auto st = Flow(stick_modes_[static_cast<size_t>(k)], omega_, trig_, xi0_[k], dxi0_[k], sigma);
    xi[k] = xi0_[k] + st.dq;
    dxi[k] = st.v;
  }
  X = sys_.stop() * sys_.static_shape() + sys_.constrained().vectors * xi;
  V = sys_.constrained().vectors * dxi;
}

double ExactEngine::Gap(double sigma) const {
  if (mode_ != Mode::kFree) return 0.0;
  return GapProbe(sigma, 0.0).jet.g;
}

}  // namespace vibro::detail
