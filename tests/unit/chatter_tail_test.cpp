// The prediction of a chattering tail (dynamics/chatter_tail.hpp, docs/model.md §5.4):
// - its estimated error bounds the true error of Δ∞, the truth being the quad engine following the
//   same sequence impact by impact from the same state (error target 1e-28 T);
// - its gradient, used by the Poincaré solver's Jacobian, equals finite differences of the jump
//   the automaton takes: central differences of the prediction in (X, Ẋ), plus the shift of the
//   impact time for a state off the stop, with the prediction's rate along the free flow taken by
//   differences of the exact engine's flow.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "dynamics/chatter_tail.hpp"
#include "dynamics/exact_engine.hpp"
#include "support.hpp"

namespace vibro::test {
namespace {

using detail::ModelT;
using detail::PredictTail;

// Post-impact states of a run (the states from which the automaton predicts).
struct PostImpact final : Observer {
  struct Row {
    double phase, t;
    Eigen::VectorXd X, V;
  };
  std::vector<Row> rows;
  double last_t = 0;
  void OnEvent(const Event& e) override { last_t = e.t; }
  void OnReset(const Reset& r) override {
    if (r.kind == ResetKind::kImpact) rows.push_back({r.phase, last_t, r.X_after, r.V_after});
  }
};

std::vector<PostImpact::Row> ImpactsOf(Scene s) {
  s.run.chatter = ChatterTreatment::kNone;  // every impact followed: the whole sequence
  const System sys(s);
  PostImpact obs;
  Log log;
  SimulationOptions opt;
  opt.observers = {&log, &obs};
  // The impact's time is that of the event emitted right after the reset: pair them up.
  vibro::Simulate(sys, s, opt);
  std::vector<PostImpact::Row> rows;
  const auto impacts = log.Of(EventKind::kImpact);
  for (size_t i = 0; i < obs.rows.size() && i < impacts.size(); ++i) {
    auto row = obs.rows[i];
    row.t = impacts[i].t;
    rows.push_back(row);
  }
  return rows;
}

// Time from `row` to the accumulation point, by the quad engine.
std::optional<double> QuadTail(Scene s, const PostImpact::Row& row) {
  s.run.precision = Precision::kQuad;
  s.run.chatter = ChatterTreatment::kAccumulation;
  s.run.periods = 2;
  const InitialOverride from{row.t, row.X, row.V};
  const Outcome run = Simulate(s, &from);
  if (run.result.status != RunStatus::kOk) return std::nullopt;
  const auto acc = run.log.Of(EventKind::kAccumulation);
  if (acc.empty()) return std::nullopt;
  return acc.front().t - row.t;
}

TEST(ChatterTail, EstimatedErrorBoundsTheTrueError) {
  // Fig. 8's scene at four forcings, the last three close to the end of sticking (f_max ≈ 1.2892
  // for r = 0.75, ω = 2.8), where R is small and falling at the switch and ε is large.
  int checked = 0, large_eps = 0;
  double worst_ratio = 0;
  for (double f : {1.2, 1.27, 1.285, 1.2892}) {
    Scene s = OneDof(0.75, 2.8, f, 1.0, 2);
    const System sys(s);
    const ModelT<double> m(sys);
    const auto rows = ImpactsOf(s);
    ASSERT_GT(rows.size(), 20u) << f;
    for (const auto& row : rows) {
      const auto p = PredictTail<double>(m, row.X, row.V, row.phase, 1.0);
      if (!(p.reaction > 0) || !(std::abs(p.epsilon) <= detail::kTailEpsilonMax)) {
        large_eps += p.reaction > 0;
        continue;
      }
      if (p.speed < 1e-9) continue;  // below: the double state itself carries the error
      const auto truth = QuadTail(s, row);
      if (!truth) continue;
      const double err = std::abs(static_cast<double>(p.delta) - *truth);
      const double bound = static_cast<double>(p.error) + 1e-15;
      worst_ratio = std::max(worst_ratio, err / bound);
      EXPECT_LE(err, bound) << "f = " << f << ", speed " << p.speed << ", ε " << p.epsilon
                            << ", Δ0 " << p.delta0;
      ++checked;
    }
  }
  RecordProperty("worst_error_over_estimate", testing::PrintToString(worst_ratio));
  EXPECT_GT(checked, 30);
  EXPECT_GT(large_eps, 0);  // the sequences near f_max do pass through |ε| > 0.1
}

TEST(ChatterTail, GradientMatchesFiniteDifferences) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Scene> scenes = {OneDof(0.6, 2.8, 1.5), Chain(2, 0.5, 0.7, 0.9, 1.3),
                               Chain(3, 0.2, 0.5, 1.7, 2.0)};
  Scene damped = Chain(2, 0.5, 0.7, 0.9, 1.3);
  damped.damping_ratios = Eigen::Vector2d(0.03, 0.08);
  scenes.push_back(damped);
  Scene stiff = Chain(10, 1.0, 0.5, 0.2, 2.0);
  stiff.physical->stiffness *= 1e4;
  stiff.physical->stiffness(0, 0) -= 1e4 - 1.0;
  stiff.damping_ratios = Eigen::VectorXd::Constant(10, 0.05);
  scenes.push_back(stiff);
  int tested = 0;
  for (const Scene& s : scenes) {
    const System sys(s);
    const ModelT<double> m(sys);
    const int n = m.dof();
    for (int trial = 0; trial < 8; ++trial) {
      Eigen::VectorXd X = sys.stop() * sys.static_shape(), V(n);
      for (int i = 0; i < n; ++i) {
        X[i] += 0.05 * u(rng);
        V[i] = 0.1 * u(rng);
      }
      X -= sys.contact() * ((sys.ContactDisplacement(X) - sys.stop()) / sys.s_B());
      V += sys.contact() * ((1e-3 - sys.ContactVelocity(V)) / sys.s_B());  // ẋ_B⁺ = 1e-3
      const double phase = 3.0 * (u(rng) + 1.0);
      const auto p = PredictTail<double>(m, X, V, phase, 1.0);
      // The gradient is used only for predictions that can be taken (|ε| ≤ 0.1).
      if (!(p.reaction > 0) || std::abs(p.epsilon) > detail::kTailEpsilonMax) continue;
      ++tested;
      const Eigen::VectorXd g = detail::DeltaGradient<double>(m, X, V, phase, p);
      // dΔ∞/dt along the free flow: one-sided second-order differences of the engine's flow.
      detail::ExactEngine engine(sys, m);
      engine.Begin({Mode::kFree, phase, 0.0, X, V, 0.0, detail::FlightStart::kGeneric,
                    detail::StickStart::kGeneric});
      const double s_step = 1e-3 * p.delta0;  // ≪ the first flight of the tail
      double along[3];
      for (int k = 0; k < 3; ++k) {
        Eigen::VectorXd Xs, Vs;
        engine.Evaluate(k * s_step, Xs, Vs);
        along[k] = PredictTail<double>(m, Xs, Vs, phase + sys.frequency() * k * s_step, 1.0).delta;
      }
      const double rate = (-3.0 * along[0] + 4.0 * along[1] - along[2]) / (2.0 * s_step);
      for (int j = 0; j < 2 * n; ++j) {
        Eigen::VectorXd Xp = X, Vp = V, Xm = X, Vm = V;
        const double h = 1e-7;
        (j < n ? Xp[j] : Vp[j - n]) += h;
        (j < n ? Xm[j] : Vm[j - n]) -= h;
        double fd = (PredictTail<double>(m, Xp, Vp, phase, 1.0).delta -
                     PredictTail<double>(m, Xm, Vm, phase, 1.0).delta) /
                    (2 * h);
        if (j < n) fd -= (1.0 + rate) * sys.contact_shape()[j] / p.speed;
        EXPECT_NEAR(g[j], fd, 1e-6 * (std::abs(fd) + 1e-3)) << "component " << j << ", n " << n;
      }
    }
  }
  EXPECT_GE(tested, 20);
}

}  // namespace
}  // namespace vibro::test
