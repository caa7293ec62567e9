// The compliant stop (docs/compliant.md) against independent truths, derived here from the
// equations of motion and not from the library:
// - an isolated impact: a body m on its own spring k_s arrives at speed v₀ on a contact K, c at its
//   rest position: m ẍ + c ẋ + (K + k_s) x = 0, x = −(v₀/ω_d) e^(−ζω₀t) sin ω_d t, ω₀² = (K + k_s)/m,
//   ζ = c/(2mω₀). Rule "gap": exit at t = π/ω_d, e = exp(−ζπ/√(1−ζ²)). Rule "force": exit where
//   λ = −K x − c ẋ = 0, tan ω_d t = −c ω_d/(K − cζω₀), which for k_s = 0 is Schwager & Pöschel's
//   ω_d t = π − atan2(2ζ√(1−ζ²), 1 − 2ζ²), e = exp(−ζω₀ t) (checked here against their form to
//   1e-15 with k_s = 0; the runs take k_s = 1e-6 K, the body's own spring, exactly). The peak force
//   max λ by bisection on λ̇ of the closed form in long double. The exact engine to 1e-12, CVODE
//   (run.engine = "cvode") to its tolerance;
// - SDND101 (m = 100, k = 1e4, K_c = 1e6, v₀ = 1): the peak at π/(2ω_c), F_max = K_c v₀/ω_c, the
//   duration π/ω_c, the impulse 2K_c v₀/ω_c², ω_c = √((k + K_c)/m);
// - SDND122's conservative bilinear oscillator with a clearance d: free on x > −d (ω₁), stiffer on
//   x < −d (ω₂, about x_e = −K_c d/(k + K_c)): at amplitude A the period is
//   (π + 2 asin(d/A))/ω₁ + 2 acos(|−d − x_e|/B)/ω₂, B² = (d + x_e)² + (v_d/ω₂)², v_d = ω₁√(A² − d²);
// - located errors of the scene keys, and rigid scenes unchanged by the keys' absence.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/rigid_model.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

// A 1-DOF body of mass m and spring ks on a compliant stop at 0 below it, arriving at speed v0.
Scene Impact(double m, double ks, double K, double c, Separation rule, double v0, double periods = 1,
             double w = 1.0) {
  Scene s;
  s.physical = PhysicalStructureSpec{Eigen::MatrixXd::Constant(1, 1, m), Eigen::MatrixXd::Constant(1, 1, ks), 0, 0};
  s.stop_position = 0;
  s.restitution = 0;
  s.stop_compliance = {K, c, rule};
  s.amplitude = 0;
  s.frequency = w;
  s.initial_displacement = Eigen::VectorXd::Zero(1);
  s.initial_velocity = Eigen::VectorXd::Constant(1, -v0);
  s.run.periods = static_cast<long long>(periods);
  s.run.samples_per_period = 0;
  s.run.lyapunov = false;
  return s;
}

struct Ran {
  RunResult result;
  Log log;
};
Ran Simulated(const Scene& s) {
  EXPECT_TRUE(Validate(s).empty()) << (Validate(s).empty() ? "" : Validate(s).front().key + ": " +
                                                                       Validate(s).front().constraint);
  const System sys(s);
  Ran r;
  SimulationOptions opt;
  opt.observers = {&r.log};
  r.result = Simulate(sys, s, opt);
  return r;
}

double Rel(double a, double b) { return std::abs(a - b) / std::abs(b); }

// The closed form of the isolated impact, in long double.
struct Isolated {
  long double m, K, c, v0, w0, zeta, wd, ks;
  Isolated(double m_, double K_, double c_, double v0_, double ks_ = 0) : m(m_), K(K_), c(c_), v0(v0_), ks(ks_) {
    w0 = std::sqrt((K + ks) / m);
    zeta = c / (2 * m * w0);
    wd = w0 * std::sqrt(1 - zeta * zeta);
  }
  long double x(long double t) const { return -(v0 / wd) * std::exp(-zeta * w0 * t) * std::sin(wd * t); }
  long double v(long double t) const {
    return -(v0 / wd) * std::exp(-zeta * w0 * t) * (wd * std::cos(wd * t) - zeta * w0 * std::sin(wd * t));
  }
  long double a(long double t) const { return -(c * v(t) + (K + ks) * x(t)) / m; }
  long double force(long double t) const { return -K * x(t) - c * v(t); }
  long double force_rate(long double t) const { return -K * v(t) - c * a(t); }
  long double ExitGap() const { return static_cast<long double>(M_PIl) / wd; }
  // K x + c ẋ = 0: (K − cζω₀) sin ω_d t = −c ω_d cos ω_d t, the root in (0, π/ω_d).
  long double ExitForce() const {
    return (static_cast<long double>(M_PIl) - std::atan2(c * wd, K - c * zeta * w0)) / wd;
  }
  // ∫_0^t λ = −K ∫x − c [x]; ∫ e^{−at} sin ω_d t = [e^{−at}(−a sin − ω_d cos)/(a² + ω_d²)].
  long double Impulse(long double t) const {
    const long double a = zeta * w0;
    const auto prim = [&](long double s) {
      return std::exp(-a * s) * (-a * std::sin(wd * s) - wd * std::cos(wd * s)) / (a * a + wd * wd);
    };
    const long double ix = -(v0 / wd) * (prim(t) - prim(0));
    return -K * ix - c * x(t);
  }
  // max of the force over [0, end]: λ(0) = c v₀, or the root of λ̇ (+ → −) by bisection.
  long double Peak(long double end, long double* at) const {
    if (!(force_rate(0) > 0)) {
      *at = 0;
      return force(0);
    }
    long double lo = 0, hi = end;
    for (int i = 0; i < 200; ++i) {
      const long double mid = (lo + hi) / 2;
      (force_rate(mid) > 0 ? lo : hi) = mid;
    }
    *at = (lo + hi) / 2;
    return force(*at);
  }
};

class IsolatedImpact : public ::testing::TestWithParam<std::tuple<double, Separation>> {};

TEST_P(IsolatedImpact, RestitutionDurationPeakAgainstClosedForms) {
  const auto [zeta, rule] = GetParam();
  const double m = 2.0, K = 8.0, v0 = 0.75, ks = 1e-6 * K;
  const double c = 2 * zeta * std::sqrt((K + ks) * m);
  // Schwager & Pöschel's closed form is the force rule's exit without the body's own spring.
  const Isolated bare(m, K, 2 * zeta * std::sqrt(K * m), v0);
  const double sp = std::exp(-zeta / std::sqrt(1 - zeta * zeta) *
                             (M_PI - std::atan2(2 * zeta * std::sqrt(1 - zeta * zeta), 1 - 2 * zeta * zeta)));
  EXPECT_LT(Rel(static_cast<double>(bare.v(bare.ExitForce()) / v0), sp), 1e-15);
  EXPECT_LT(Rel(static_cast<double>(bare.ExitForce()),
                (M_PI - std::atan2(2 * zeta * std::sqrt(1 - zeta * zeta), 1 - 2 * zeta * zeta)) /
                    (std::sqrt(K / m) * std::sqrt(1 - zeta * zeta))),
            1e-15);
  const Ran r = Simulated(Impact(m, ks, K, c, rule, v0));
  ASSERT_EQ(r.result.status, RunStatus::kOk) << r.result.message;
  const auto rel = r.log.Of(EventKind::kRelease);
  ASSERT_EQ(r.log.Of(EventKind::kStick).size(), 1u);
  ASSERT_EQ(rel.size(), 1u);
  const Isolated truth(m, K, c, v0, ks);
  const long double t_exit = rule == Separation::kGap ? truth.ExitGap() : truth.ExitForce();
  const double e_closed = rule == Separation::kGap ? std::exp(-zeta * M_PI / std::sqrt(1 - zeta * zeta))
                                                   : static_cast<double>(truth.v(t_exit) / v0);
  EXPECT_LT(Rel(rel[0].v_after / v0, e_closed), 1e-12) << "e = " << rel[0].v_after / v0;
  EXPECT_LT(Rel(rel[0].t, static_cast<double>(t_exit)), 1e-12);
  EXPECT_LT(Rel(rel[0].stick_duration, static_cast<double>(t_exit)), 1e-12);
  long double at = 0;
  const long double peak = truth.Peak(t_exit, &at);
  EXPECT_LT(Rel(rel[0].reaction_max, static_cast<double>(peak)), 1e-12) << rel[0].reaction_max;
  if (at > 0) {
    EXPECT_LT(Rel(rel[0].peak_time, static_cast<double>(at)), 1e-8);  // a maximum: flat in t
  }
  EXPECT_LT(Rel(rel[0].reaction_integral, static_cast<double>(truth.Impulse(t_exit))), 1e-12);
  // The energy the contact takes: the body's kinetic energy lost less what its own spring holds at
  // the exit (the dashpot's ∫cẋ², and, rule "force", the contact spring's ½K x² left to relax).
  const double xe = static_cast<double>(truth.x(t_exit));
  const double lost = 0.5 * m * v0 * v0 * (1 - e_closed * e_closed) - 0.5 * ks * xe * xe;
  EXPECT_LT(Rel(rel[0].energy_dissipated, lost), 1e-10);
  // The largest penetration: where ẋ = 0, tan(ω_d t) = ω_d/(ζω₀).
  const long double tp = std::atan2(truth.wd, truth.zeta * truth.w0) / truth.wd;
  EXPECT_LT(Rel(rel[0].penetration_max, static_cast<double>(-truth.x(tp))), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Rules, IsolatedImpact,
                         ::testing::Combine(::testing::Values(0.01, 0.1, 0.3, 0.5),
                                            ::testing::Values(Separation::kGap, Separation::kForce)));

// CVODE alone (run.engine = "cvode": the contact phase integrated with the spring–dashpot force,
// its exit, peak and largest penetration by CVODE's root finding, docs/compliant.md "CVODE") against
// the same closed forms, to its tolerance: at rtol = 1e-12, atol = 1e-14, every quantity within
// kCvodeTol = 1000·rtol = 1e-9 relative (the peak's instant, where the force is flat, 1e-5). Measured:
// restitution 1.4e-11, duration 6e-13, peak 2.5e-12, impulse 3.7e-12, the dashpot's energy (a
// quadrature outside the error test) 2.6e-10.
constexpr double kCvodeTol = 1e-9;

class IsolatedImpactCvode : public ::testing::TestWithParam<std::tuple<double, Separation>> {};

TEST_P(IsolatedImpactCvode, RestitutionDurationPeakAgainstClosedForms) {
  const auto [zeta, rule] = GetParam();
  const double m = 2.0, K = 8.0, v0 = 0.75, ks = 1e-6 * K;
  const double c = 2 * zeta * std::sqrt((K + ks) * m);
  Scene s = Impact(m, ks, K, c, rule, v0);
  s.run.engine = Engine::kCvode;
  s.run.rtol = 1e-12;
  s.run.atol = 1e-14;
  const Ran r = Simulated(s);
  ASSERT_EQ(r.result.status, RunStatus::kOk) << r.result.message;
  EXPECT_GT(r.result.solver.steps, 0);  // integrated, not the closed form
  const auto rel = r.log.Of(EventKind::kRelease);
  ASSERT_EQ(r.log.Of(EventKind::kStick).size(), 1u);
  ASSERT_EQ(rel.size(), 1u);
  const Isolated truth(m, K, c, v0, ks);
  const long double t_exit = rule == Separation::kGap ? truth.ExitGap() : truth.ExitForce();
  const double e_closed = rule == Separation::kGap ? std::exp(-zeta * M_PI / std::sqrt(1 - zeta * zeta))
                                                   : static_cast<double>(truth.v(t_exit) / v0);
  EXPECT_LT(Rel(rel[0].v_after / v0, e_closed), kCvodeTol) << "e = " << rel[0].v_after / v0;
  EXPECT_LT(Rel(rel[0].stick_duration, static_cast<double>(t_exit)), kCvodeTol);
  long double at = 0;
  const long double peak = truth.Peak(t_exit, &at);
  EXPECT_LT(Rel(rel[0].reaction_max, static_cast<double>(peak)), kCvodeTol) << rel[0].reaction_max;
  if (at > 0) {
    EXPECT_LT(Rel(rel[0].peak_time, static_cast<double>(at)), 1e-5);
  }
  EXPECT_LT(Rel(rel[0].reaction_integral, static_cast<double>(truth.Impulse(t_exit))), kCvodeTol);
  const double xe = static_cast<double>(truth.x(t_exit));
  const double lost = 0.5 * m * v0 * v0 * (1 - e_closed * e_closed) - 0.5 * ks * xe * xe;
  EXPECT_LT(Rel(rel[0].energy_dissipated, lost), kCvodeTol);
  const long double tp = std::atan2(truth.wd, truth.zeta * truth.w0) / truth.wd;
  EXPECT_LT(Rel(rel[0].penetration_max, static_cast<double>(-truth.x(tp))), kCvodeTol);
}

INSTANTIATE_TEST_SUITE_P(Rules, IsolatedImpactCvode,
                         ::testing::Combine(::testing::Values(0.01, 0.1, 0.3, 0.5),
                                            ::testing::Values(Separation::kGap, Separation::kForce)));

TEST(Compliant, Sdnd101PeakDurationImpulse) {
  const double m = 100, k = 1e4, Kc = 1e6, v0 = 1;
  const double wc = std::sqrt((k + Kc) / m);
  const Ran r = Simulated(Impact(m, k, Kc, 0, Separation::kForce, v0, 1, 1.0));
  ASSERT_EQ(r.result.status, RunStatus::kOk) << r.result.message;
  const auto rel = r.log.Of(EventKind::kRelease);
  ASSERT_GE(rel.size(), 1u);
  EXPECT_LT(Rel(rel[0].peak_time, M_PI / (2 * wc)), 1e-12);
  EXPECT_LT(Rel(rel[0].reaction_max, Kc * v0 / wc), 1e-12);
  EXPECT_LT(Rel(rel[0].stick_duration, M_PI / wc), 1e-12);
  EXPECT_LT(Rel(rel[0].reaction_integral, 2 * Kc * v0 / (wc * wc)), 1e-12);
  EXPECT_LT(Rel(rel[0].penetration_max, v0 / wc), 1e-12);
  EXPECT_LT(std::abs(rel[0].energy_dissipated), 1e-12);
  EXPECT_LT(Rel(rel[0].v_after, v0), 1e-12);  // undamped: it leaves as it came
}

// The conservative bilinear oscillator with a clearance (SDND122's frequency–energy relation).
TEST(Compliant, BilinearOscillatorPeriodAgainstEnergy) {
  const double m = 1.5, k = 6.0, Kc = 54.0, d = 0.1;
  const double w1 = std::sqrt(k / m), w2 = std::sqrt((k + Kc) / m);
  for (const double A : {0.1000001, 0.12, 0.3, 1.0, 5.0}) {
    Scene s = Impact(m, k, Kc, 0, Separation::kForce, 0, 40, 0.05);
    s.stop_position = -d;
    s.initial_displacement = Eigen::VectorXd::Constant(1, A);
    s.initial_velocity = Eigen::VectorXd::Zero(1);
    const Ran r = Simulated(s);
    ASSERT_EQ(r.result.status, RunStatus::kOk) << r.result.message;
    const auto in = r.log.Of(EventKind::kStick);
    ASSERT_GE(in.size(), 3u) << "A = " << A;
    const double xe = -Kc * d / (k + Kc);
    const double vd = w1 * std::sqrt(A * A - d * d);
    const double ud = d + xe;  // |−d − x_e|
    const double B = std::sqrt(ud * ud + vd * vd / (w2 * w2));
    const double T = (M_PI + 2 * std::asin(d / A)) / w1 + 2 * std::acos(ud / B) / w2;
    const double measured = (in.back().t - in.front().t) / static_cast<double>(in.size() - 1);
    EXPECT_LT(Rel(measured, T), 1e-11) << "A = " << A;
  }
}

// The distance to the rigid model falls like k^(−1/2) (the penetration v/ω_c, ω_c = √(k/m)): on
// SDND121's scene (m = 156 kg, k = 2e6 N/m, gap 1e-3 m, F = 3000 sin 10πt N), undamped (r = 1
// beside it), over its first period, each decade of stiffness divides the largest distance by √10.
TEST(Compliant, ConvergenceToTheRigidModelAtRateKToMinusOneHalf) {
  Scene s;
  s.physical = PhysicalStructureSpec{Eigen::MatrixXd::Constant(1, 1, 156.0), Eigen::MatrixXd::Constant(1, 1, 2e6), 0, 0};
  s.stop_position = -1e-3;
  s.amplitude = 3000;
  s.frequency = 10 * M_PI;
  s.initial_displacement = Eigen::VectorXd::Zero(1);
  s.initial_velocity = Eigen::VectorXd::Zero(1);
  s.run.periods = 1;
  s.run.samples_per_period = 2000;
  s.run.lyapunov = false;
  std::vector<double> d;
  for (const double k : {1e11, 1e12, 1e13}) {
    s.stop_compliance = {k, 0, Separation::kForce};
    const RigidComparison c = CompareWithRigid(s, 2);
    ASSERT_EQ(c.compliant_result.status, RunStatus::kOk) << c.compliant_result.message;
    ASSERT_EQ(c.rigid_result.status, RunStatus::kOk) << c.rigid_result.message;
    EXPECT_EQ(c.rigid.restitution[0], 1.0);
    d.push_back(c.distance);
  }
  for (size_t i = 1; i < d.size(); ++i) EXPECT_NEAR(std::log10(d[i - 1] / d[i]), 0.5, 0.03) << d[i - 1] << " " << d[i];
}

TEST(Compliant, EquivalentRestitution) {
  for (const double z : {0.01, 0.1, 0.3, 0.5}) {
    const double s = std::sqrt(1 - z * z);
    EXPECT_DOUBLE_EQ(EquivalentRestitution(z, Separation::kGap), std::exp(-z * M_PI / s));
    // Schwager & Pöschel's coefficient against the force rule's exit of the isolated impact (above).
    const Isolated t(1.0, 1.0, 2 * z, 1.0);
    EXPECT_NEAR(EquivalentRestitution(z, Separation::kForce), static_cast<double>(t.v(t.ExitForce())), 1e-15);
  }
  // Two rules, one damping: 2 % apart at ζ = 0.1, 83 % at ζ = 0.5 (the numbers).
  EXPECT_NEAR(EquivalentRestitution(0.1, Separation::kForce) / EquivalentRestitution(0.1, Separation::kGap) - 1, 0.020, 0.001);
  EXPECT_NEAR(EquivalentRestitution(0.5, Separation::kForce) / EquivalentRestitution(0.5, Separation::kGap) - 1, 0.831, 0.001);
  // Critically damped, force rule: x = −t e^(−t), λ = 0 at t = 2, e = e^(−2).
  EXPECT_DOUBLE_EQ(EquivalentRestitution(1.0, Separation::kForce), std::exp(-2.0));
}

TEST(Compliant, SceneKeysLocatedErrors) {
  const std::string base =
      "[excitation]\namplitude = 0.5\nfrequency = 1.3\n[structure]\nmass = [[1.0]]\nstiffness = [[1.0]]\n"
      "forcing_dof = 0\n";
  const auto errors = [&](const std::string& stop) -> std::string {
    try {
      (void)ParseScene(base + (stop.rfind("[stop]", 0) == 0 ? "contact_dof = 0\n" : "") + stop, "s.toml");
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(errors("[stop]\nposition = 0.1\nstiffness = -1\n").find("s.toml:"), std::string::npos);
  EXPECT_NE(errors("[stop]\nposition = 0.1\nstiffness = -1\n").find("stop.stiffness"), std::string::npos);
  EXPECT_NE(errors("[stop]\nposition = 0.1\nstiffness = 0\n").find("k > 0"), std::string::npos);
  EXPECT_NE(errors("[stop]\nposition = 0.1\nstiffness = 10\ndamping = -2\n").find("stop.damping"), std::string::npos);
  EXPECT_NE(errors("[stop]\nposition = 0.1\nstiffness = 10\nseparation = \"glue\"\n").find("stop.separation"),
            std::string::npos);
  EXPECT_NE(errors("[stop]\nposition = 0.1\nrestitution = 0.5\ndamping = 2\n").find("stop.damping"),
            std::string::npos);
  EXPECT_NE(errors("[stop]\nposition = 0.1\nrestitution = 0.5\nstiffness = 2\n").find("stop.restitution"),
            std::string::npos);
  EXPECT_NE(errors("[stop]\nposition = 0.1\nstiffness = 2\n[run]\nprecision = \"quad\"\n").find("run.precision"),
            std::string::npos);
  // CVODE takes a compliant stop (its contact phase integrated).
  EXPECT_EQ(errors("[stop]\nposition = 0.1\nstiffness = 2\n[run]\nengine = \"cvode\"\n"), "");
  EXPECT_EQ(errors("[stop]\nposition = 0.1\nstiffness = 2\ndamping = 0.1\nseparation = \"gap\"\n"), "");
  EXPECT_EQ(errors("[stop]\nposition = 0.1\nrestitution = 0.5\n"), "");
  const Scene s = ParseScene(base + "contact_dof = 0\n[stop]\nposition = 0.1\nstiffness = 2\ndamping = 0.1\nseparation = \"gap\"\n",
                             "s.toml").scene;
  EXPECT_EQ(s.stop_compliance.stiffness, 2.0);
  EXPECT_EQ(s.stop_compliance.damping, 0.1);
  EXPECT_EQ(s.stop_compliance.separation, Separation::kGap);
  const Scene t = ParseScene(base + "[[contact]]\ndof = 0\nside = \"below\"\nposition = 0.1\nstiffness = 3\n", "t.toml").scene;
  ASSERT_EQ(t.contacts.size(), 1u);
  EXPECT_EQ(t.contacts[0].compliance.stiffness, 3.0);
  EXPECT_EQ(t.contacts[0].compliance.separation, Separation::kForce);
}

}  // namespace
}  // namespace vibro::test
