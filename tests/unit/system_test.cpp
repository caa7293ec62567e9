// Structural model (docs/model.md §1.3, §4.2): modal data against the physical matrices.
#include "vibro/system.hpp"

#include <cmath>
#include <random>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "vibro/scene_file.hpp"
#include "vibro/observer.hpp"
#include "vibro/simulator.hpp"

namespace vibro {
namespace {

Scene PhysicalScene(const Eigen::MatrixXd& M, const Eigen::MatrixXd& K, int a, int b,
                    double x0 = 1.0) {
  Scene s;
  s.physical = PhysicalStructureSpec{M, K, a, b};
  s.stop_position = x0;
  s.restitution = 0.5;
  s.amplitude = 1.0;
  s.frequency = 1.3;
  return s;
}

// A random lumped chain ground -k0- m0 -k1- m1 ... with optional extra springs to ground.
Scene RandomChain(std::mt19937& gen, int n, int a, int b) {
  std::uniform_real_distribution<double> u(0.5, 2.0);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n), K = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    M(i, i) = u(gen);
    K(i, i) += 0.3 * u(gen);  // to ground
  }
  for (int i = 1; i < n; ++i) {
    const double k = u(gen);
    K(i - 1, i - 1) += k;
    K(i, i) += k;
    K(i - 1, i) -= k;
    K(i, i - 1) -= k;
  }
  return PhysicalScene(M, K, a, b);
}

Eigen::MatrixXd Without(const Eigen::MatrixXd& m, int b) {
  const auto n = m.rows();
  Eigen::MatrixXd out(n - 1, n - 1);
  for (Eigen::Index i = 0, r = 0; i < n; ++i) {
    if (i == b) continue;
    for (Eigen::Index j = 0, c = 0; j < n; ++j) {
      if (j == b) continue;
      out(r, c++) = m(i, j);
    }
    ++r;
  }
  return out;
}

TEST(System, TwoDofExampleOfModelSection13) {
  // docs/model.md §1.3: m1 = m2 = 1, k1 = k2 = 1, stop on mass 2, force on mass 1.
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(2, 2), K(2, 2);
  K << 2, -1, -1, 1;
  const System sys(PhysicalScene(M, K, 0, 1));
  const double r5 = std::sqrt(5.0);
  EXPECT_NEAR(sys.omega()[0], std::sqrt((3 - r5) / 2), 1e-12);
  EXPECT_NEAR(sys.omega()[1], std::sqrt((3 + r5) / 2), 1e-12);
  EXPECT_NEAR(sys.mode_shapes()(0, 0), (r5 - 1) / 2, 1e-12);   // ψ_1 = (0.618034, 1)
  EXPECT_NEAR(sys.mode_shapes()(0, 1), -(r5 + 1) / 2, 1e-12);  // ψ_2 = (−1.618034, 1)
  EXPECT_NEAR(sys.contact()[0], (5 + r5) / 10, 1e-12);         // 0.723607
  EXPECT_NEAR(sys.contact()[1], (5 - r5) / 10, 1e-12);         // 0.276393
  EXPECT_NEAR(sys.forcing()[0], 1 / r5, 1e-12);
  EXPECT_NEAR(sys.forcing()[1], -1 / r5, 1e-12);
  EXPECT_NEAR(sys.s_B(), 1.0, 1e-12);
  EXPECT_NEAR(sys.s_A(), 0.0, 1e-12);
  ASSERT_EQ(sys.constrained().frequencies.size(), 1);
  EXPECT_NEAR(sys.constrained().frequencies[0], std::sqrt(2.0), 1e-12);
  ASSERT_TRUE(sys.static_reaction().has_value());
  EXPECT_NEAR(*sys.static_reaction(), 0.5, 1e-12);  // x0/2
}

TEST(System, ModalIdentitiesOnRandomChains) {
  std::mt19937 gen(12345);
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 2 + trial % 5;
    const int a = static_cast<int>(gen() % static_cast<unsigned>(n));
    const int b = static_cast<int>(gen() % static_cast<unsigned>(n));
    const Scene scene = RandomChain(gen, n, a, b);
    const System sys(scene);
    const auto& M = scene.physical->mass;
    const auto& K = scene.physical->stiffness;
    const Eigen::MatrixXd Minv = M.inverse(), Kinv = K.inverse();
    SCOPED_TRACE(testing::Message() << "n=" << n << " A=" << a << " B=" << b);
    ASSERT_EQ(sys.dof(), n);
    EXPECT_NEAR(sys.s_B(), Minv(b, b), 1e-12 * Minv(b, b));
    EXPECT_NEAR(sys.s_A(), Minv(a, b), 1e-12 * Minv(b, b));
    const Eigen::VectorXd w2 = sys.omega().cwiseAbs2();
    EXPECT_NEAR(sys.contact().cwiseQuotient(w2).sum(), Kinv(b, b), 1e-11 * Kinv(b, b));
    EXPECT_NEAR(sys.forcing().cwiseQuotient(w2).sum(), Kinv(a, b), 1e-11 * Kinv(b, b));
    EXPECT_NEAR(sys.flexibility(), Kinv(b, b), 1e-11 * Kinv(b, b));
    for (int i = 0; i < n; ++i) {
      EXPECT_GT(sys.contact()[i], 0.0);
      EXPECT_NEAR(sys.mode_shapes()(b, i), 1.0, 1e-14);
    }
    if (a != b) {
      EXPECT_NEAR(sys.s_A(), 0.0, 1e-12);  // lumped masses: s_A = (M⁻¹)_AB = 0
    }

    // Constrained pulsations = eigenfrequencies of the structure with DOF B clamped.
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> clamped(Without(K, b), Without(M, b));
    const Eigen::VectorXd expected = clamped.eigenvalues().cwiseSqrt();
    ASSERT_EQ(sys.constrained().frequencies.size(), n - 1);
    for (int k = 0; k < n - 1; ++k)
      EXPECT_NEAR(sys.constrained().frequencies[k], expected[k], 1e-11 * expected[k]);
  }
}

TEST(System, ConstrainedModesDiagonaliseTheStickingOperator) {
  // A = Ω − T_B (c∘w2)ᵀ/s_B (docs/model.md §4.2): A v_k = ω'_k² v_k, cᵀv_k = 0, L E = I, cᵀF_c = 0.
  std::mt19937 gen(7);
  for (int n = 2; n <= 6; ++n) {
    const System sys(RandomChain(gen, n, 0, n - 1));
    const auto& cm = sys.constrained();
    const Eigen::VectorXd w2 = sys.omega().cwiseAbs2();
    const Eigen::MatrixXd A =
        Eigen::MatrixXd(w2.asDiagonal()) -
        sys.contact() * sys.contact_shape().cwiseProduct(w2).transpose() / sys.s_B();
    EXPECT_NEAR((A * sys.static_shape()).norm(), 0.0, 1e-12);
    for (int k = 0; k < n - 1; ++k) {
      const Eigen::VectorXd v = cm.vectors.col(k);
      const double l2 = cm.frequencies[k] * cm.frequencies[k];
      EXPECT_NEAR((A * v - l2 * v).norm(), 0.0, 1e-11 * (1 + l2) * v.norm());
      EXPECT_NEAR(sys.contact_shape().dot(v), 0.0, 1e-12 * v.norm());
      EXPECT_NEAR(cm.left.row(k).dot(sys.static_shape()), 0.0, 1e-12);
      for (int j = 0; j < n - 1; ++j)
        EXPECT_NEAR(cm.left.row(k).dot(cm.vectors.col(j)), k == j ? 1.0 : 0.0, 1e-12);
    }
    const Eigen::VectorXd Fc = sys.forcing() - sys.s_A() / sys.s_B() * sys.contact();
    EXPECT_NEAR(sys.contact_shape().dot(Fc), 0.0, 1e-12);
    EXPECT_NEAR((cm.left * Fc - cm.modal_forcing).norm(), 0.0, 1e-12);
    // Reaction at the static equilibrium with f = 0 equals x0/flexibility.
    const Eigen::VectorXd X = sys.stop() * sys.static_shape();
    EXPECT_NEAR(sys.Reaction(X, Eigen::VectorXd::Zero(n), 0.0), *sys.static_reaction(), 1e-12);
  }
}

TEST(System, ConstrainedDampingIsTheProjectedDamping) {
  // docs/model.md §7: on the stop Ẍ = −AX − ΠDẊ + F_c f sin ωt. With Ẋ = V ξ̇ the damping force ΠDVξ̇ lies
  // in span(V), and must equal V D' ξ̇ for the reduced matrix D' of the constrained modes.
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> u(0.0, 0.2);
  for (int n = 2; n <= 5; ++n) {
    Scene scene = RandomChain(gen, n, 0, n - 1);
    scene.damping_ratios = Eigen::VectorXd::NullaryExpr(n, [&] { return u(gen); });
    const System sys(scene);
    const auto& cm = sys.constrained();
    const Eigen::MatrixXd Pi =
        Eigen::MatrixXd::Identity(n, n) - sys.contact() * sys.contact_shape().transpose() / sys.s_B();
    const Eigen::VectorXd D = 2.0 * sys.damping().cwiseProduct(sys.omega());
    const Eigen::MatrixXd full = Pi * D.asDiagonal() * cm.vectors;
    EXPECT_NEAR((cm.vectors * cm.damping - full).norm(), 0.0, 1e-12 * (1 + full.norm())) << n;
  }
}

TEST(System, ModeWithNodeAtBIsKeptOutOfTheContact) {
  // Symmetric chain ground-k-m-k-m-k-m-k-ground with B at the middle mass: the antisymmetric
  // mode has a node at B.
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(3, 3), K(3, 3);
  K << 2, -1, 0, -1, 2, -1, 0, -1, 2;
  const System sys(PhysicalScene(M, K, 0, 1));
  int invisible = 0;
  for (int i = 0; i < 3; ++i) {
    if (sys.contact_shape()[i] == 0.0) {
      ++invisible;
      EXPECT_EQ(sys.contact()[i], 0.0);
      EXPECT_NEAR(sys.omega()[i], std::sqrt(2.0), 1e-12);  // antisymmetric mode: ω² = 2
      EXPECT_NEAR(std::abs(sys.forcing()[i]), 1 / std::sqrt(2.0), 1e-12);  // mass-normalised
    }
  }
  EXPECT_EQ(invisible, 1);
  EXPECT_NEAR(sys.s_B(), 1.0, 1e-12);  // (M⁻¹)_BB
  EXPECT_NEAR(sys.flexibility(), K.inverse()(1, 1), 1e-12);
  // Clamping B leaves two masses on springs 2 (each tied to ground and to the clamp): ω'² = 2, 2.
  ASSERT_EQ(sys.constrained().frequencies.size(), 2);
  EXPECT_NEAR(sys.constrained().frequencies[0], std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(sys.constrained().frequencies[1], std::sqrt(2.0), 1e-12);
}

TEST(System, ModalTruncationKeepsTheLowestModes) {
  std::mt19937 gen(3);
  Scene scene = RandomChain(gen, 5, 0, 4);
  const System full(scene);
  scene.modes = 2;
  const System cut(scene);
  ASSERT_EQ(cut.dof(), 2);
  EXPECT_DOUBLE_EQ(cut.omega()[0], full.omega()[0]);
  EXPECT_DOUBLE_EQ(cut.omega()[1], full.omega()[1]);
  EXPECT_DOUBLE_EQ(cut.contact()[1], full.contact()[1]);
}

TEST(System, ModalFormTruncationSelectsLowestFrequencies) {
  const auto loaded = ParseScene(R"(
[structure]
frequencies = [3.0, 1.0, 2.0]
forcing = [0.3, 0.1, 0.2]
contact = [3.5, 1.5, 2.5]
modes = 2
[stop]
position = 1.0
restitution = 0.5
[excitation]
amplitude = 1.0
frequency = 2.0
[initial]
displacement = [30.0, 10.0, 20.0]
velocity = [0.0, 0.0, 0.0]
)",
                                 "inline");
  const System sys(loaded.scene);
  ASSERT_EQ(sys.dof(), 2);
  EXPECT_EQ(sys.omega()[0], 1.0);
  EXPECT_EQ(sys.omega()[1], 2.0);
  EXPECT_EQ(sys.forcing()[1], 0.2);
  EXPECT_EQ(sys.contact()[0], 1.5);
  const auto init = sys.Initial(loaded.scene);
  EXPECT_EQ(init.X[0], 10.0);
  EXPECT_EQ(init.X[1], 20.0);
}

TEST(System, DefaultInitialStateIsTheStaticPreloadEquilibrium) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(2, 2), K(2, 2);
  K << 2, -1, -1, 1;
  Scene scene = PhysicalScene(M, K, 0, 1, 1.0);
  const System sys(scene);
  const auto init = sys.Initial(scene);
  EXPECT_TRUE(init.sticking);
  EXPECT_NEAR(sys.ContactDisplacement(init.X), 1.0, 1e-15);
  // Physical displacement q = Ψ X: the static deflection under the preload reaction x0/2 at B
  // is q = K⁻¹ e_B · 0.5 = (0.5, 1).
  const Eigen::VectorXd q = sys.mode_shapes() * init.X;
  EXPECT_NEAR(q[0], 0.5, 1e-12);
  EXPECT_NEAR(q[1], 1.0, 1e-12);
  scene.stop_position = -1.0;
  const System clearance(scene);
  const auto origin = clearance.Initial(scene);
  EXPECT_FALSE(origin.sticking);
  EXPECT_EQ(origin.X.norm(), 0.0);
  EXPECT_FALSE(clearance.static_reaction().has_value());
}


TEST(System, DefaultStartAtRestOnTheStopIsOnItAndSticksFromTheStart) {
  // Issue 24 item 4: a random modal 3-DOF preload scene whose static equilibrium x0·T_B/s_B rounds
  // to 1 ulp above the stop. The truth sticks from t = 0: R(0) is the static reaction x0/δ > 0
  // (sin ωt = 0 at t = 0), so the run must stick at t = 0 and release next, with no impact before.
  const auto loaded = LoadScene(std::string(VIBRO_TEST_SCENES_DIR) + "/modal3_preload.toml");
  const Scene& scene = loaded.scene;
  const System sys(scene);
  const auto init = sys.Initial(scene);
  const double xB = sys.ContactDisplacement(init.X);
  EXPECT_LE(xB, scene.stop_position);
  EXPECT_GE(xB, scene.stop_position - sys.StopTolerance(init.X));
  ASSERT_TRUE(sys.static_reaction().has_value());
  EXPECT_GT(sys.Reaction(init.X, init.V, 0.0), 0.0);
  struct First final : Observer {
    std::vector<Event> events;
    void OnEvent(const Event& e) override { events.push_back(e); }
  } log;
  SimulationOptions opt;
  opt.observers = {&log};
  const RunResult r = Simulate(sys, scene, opt);
  ASSERT_EQ(r.status, RunStatus::kOk) << r.message;
  ASSERT_GE(log.events.size(), 2u);
  EXPECT_EQ(log.events[0].kind, EventKind::kStick) << "first event at t = " << log.events[0].t;
  EXPECT_EQ(log.events[0].t, 0.0);
  EXPECT_EQ(log.events[1].kind, EventKind::kRelease) << "second event at t = " << log.events[1].t;
  EXPECT_GT(log.events[1].t, 1e-3);
}

TEST(System, GivenStateWithinRoundingOfTheStopIsOnItAndAtRest) {
  // Issue 24 item 5: a state of the 2-DOF chain (physical form) on the stop whose contact velocity
  // is a rounding residue (ẋ_B = −2.8e-17) is accepted as at rest on the stop; one moving into the
  // stop (−1e-9) or below it (1e-9) stays refused.
  const std::string path = std::string(VIBRO_SCENES_DIR) + "/chain2.toml";
  const auto with = [&](double qB, double vB) {
    return LoadScene(path, {"initial.displacement=[0.4375, " + fmt::format("{:.17g}", qB) + "]",
                            "initial.velocity=[0.6251, " + fmt::format("{:.17g}", vB) + "]"});
  };
  const auto loaded = with(1.0, -2.8e-17);
  const System sys(loaded.scene);
  const auto init = sys.Initial(loaded.scene);
  EXPECT_LE(std::abs(sys.ContactDisplacement(init.X) - 1.0), sys.StopTolerance(init.X));
  EXPECT_LE(sys.ContactVelocity(init.V), 0.0);
  EXPECT_GE(sys.ContactVelocity(init.V), -sys.RestTolerance(init.V));
  for (double vB : {2.8e-17, 0.0}) EXPECT_NO_THROW(with(1.0, vB));
  EXPECT_THROW(with(1.0, -1e-9), InputError);
  EXPECT_THROW(with(1.0 - 1e-9, 0.0), InputError);
}

// [[contact]] in the modal form (docs/contacts.md, "the modal form"): contacts_chain2_modal.toml is
// contacts_chain2.toml with its modes derived in closed form (the scene's comment, g = (1 + √5)/2),
// so the two models must agree to rounding: every contact's shape c_j, T_j, stop and the Delassus
// matrix. Oracle by hand: W_00 = 1/m_1 = 1, W_11 = 1/m_0 = 1, W_01 = 0 (stops on different masses
// of a diagonal M, MODEL §11.1.3 in docs/contacts.md), whatever the modal data.
TEST(System, ModalFormContactsEqualThePhysicalForm) {
  const System physical(LoadScene(std::string(VIBRO_SCENES_DIR) + "/contacts_chain2.toml").scene);
  const System modal(LoadScene(std::string(VIBRO_SCENES_DIR) + "/contacts_chain2_modal.toml").scene);
  ASSERT_EQ(modal.contact_count(), 2);
  EXPECT_FALSE(modal.physical());
  for (int j = 0; j < 2; ++j) {
    const ContactModel& p = physical.contacts()[static_cast<size_t>(j)];
    const ContactModel& m = modal.contacts()[static_cast<size_t>(j)];
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(m.shape[i], p.shape[i], 1e-15 * (1 + std::abs(p.shape[i]))) << j << " " << i;
      EXPECT_NEAR(m.contact[i], p.contact[i], 1e-15) << j << " " << i;
    }
    EXPECT_EQ(m.stop, p.stop);
    EXPECT_EQ(m.restitution, p.restitution);
  }
  const Eigen::Matrix2d W_exact = Eigen::Matrix2d::Identity();
  EXPECT_LE((modal.delassus() - W_exact).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LE((physical.delassus() - W_exact).cwiseAbs().maxCoeff(), 1e-15);
}

// A stop above as contact 0 in the modal form: its components are −1 (c_0 = σ_0 a_0 = 1), so the
// gap is Σ X_i − σ_0 d_0 = Σ X_i + d_0 and the contact's coordinate w_0ᵀq = −Σ X_i ≤ d_0.
TEST(System, ModalFormContactZeroAboveIsScaledToMinusOne) {
  const auto loaded = ParseScene(R"(
[structure]
frequencies = [1.0, 2.0]
forcing = [0.5, 0.5]
contact = [0.5, 0.25]
[[contact]]
side = "above"
position = 0.5
restitution = 0.5
[[contact]]
modal = [1.0, -1.0]
side = "below"
position = -0.3
restitution = 0.7
[excitation]
amplitude = 1.0
frequency = 1.5
)", "above.toml");
  const System sys(loaded.scene);
  EXPECT_EQ(sys.stop(), -0.5);
  EXPECT_EQ(sys.contacts()[0].shape, Eigen::Vector2d(1.0, 1.0));
  EXPECT_EQ(sys.contacts()[1].shape, Eigen::Vector2d(1.0, -1.0));
  EXPECT_EQ(sys.contacts()[1].contact, Eigen::Vector2d(0.5, -0.25));  // T_1 = μ⁻¹c_1, μ_i = 1/T_B,i
  EXPECT_EQ(sys.contacts()[1].stop, -0.3);
  // W_01 = c_0ᵀμ⁻¹c_1 = 0.5 − 0.25
  EXPECT_DOUBLE_EQ(sys.delassus()(0, 1), 0.25);
  EXPECT_DOUBLE_EQ(sys.delassus()(1, 1), 0.75);
}

}  // namespace
}  // namespace vibro
