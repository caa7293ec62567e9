// max R of a sticking phase (docs/loads.md §3) against independent truths:
// - the certified search's ingredients: the state-based jet (R, Ṙ, R̈) against the engine's own
//   closed form of the held flow, its Taylor derivatives R''' and R'''' against differences of the
//   lower ones, and the bounds M ≥ |R'''| and M5 ≥ |R⁽⁵⁾| against the derivatives they bound, sampled
//   densely over the window they claim;
// - the maximum itself against the reaction of eq. (5) evaluated by this test on 20 000 dense
//   samples per period and refined by the parabola through the three largest (its error is
//   |R'''|h³/24 ≈ 1e-11 at these spacings), on scenes that take every path of the search: the
//   undamped constrained modes (Taylor step), the damped closed form (Newton steps), CVODE (the grid
//   search), quad precision, one DOF.
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "dynamics/reaction_max.hpp"
#include "dynamics/exact_engine.hpp"
#include "support.hpp"
#include "vibro/loads.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

using detail::ModelT;

// A state held on the stop: a random state projected onto x_B = x0, ẋ_B = 0.
void OnStop(const System& sys, std::mt19937_64& rng, Eigen::VectorXd& X, Eigen::VectorXd& V) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = sys.dof();
  X = sys.stop() * sys.static_shape();
  V.resize(n);
  for (int i = 0; i < n; ++i) {
    X[i] += 0.3 * u(rng);
    V[i] = 0.5 * u(rng);
  }
  X -= sys.contact() * ((sys.ContactDisplacement(X) - sys.stop()) / sys.s_B());
  V -= sys.contact() * (sys.ContactVelocity(V) / sys.s_B());
}

TEST(LoadsMaxR, JetsAndBoundsOfTheHeldFlow) {
  std::mt19937_64 rng(11);
  std::vector<Scene> scenes = {Chain(3, 1.0, 0.0, 0.8, 1.0), Chain(2, 1.0, 0.0, 1.3, 2.0), Chain(5, 0.5, 0.0, 0.6, 1.5)};
  Scene damped = Chain(3, 1.0, 0.0, 0.8, 1.0);
  damped.damping_ratios = Eigen::Vector3d(0.02, 0.05, 0.1);
  scenes.push_back(damped);
  int checked_taylor = 0;
  for (const Scene& s : scenes) {
    const System sys(s);
    const ModelT<double> m(sys);
    detail::ReactionMaxT<double> search;
    for (int trial = 0; trial < 4; ++trial) {
      Eigen::VectorXd X, V;
      OnStop(sys, rng, X, V);
      const double phase = 2.0 * trial + 0.3;
      detail::ExactEngine engine(sys, m);
      engine.Begin({Mode::kSticking, phase, 0.0, X, V, 0.0, detail::FlightStart::kGeneric,
                    detail::StickStart::kGeneric});
      const double H = 3.0;
      double M = 0, M5 = 0;
      ASSERT_TRUE(engine.HeldReactionBound(H, M, &M5));
      double scale = 0;
      for (int k = 0; k <= 600; ++k) {
        const double sg = H * k / 600.0;
        double R = 0, rate = 0, accel = 0;
        ASSERT_TRUE(engine.HeldReactionJet(sg, R, rate, accel));
        scale = std::max({scale, std::abs(R), std::abs(rate), std::abs(accel)});
        // The state-based jet (JetAt, eq. (5) on the dense output) against the engine's own.
        Eigen::VectorXd Xs, Vs;
        engine.Evaluate(sg, Xs, Vs);
        const auto j = search.JetAt(m, Xs, Vs, phase + sys.frequency() * sg);
        EXPECT_NEAR(j.R, R, 1e-12 * (1 + std::abs(R))) << "scene " << s.title << " σ " << sg;
        EXPECT_NEAR(j.rate, rate, 1e-11 * (1 + std::abs(rate)));
        EXPECT_NEAR(j.accel, accel, 1e-11 * (1 + std::abs(accel)));
        // R''' by a central difference of R̈ (step 1e-4: error ~1e-8 |R⁽⁵⁾|/6), bounded by M.
        const double e = 1e-4;
        double Rp, rp, ap, Rm, rm, am;
        engine.HeldReactionJet(sg + e, Rp, rp, ap);
        engine.HeldReactionJet(sg - e, Rm, rm, am);
        const double r3 = (ap - am) / (2 * e);
        EXPECT_LE(std::abs(r3), M * (1 + 1e-6)) << "σ " << sg;
        double d[5], dp[5], dm[5];
        if (!engine.HeldReactionTaylor(sg, d)) continue;  // the damped closed form has none
        ++checked_taylor;
        engine.HeldReactionTaylor(sg + e, dp);
        engine.HeldReactionTaylor(sg - e, dm);
        EXPECT_NEAR(d[0], R, 1e-14 * (1 + std::abs(R)));
        EXPECT_NEAR(d[1], rate, 1e-14 * (1 + std::abs(rate)));
        EXPECT_NEAR(d[2], accel, 1e-14 * (1 + std::abs(accel)));
        EXPECT_NEAR(d[3], r3, 1e-6 * (1 + std::abs(d[3])));
        EXPECT_NEAR(d[4], (dp[3] - dm[3]) / (2 * e), 1e-6 * (1 + std::abs(d[4])));
        // R⁽⁵⁾ by a central difference of R⁽⁴⁾, bounded by M5.
        EXPECT_LE(std::abs((dp[4] - dm[4]) / (2 * e)), M5 * (1 + 1e-6)) << "σ " << sg;
      }
      EXPECT_GT(scale, 0.1);
    }
  }
  EXPECT_GT(checked_taylor, 3000);
}

Scene Load(const std::string& name, const std::vector<std::string>& sets) {
  return LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + name, sets).scene;
}

// R of eq. (5), damped as docs/model.md §7, from a sampled state (this test's own formula).
double ReactionOf(const System& sys, const Eigen::VectorXd& X, const Eigen::VectorXd& V, double t) {
  double elastic = 0;
  for (int i = 0; i < sys.dof(); ++i) {
    const double w = sys.omega()[i];
    elastic += sys.contact_shape()[i] * (w * w * X[i] + 2 * sys.damping()[i] * w * V[i]);
  }
  return (elastic - sys.s_A() * sys.amplitude() * std::sin(sys.frequency() * t)) / sys.s_B();
}

// Every release of a run of `s` with its sticking phase longer than 20 samples: vibro's max R
// against this test's R of eq. (5) on the dense samples (at least every sample, and the vertex of
// the parabola through the three largest within 1e-10 when the largest is inside the phase). The
// number of phases checked.
int CheckAgainstSamples(Scene s, int spp, const std::string& what) {
  s.run.samples_per_period = spp;
  const System sys(s);
  Log log;
  LoadsRecorder rec(sys, 0);
  SimulationOptions opt;
  opt.observers = {&log, &rec};
  const RunResult r = vibro::Simulate(sys, s, opt);
  EXPECT_EQ(r.status, RunStatus::kOk) << what << ": " << r.message;
  const double h = sys.period() / spp;
  int checked = 0;
  for (const Event& e : log.events) {
    if (e.kind != EventKind::kRelease || !(e.stick_duration > 20 * h)) continue;
    const double t1 = e.t, t0 = t1 - e.stick_duration;
    std::vector<double> Rs;
    for (const auto& row : log.samples)
      if (row.t >= t0 && row.t <= t1) Rs.push_back(ReactionOf(sys, row.X, row.V, row.t));
    if (Rs.size() < 10) continue;
    size_t k = 0;
    for (size_t i = 1; i < Rs.size(); ++i)
      if (Rs[i] > Rs[k]) k = i;
    const double top = Rs[k];
    const double scale = std::max(1.0, std::abs(top));
    // vibro's maximum is at least every sample's R (to rounding) ...
    EXPECT_GE(e.reaction_max, top - 1e-13 * scale) << what << " release at t = " << t1;
    if (k == 0 || k + 1 == Rs.size()) {
      // ... and at an end of the phase, at most one sample step of R above it.
      EXPECT_LE(e.reaction_max, top + std::abs(Rs[k == 0 ? 1 : k - 1] - top) + 1e-12 * scale) << what;
    } else {
      // ... and inside, the vertex of the parabola through the three largest samples, whose error
      // is of the order of R'''h³, the third difference there.
      const double a = Rs[k - 1], b = Rs[k], d = Rs[k + 1];
      const double vertex = b + (d - a) * (d - a) / (8 * (2 * b - a - d));
      const auto third = [&](size_t i) { return std::abs(Rs[i + 3] - 3 * Rs[i + 2] + 3 * Rs[i + 1] - Rs[i]); };
      const double d3 = k + 2 < Rs.size() ? third(k - 1) : k >= 2 ? third(k - 2) : 0.0;
      EXPECT_NEAR(e.reaction_max, vertex, 1e-10 * scale + d3) << what << " release at t = " << t1;
    }
    ++checked;
  }
  return checked;
}

TEST(LoadsMaxR, MaximumAgainstDenseSamples) {
  struct Case {
    const char* file;
    std::vector<std::string> sets;
  };
  const std::vector<Case> cases = {
      {"chain3.toml", {}},
      {"chain3.toml", {"excitation.frequency=0.7", "excitation.amplitude=1.3"}},
      {"chain3.toml", {"stop.restitution=0.5"}},
      {"chain3.toml", {"run.engine=\"cvode\"", "run.rtol=1e-12", "run.atol=1e-14"}},
      {"chain3.toml", {"run.precision=\"quad\""}},
      {"chain2_damped.toml", {}},
      {"fig08_preload.toml", {}},
  };
  int phases = 0;
  for (const Case& c : cases) {
    Scene s = Load(c.file, c.sets);
    s.run.periods = 10;
    const int here = CheckAgainstSamples(s, 20000, c.file + (c.sets.empty() ? std::string() : " " + c.sets[0]));
    EXPECT_GE(here, 2) << c.file << (c.sets.empty() ? "" : " " + c.sets[0]);
    phases += here;
  }
  EXPECT_GE(phases, 25);
}

// Random chains of 2 to 5 masses and springs, undamped or with modal damping, forced on a random
// mass, preloaded against a stop on another with r ∈ {0, 0.3, 0.6}, over random ω and f: the worst
// case of the search (several modes, maxima anywhere in the phase, transients), against the samples.
TEST(LoadsMaxR, RandomStickingChains) {
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int scenes = 0, phases = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 2 + static_cast<int>(u(rng) * 4.0);
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n), K = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; ++i) M(i, i) = 0.5 + 1.5 * u(rng);
    for (int i = 0; i < n; ++i) {
      const double k = 0.5 + 1.5 * u(rng);
      K(i, i) += k;
      if (i > 0) {
        K(i - 1, i - 1) += k;
        K(i - 1, i) -= k;
        K(i, i - 1) -= k;
      }
    }
    Scene s;
    s.physical = PhysicalStructureSpec{M, K, static_cast<int>(u(rng) * n), static_cast<int>(u(rng) * n)};
    const double restitutions[] = {0.0, 0.3, 0.6};
    s.restitution = restitutions[static_cast<int>(u(rng) * 3.0)];
    s.frequency = 0.3 + 1.7 * u(rng);
    s.amplitude = 0.5 + 2.5 * u(rng);
    s.stop_position = 0.05 + 0.5 * u(rng);
    if (u(rng) < 0.4) {
      s.damping_ratios.resize(n);
      for (int i = 0; i < n; ++i) s.damping_ratios[i] = 0.01 + 0.1 * u(rng);
    }
    s.run.periods = 8;
    // Samples about 4e-4 apart whatever the period.
    const int spp = std::max(4000, static_cast<int>(2 * M_PI / s.frequency / 4e-4));
    const int here = CheckAgainstSamples(s, spp, "random chain " + std::to_string(trial));
    scenes += here > 0;
    phases += here;
  }
  std::printf("random chains: %d phases in %d scenes that stick\n", phases, scenes);
  EXPECT_GE(scenes, 10);
  EXPECT_GE(phases, 60);
}

}  // namespace
}  // namespace vibro::test
