// Poincaré solver (docs/model.md §5): the analytic Jacobian against finite differences of the simulated
// map, 1-DOF orbits against the closed forms of §6, Newton from a short transient, an unstable
// orbit, and the multipliers against the decay of the transient and the CVODE engine.
#include <cmath>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/poincare.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

Scene Shipped(const char* file, std::vector<std::string> sets = {}) {
  sets.push_back("run.samples_per_period=0");
  return LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, sets).scene;
}

// Central differences of F(z) = z(t0 + qT) at the orbit point.
Eigen::MatrixXd FiniteDifferences(const System& sys, const Scene& scene, const OrbitResult& o,
                                  double h) {
  const auto n = sys.dof();
  Eigen::VectorXd z(2 * n);
  z << o.X, o.V;
  Eigen::MatrixXd J(2 * n, 2 * n);
  for (Eigen::Index j = 0; j < 2 * n; ++j) {
    Eigen::VectorXd zp = z, zm = z;
    zp[j] += h;
    zm[j] -= h;
    const auto fp = StroboscopicMap(sys, scene, o.section_time, zp.head(n), zp.tail(n), o.period);
    const auto fm = StroboscopicMap(sys, scene, o.section_time, zm.head(n), zm.tail(n), o.period);
    Eigen::VectorXd a(2 * n), b(2 * n);
    a << fp.X, fp.V;
    b << fm.X, fm.V;
    J.col(j) = (a - b) / (2 * h);
  }
  return J;
}

void CheckJacobian(const Scene& scene, OrbitKind kind, int period = 0) {
  const System sys(scene);
  OrbitRequest req;
  req.kind = kind;
  req.period = period;
  const OrbitResult o = FindOrbit(sys, scene, req);
  ASSERT_EQ(o.status, "converged") << o.message;
  const Eigen::MatrixXd fd = FiniteDifferences(sys, scene, o, 1e-6);
  const double scale = 1.0 + o.monodromy.cwiseAbs().maxCoeff();
  EXPECT_LT((o.monodromy - fd).cwiseAbs().maxCoeff(), 2e-5 * scale)
      << "analytic\n" << o.monodromy << "\nfinite differences\n" << fd;
}

TEST(Poincare, AnalyticJacobianMatchesFiniteDifferences) {
  {
    SCOPED_TRACE("2-DOF, r = 0.5, chattering");
    CheckJacobian(Shipped("chain2.toml"), OrbitKind::kSticking);
  }
  {
    SCOPED_TRACE("2-DOF, r = 0");
    CheckJacobian(Shipped("chain2.toml", {"stop.restitution=0.0"}), OrbitKind::kSticking);
  }
  {
    SCOPED_TRACE("3-DOF, r = 0");
    CheckJacobian(Shipped("chain3.toml"), OrbitKind::kSticking);
  }
  {
    SCOPED_TRACE("2-DOF damped, r = 0.5");
    CheckJacobian(Shipped("chain2_damped.toml"), OrbitKind::kSticking);
  }
  {
    SCOPED_TRACE("10-DOF stiff chain, 5 % damping");
    CheckJacobian(Shipped("chain10_stiff.toml", {"structure.damping_ratios=[0.05, 0.05, 0.05, 0.05, "
                                                 "0.05, 0.05, 0.05, 0.05, 0.05, 0.05]"}),
                  OrbitKind::kSticking);
  }
  {
    SCOPED_TRACE("3-DOF impact orbit, r = 0.5");
    CheckJacobian(Shipped("chain3.toml", {"stop.restitution=0.5", "excitation.frequency=2.0",
                                          "excitation.amplitude=2.0"}),
                  OrbitKind::kImpact, 1);
  }
}

TEST(Poincare, OneDofOrbitsMatchTheClosedForms) {
  // docs/model.md §6 (r = 0): SP = 1 − ω(t'_0 − t'_1)/(2πq); DP is empty (superstable).
  for (double w : {2.8, 5.0, 10.0}) {
    const double f = 1.5;
    const Scene s = OneDof(0.0, w, f, 1.0, 50);
    const System sys(s);
    const OrbitResult o = FindOrbit(sys, s, {});
    ASSERT_EQ(o.status, "converged") << o.message;
    const LD t1 = ReleaseTime(w, f);
    const LD t0 = Flight1{w, f, t1, 1, 0}.Landing(1);
    const int q = static_cast<int>(std::ceil(w * (t0 - t1) / (2 * M_PIl)));
    EXPECT_EQ(o.period, q);
    ASSERT_TRUE(o.summary.sticking_fraction.has_value());
    EXPECT_NEAR(*o.summary.sticking_fraction, static_cast<double>(1 - w * (t0 - t1) / (2 * M_PIl * q)),
                1e-12);
    EXPECT_TRUE(o.multipliers.empty());
    EXPECT_TRUE(o.stable);
    EXPECT_LT(o.monodromy.cwiseAbs().maxCoeff(), 1e-12);  // the stroboscopic Jacobian is 0
  }
}

TEST(Poincare, Fig5CoexistingSingleImpactOrbitHasMultipliersOfModulusR) {
  // docs/model.md §5.6: Fig. 5, (r, ω, f, x0) = (0.75, 10, 1.1, 1): a stable single-impact period-1 orbit
  // coexists with the sticking one; its impact map has det = r², so a complex pair of multipliers
  // has modulus exactly r.
  const Scene s = Shipped("fig05_coexistence.toml");
  const System sys(s);
  OrbitRequest req;
  req.kind = OrbitKind::kImpact;
  const OrbitResult o = FindOrbit(sys, s, req);
  ASSERT_EQ(o.status, "converged") << o.message;
  EXPECT_EQ(o.summary.kind, "impact-periodic");
  EXPECT_EQ(o.period, 1);
  EXPECT_EQ(o.summary.impacts_per_period, 1);
  ASSERT_EQ(o.multipliers.size(), 2u);
  for (const auto& m : o.multipliers) {
    EXPECT_NEAR(std::abs(m), 0.75, 1e-10);
    EXPECT_GT(std::abs(m.imag()), 0.1);  // a complex pair
  }
  EXPECT_NEAR(std::abs(o.multipliers[0] * o.multipliers[1]), 0.75 * 0.75, 1e-10);
  EXPECT_TRUE(o.stable);
  // And the sticking orbit of the same scene.
  const OrbitResult st = FindOrbit(sys, s, {});
  ASSERT_EQ(st.status, "converged");
  EXPECT_EQ(st.summary.kind, "sticking-periodic");
}

TEST(Poincare, ConvergesFromAShortTransientInAHandfulOfIterations) {
  const Scene s = Shipped("chain2.toml");
  const System sys(s);
  OrbitRequest quick;
  quick.transient_periods = 4;
  const OrbitResult a = FindOrbit(sys, s, quick);
  const OrbitResult b = FindOrbit(sys, s, {});
  ASSERT_EQ(a.status, "converged") << a.message;
  EXPECT_GE(a.newton_iterations, 1);
  EXPECT_LE(a.newton_iterations, 8);
  EXPECT_LT(a.residual, 1e-12);
  EXPECT_NEAR(*a.summary.sticking_fraction, *b.summary.sticking_fraction, 1e-12);
}

TEST(Poincare, UnstableOrbitIsFoundAndReportedUnstable) {
  // 3-DOF chain, r = 0.5, ω = 2, f = 2: the one-impact period-1 orbit has a multiplier ≈ −1.47
  // (past a flip); the simulation never settles on it, Newton finds it.
  const Scene s = Shipped("chain3.toml", {"stop.restitution=0.5", "excitation.frequency=2.0",
                                          "excitation.amplitude=2.0"});
  const System sys(s);
  OrbitRequest req;
  req.kind = OrbitKind::kImpact;
  req.period = 1;
  const OrbitResult o = FindOrbit(sys, s, req);
  ASSERT_EQ(o.status, "converged") << o.message;
  EXPECT_FALSE(o.stable);
  ASSERT_FALSE(o.multipliers.empty());
  const auto lead = o.multipliers.front();
  EXPECT_GT(std::abs(lead), 1.0);
  // Independent check: a tiny perturbation grows like |μ|^k under the simulation.
  const auto n = sys.dof();
  Eigen::VectorXd X = o.X, V = o.V;
  X[0] += 1e-9;
  double d0 = 1e-9, growth = 0;
  for (int k = 0; k < 8; ++k) {
    const auto m = StroboscopicMap(sys, s, o.section_time, X, V, 1);
    X = m.X;
    V = m.V;
    Eigen::VectorXd dz(2 * n);
    dz << X - o.X, V - o.V;
    growth = dz.norm() / d0;
  }
  EXPECT_GT(growth, 10.0);  // |μ|⁸ ≈ 22 for |μ| = 1.47
}

TEST(Poincare, MultipliersMatchTheTransientDecayAndTheCvodeMap) {
  const Scene s = Shipped("chain2.toml");
  const System sys(s);
  const OrbitResult o = FindOrbit(sys, s, {});
  ASSERT_EQ(o.status, "converged");
  const double rho = std::abs(o.multipliers.front());
  // Decay of the distance to the orbit along a transient started off it.
  Eigen::VectorXd X = o.X, V = o.V;
  X[0] += 1e-4;
  std::vector<double> dist;
  for (int k = 0; k < 12; ++k) {
    const auto m = StroboscopicMap(sys, s, o.section_time, X, V, 1);
    X = m.X;
    V = m.V;
    Eigen::VectorXd dz(4);
    dz << X - o.X, V - o.V;
    dist.push_back(dz.norm());
  }
  // Complex pair: the distance decays like ρᵏ on average (over two steps).
  const double observed = std::sqrt(dist[9] / dist[7]);
  EXPECT_NEAR(observed, rho, 0.05 * rho);
  // The stroboscopic Jacobian of the CVODE engine, by finite differences, has the same non-zero
  // spectrum (docs/model.md §5.6).
  Scene c = s;
  c.run.engine = Engine::kCvode;
  c.run.rtol = 1e-12;
  c.run.atol = 1e-14;
  const Eigen::MatrixXd J = FiniteDifferences(sys, c, o, 1e-5);
  Eigen::ComplexEigenSolver<Eigen::MatrixXcd> es(J.cast<std::complex<double>>());
  double lead = 0;
  for (Eigen::Index i = 0; i < es.eigenvalues().size(); ++i) lead = std::max(lead, std::abs(es.eigenvalues()[i]));
  EXPECT_NEAR(lead, rho, 1e-3);
}


TEST(Poincare, OrbitNearTheEndOfStickingTakesTheQuadFallbackAndIsAFixedPointOfTheQuadMap) {
  // Issue 24 item 7: the 2-DOF chain at ω = 0.8, 1e-10 and 1e-11 below the end of its sticking
  // branch (f_max = 1.2062880835761711, located by continuation with quad evaluations). Double
  // leaves the chattering tails undetermined there; the orbit solver redoes those evaluations in
  // quad and converges. Independent truth: the quad engine's map returns the orbit's section
  // point to itself.
  const double f_max = 1.2062880835761711;
  for (double df : {1e-10, 1e-11}) {
    SCOPED_TRACE(df);
    const Scene sc = LoadScene(std::string(VIBRO_SCENES_DIR) + "/chain2.toml",
                               {"run.samples_per_period=0", fmt::format("excitation.amplitude={:.17g}", f_max - df)})
                         .scene;
    const System sys(sc);
    const OrbitResult o = SolveOrbit(sys, sc, OrbitRequest{});
    ASSERT_EQ(o.status, "converged") << o.message;
    EXPECT_GT(o.quad_evaluations, 0);
    EXPECT_EQ(o.summary.kind, "sticking-periodic");
    EXPECT_GT(o.summary.sticking_fraction.value_or(0), 0.0);
    Scene quad = sc;
    quad.run.precision = Precision::kQuad;
    const MapValue m = StroboscopicMap(sys, quad, o.section_time, o.X, o.V, o.period);
    ASSERT_EQ(m.status, RunStatus::kOk);
    EXPECT_LT(std::max((m.X - o.X).cwiseAbs().maxCoeff(), (m.V - o.V).cwiseAbs().maxCoeff()), 1e-10);
  }
}

}  // namespace
}  // namespace vibro::test
