// Newton from a given state (orbit_from_state.hpp): Fig. 5's unstable single-impact orbit from
// its impact state given by the closed form (not by vibro), the 2-DOF chain's sticking orbit from
// its release state, and the distance reported for starts near and far from an orbit.
#include <cmath>

#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

OrbitRequest Kind(OrbitKind kind) {
  OrbitRequest r;
  r.kind = kind;
  return r;
}

Scene Shipped(const char* file, std::vector<std::string> sets = {}) {
  sets.push_back("run.samples_per_period=0");
  return LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, sets).scene;
}

// Period-1 single-impact orbits of ẍ + x = f sin ωt, x ≥ x0, restitution r (undamped 1-DOF).
// With P = f/(1 − ω²), τ = T = 2π/ω, c = cos τ, s = sin τ, the flight from the impact at phase φ
// with x = x0, ẋ = v⁺ is x(t) = A cos(t − t_i) + B sin(t − t_i) + P sin ωt, A = x0 − P sin φ,
// B = v⁺ − Pω cos φ. Returning to x0 with ẋ⁻ = −v⁺/r one period later gives two equations linear
// in (sin φ, cos φ, v⁺):
//   P(1−c) sin φ − Pω s cos φ + s v⁺ = x0 (1−c)
//   P s sin φ + Pω (1−c) cos φ + (c + 1/r) v⁺ = x0 s
// Eliminating v⁺ leaves α sin φ + β cos φ = γ, i.e. ρ sin(φ + δ) = γ: two phases.
struct ImpactOrbit {
  double phase, v_plus;
};
std::vector<ImpactOrbit> ClosedFormImpactOrbits(double r, double w, double f, double x0) {
  const double P = f / (1.0 - w * w), tau = 2.0 * M_PI / w, c = std::cos(tau), s = std::sin(tau);
  const double k = c + 1.0 / r;
  const double alpha = P * (1.0 - c) * k - P * s * s;
  const double beta = -P * w * s * k - P * w * (1.0 - c) * s;
  const double gamma = x0 * (1.0 - c) * k - x0 * s * s;
  const double rho = std::hypot(alpha, beta), delta = std::atan2(beta, alpha);
  std::vector<ImpactOrbit> out;
  for (double a : {std::asin(gamma / rho), M_PI - std::asin(gamma / rho)}) {
    const double phi = std::fmod(a - delta + 4.0 * M_PI, 2.0 * M_PI);
    const double v = (x0 * (1.0 - c) - P * (1.0 - c) * std::sin(phi) + P * w * s * std::cos(phi)) / s;
    out.push_back({phi, v});
  }
  return out;
}

TEST(OrbitFromState, Fig5UnstableImpactOrbitFromItsImpactStateExactly) {
  const Scene scene = Shipped("fig05_coexistence.toml");
  const System sys(scene);
  const double r = sys.restitution(), w = sys.frequency();
  // The closed-form orbit the issue quotes: impact phase ≈ 5.1387, v⁺ ≈ 0.27569.
  ImpactOrbit exact{0, 0};
  for (const auto& o : ClosedFormImpactOrbits(r, w, sys.amplitude(), sys.stop()))
    if (o.v_plus > 0 && std::abs(o.phase - 5.1387) < 1e-3) exact = o;
  ASSERT_NEAR(exact.phase, 5.1387, 1e-4);
  ASSERT_NEAR(exact.v_plus, 0.27569, 1e-5);

  // Start exactly at the impact instant, just after the impact.
  const InitialOverride start{exact.phase / w, Eigen::VectorXd::Constant(1, sys.stop()),
                              Eigen::VectorXd::Constant(1, exact.v_plus)};
  OrbitRequest req;
  req.kind = OrbitKind::kAuto;
  const OrbitResult o = OrbitFromState(sys, scene, start, req);
  ASSERT_EQ(o.status, "converged") << o.message;
  EXPECT_TRUE(o.message.empty()) << o.message;
  EXPECT_EQ(o.period, 1);
  EXPECT_EQ(o.summary.kind, "impact-periodic");
  ASSERT_TRUE(o.distance_from_start);
  EXPECT_LT(*o.distance_from_start, 1e-12);
  ASSERT_EQ(o.summary.impact_phases.size(), 1u);
  EXPECT_NEAR(o.summary.impact_phases[0], exact.phase, 1e-11);
  EXPECT_NEAR(o.summary.impact_velocities[0], -exact.v_plus / r, 1e-11);
  // A real multiplier > 1 (≈ 4.26), and det DP = r² (undamped flow: det 1; impact saltation
  // [[−r, 0], [(1+r)a/v, −r]]: det r²).
  ASSERT_EQ(o.multipliers.size(), 2u);
  EXPECT_EQ(o.multipliers[0].imag(), 0.0);
  EXPECT_GT(o.multipliers[0].real(), 1.0);
  EXPECT_NEAR(o.multipliers[0].real(), 4.26, 0.01);
  EXPECT_NEAR(std::abs(o.multipliers[0] * o.multipliers[1]), r * r, 1e-10);
  EXPECT_NEAR(o.monodromy.determinant(), r * r, 1e-10);
  EXPECT_FALSE(o.stable);

  // The same start through SolveOrbit without a transient; with the default transient, the
  // start runs off to the stable sticking orbit, and the result says it is far from the start.
  OrbitRequest none = req;
  none.start = start;
  none.transient_periods = 0;
  const OrbitResult again = SolveOrbit(sys, scene, none);
  ASSERT_EQ(again.status, "converged");
  EXPECT_EQ(again.summary.kind, "impact-periodic");
  OrbitRequest after = none;
  after.transient_periods = 200;
  const OrbitResult settled = SolveOrbit(sys, scene, after);
  ASSERT_EQ(settled.status, "converged");
  EXPECT_EQ(settled.summary.kind, "sticking-periodic");
  ASSERT_TRUE(settled.distance_from_start);
  EXPECT_GT(*settled.distance_from_start, 1e-2);
  EXPECT_NE(settled.message.find("from the start state"), std::string::npos) << settled.message;
}

TEST(OrbitFromState, DistanceScalesWithTheOffsetOfTheStart) {
  const Scene scene = Shipped("fig05_coexistence.toml");
  const System sys(scene);
  ImpactOrbit exact{0, 0};
  for (const auto& o : ClosedFormImpactOrbits(sys.restitution(), sys.frequency(), sys.amplitude(), sys.stop()))
    if (o.v_plus > 0 && std::abs(o.phase - 5.1387) < 1e-3) exact = o;
  for (double eps : {1e-9, 1e-7, 1e-4}) {
    const InitialOverride start{exact.phase / sys.frequency(), Eigen::VectorXd::Constant(1, sys.stop()),
                                Eigen::VectorXd::Constant(1, exact.v_plus + eps)};
    const OrbitResult o = OrbitFromState(sys, scene, start, Kind(OrbitKind::kImpact));
    ASSERT_EQ(o.status, "converged") << eps;
    // Newton returns to the same unstable orbit; the distance is O(eps) (the flow over part of a
    // period magnifies a velocity offset by at most a few).
    EXPECT_NEAR(o.multipliers[0].real(), 4.2553, 1e-3);
    EXPECT_GT(*o.distance_from_start, 0.1 * eps);
    EXPECT_LT(*o.distance_from_start, 10.0 * eps);
    // The "not on this orbit" note comes above 1e-6.
    EXPECT_EQ(o.message.empty(), eps < 1e-6) << o.message;
  }
}

// Catches the state just after the first release of a run.
struct ReleaseCatcher final : Observer {
  bool caught = false;
  double phase = 0;
  Eigen::VectorXd X, V;
  void OnReset(const Reset& r) override {
    if (caught || r.kind != ResetKind::kRelease) return;
    caught = true;
    phase = r.phase;
    X = r.X_after;
    V = r.V_after;
  }
};

TEST(OrbitFromState, Chain2StickingOrbitFromItsReleaseStateExactly) {
  const Scene scene = Shipped("chain2.toml");
  const System sys(scene);
  // The orbit after a transient, then its release state, found by simulating one period of it.
  const OrbitResult ref = SolveOrbit(sys, scene, Kind(OrbitKind::kSticking));
  ASSERT_EQ(ref.status, "converged") << ref.message;
  ReleaseCatcher catcher;
  Scene sc = scene;
  sc.run.periods = ref.period;
  const InitialOverride here{ref.section_time, ref.X, ref.V};
  SimulationOptions opt;
  opt.initial = &here;
  opt.observers = {&catcher};
  Simulate(sys, sc, opt);
  ASSERT_TRUE(catcher.caught);
  // At the release B is on the stop at rest with R = 0.
  EXPECT_NEAR(sys.ContactDisplacement(catcher.X), sys.stop(), 1e-12);
  EXPECT_NEAR(sys.ContactVelocity(catcher.V), 0.0, 1e-12);
  EXPECT_NEAR(sys.Reaction(catcher.X, catcher.V, catcher.phase), 0.0, 1e-10);

  const InitialOverride start{catcher.phase / sys.frequency(), catcher.X, catcher.V};
  const OrbitResult o = OrbitFromState(sys, scene, start, Kind(OrbitKind::kAuto));
  ASSERT_EQ(o.status, "converged") << o.message;
  EXPECT_EQ(o.period, 1);
  EXPECT_EQ(o.summary.kind, "sticking-periodic");
  EXPECT_LT(*o.distance_from_start, 1e-9);
  EXPECT_TRUE(o.stable);
  // The release phase is the end of the orbit's sticking phase.
  ASSERT_EQ(o.summary.stick_phases.size(), 1u);
  EXPECT_NEAR(std::remainder(o.summary.stick_phases[0].second - catcher.phase, 2 * M_PI), 0.0, 1e-8);
  // An independent engine: CVODE (rtol 1e-12) simulating from the rest state settles on the same
  // sticking fraction.
  Scene cv = scene;
  cv.run.engine = Engine::kCvode;
  cv.run.rtol = 1e-12;
  cv.run.atol = 1e-14;
  AttractorRecorder rec(sys, cv);
  SimulationOptions copt;
  copt.observers = {&rec};
  Simulate(sys, cv, copt);
  const Attractor a = rec.Classify();
  ASSERT_EQ(a.kind, "sticking-periodic");
  EXPECT_NEAR(*o.summary.sticking_fraction, *a.sticking_fraction, 1e-7);
}

TEST(OrbitFromState, AStartAtRestOnTheStopReachesThePeriodOneOrbit) {
  // The default [initial] state (at rest on the stop) is not on the orbit: Newton from it
  // converges, reports the distance, and the first return after two periods is reduced to the
  // orbit's own period.
  const Scene scene = Shipped("chain2.toml");
  const System sys(scene);
  OrbitRequest req;
  req.transient_periods = 0;
  const OrbitResult o = SolveOrbit(sys, scene, req);
  ASSERT_EQ(o.status, "converged") << o.message;
  EXPECT_EQ(o.period, 1);
  EXPECT_GT(*o.distance_from_start, 1e-2);
  EXPECT_NE(o.message.find("not on this orbit"), std::string::npos);
}

}  // namespace
}  // namespace vibro::test
