// Periodic orbits with several contacts (docs/contacts.md, "Periodic orbits") against truths that
// do not share the tangent map:
//  * the symmetric two-sided 1-DOF oscillator's period-1 orbit with one impact on each stop: its
//    impact phases and speeds from the closed form (T1)-(T2) of docs/contacts.md ("Checked
//    against"), det DF = r⁴ (two impacts, det of each saltation r²: a complex pair has modulus r²);
//  * the analytic DF against central finite differences of the stroboscopic map computed by the
//    quad engine (each evaluation exact to ~1e-30, rounded once to double: a five-point stencil
//    has truncation ~h⁴ times the map's fifth derivative and rounding ~1e-16/h), on every shipped
//    scene with several contacts (each has a periodic orbit), and on orbits of a 2-DOF chain where
//    an impact pair hits while a coupled stop sticks (it stays, or is lifted off), or a plastic
//    impact leaves;
//  * the Floquet multipliers of a 2-DOF orbit against the Lyapunov exponents of a run on it, which
//    re-orthonormalise the same tangent every period instead of taking eigenvalues;
//  * `vibro check` on symmetric orbits (issue 37, item 7): impacts compared as cyclic lists, each
//    named by its contact, against the closed form (T1)-(T2) and against the symmetry x → −x,
//    t → t + T/2 of a symmetric 2-DOF scene; a mirrored or shifted record is not taken for the orbit;
//  * simultaneous impacts: coupled contacts (W_jk ≠ 0) leave the map without a Jacobian, which
//    the orbit says instead of multipliers; decoupled ones (W_jk = 0) give the product of the
//    single impacts' saltations, checked against quad finite differences.
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>

#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/check.hpp"
#include "vibro/lyapunov.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/poincare.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

Scene Shipped(const char* file, std::vector<std::string> sets = {}) {
  sets.push_back("run.samples_per_period=0");
  return LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, sets).scene;
}

// The 1-DOF oscillator (unit mass, stiffness ω_1²) with stops at −Δ (below) and +Δ (above).
Scene TwoSided(double w1, double a, double delta, double r, double w) {
  Scene s;
  s.physical = PhysicalStructureSpec{Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Constant(1, 1, w1 * w1), 0, 0};
  s.contacts = {ContactSpec{0, -1, Side::kBelow, -delta, r}, ContactSpec{0, -1, Side::kAbove, delta, r}};
  s.frequency = w;
  s.amplitude = a;
  s.run.periods = 20;
  s.run.samples_per_period = 0;
  return s;
}

// Central differences of F(z) = z(t0 + qT) by the quad engine, five-point stencil
// (f(−2h) − 8f(−h) + 8f(h) − f(2h))/(12h).
Eigen::MatrixXd QuadFiniteDifferences(const System& sys, Scene scene, double t0, const Eigen::VectorXd& X,
                                      const Eigen::VectorXd& V, int q, double h = 1e-4) {
  scene.run.precision = Precision::kQuad;
  const auto n = sys.dof();
  Eigen::VectorXd z(2 * n);
  z << X, V;
  Eigen::MatrixXd J(2 * n, 2 * n);
  const auto F = [&](const Eigen::VectorXd& zz) {
    const MapValue m = StroboscopicMap(sys, scene, t0, zz.head(n), zz.tail(n), q);
    EXPECT_EQ(m.status, RunStatus::kOk);
    Eigen::VectorXd out(2 * n);
    out << m.X, m.V;
    return out;
  };
  for (Eigen::Index j = 0; j < 2 * n; ++j) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(2 * n);
    e[j] = h;
    J.col(j) = (F(z - 2 * e) - 8 * F(z - e) + 8 * F(z + e) - F(z + 2 * e)) / (12 * h);
  }
  return J;
}

std::vector<std::complex<double>> Eigenvalues(const Eigen::MatrixXd& m) {
  Eigen::ComplexEigenSolver<Eigen::MatrixXcd> es(m.cast<std::complex<double>>());
  std::vector<std::complex<double>> mu(es.eigenvalues().data(), es.eigenvalues().data() + es.eigenvalues().size());
  std::sort(mu.begin(), mu.end(), [](auto a, auto b) {
    return std::abs(a) != std::abs(b) ? std::abs(a) > std::abs(b) : a.imag() > b.imag();
  });
  return mu;
}

double Wrap(LD phase) {
  const LD two_pi = 2 * M_PIl;
  LD p = std::fmod(phase, two_pi);
  if (p < 0) p += two_pi;
  return static_cast<double>(p);
}

// (T1)-(T2): the two impact speeds of the symmetric orbit and their phases at the upper stop.
struct Symmetric {
  LD V, phi;
};
std::vector<Symmetric> SymmetricOrbits(LD w1, LD a, LD delta, LD r, LD w) {
  const LD U = a / (w1 * w1 - w * w), theta = w1 * M_PIl / w;
  const LD k1 = (1 + r) * std::tan(theta / 2) / (2 * w1), k2 = (1 - r) / (2 * w);
  const LD A = k1 * k1 + k2 * k2, B = -2 * delta * k1, C = delta * delta - U * U;
  const LD disc = B * B - 4 * A * C;
  std::vector<Symmetric> out;
  for (const LD V : {(-B + std::sqrt(disc)) / (2 * A), (-B - std::sqrt(disc)) / (2 * A)})
    if (V > 0) out.push_back({V, std::atan2((delta - k1 * V) / U, k2 * V / U)});
  return out;
}

void CheckSymmetricOrbit(double w1, double a, double delta, double r, double w, bool stable) {
  const auto all = SymmetricOrbits(w1, a, delta, r, w);
  // The larger root is the stable orbit where there are two (a fold pair).
  ASSERT_GE(all.size(), stable ? 1u : 2u);
  const Symmetric& o = all[stable ? 0 : 1];
  SCOPED_TRACE(testing::Message() << "(ω1, a, Δ, r, ω) = (" << w1 << ", " << a << ", " << delta << ", " << r
                                  << ", " << w << "), V = " << static_cast<double>(o.V));
  const Scene scene = TwoSided(w1, a, delta, r, w);
  const System sys(scene);
  // Newton from the state just after the impact on +Δ (ẋ = −rV), no transient.
  OrbitRequest req;
  req.kind = OrbitKind::kImpact;
  req.transient_periods = 0;
  req.start = InitialOverride{Wrap(o.phi) / w, Eigen::VectorXd::Constant(1, delta),
                              Eigen::VectorXd::Constant(1, static_cast<double>(-r * o.V))};
  const OrbitResult orbit = SolveOrbit(sys, scene, req);
  ASSERT_EQ(orbit.status, "converged") << orbit.message;
  EXPECT_EQ(orbit.period, 1);
  EXPECT_TRUE(orbit.no_jacobian.empty()) << orbit.no_jacobian;
  // One impact per stop, in either order from the section.
  EXPECT_EQ(orbit.sequence, "0:impact 1:impact");  // canonical, whichever stop the section follows
  // Impacts at φ (upper stop) and φ + π (lower), arriving with gap rate −V on either stop.
  ASSERT_EQ(orbit.summary.impact_phases.size(), 2u);
  std::vector<double> want = {Wrap(o.phi), Wrap(o.phi + M_PIl)}, got = orbit.summary.impact_phases;
  std::sort(want.begin(), want.end());
  std::sort(got.begin(), got.end());
  for (size_t k = 0; k < 2; ++k) {
    EXPECT_NEAR(got[k], want[k], 1e-12);
    EXPECT_NEAR(orbit.summary.impact_velocities[k], static_cast<double>(-o.V), 1e-12 * static_cast<double>(o.V));
  }
  // det DF = r⁴ (no damping, two impacts of det r² each).
  EXPECT_NEAR(orbit.monodromy.determinant(), std::pow(r, 4), 1e-12);
  ASSERT_EQ(orbit.multipliers.size(), 2u);
  if (stable) {
    // A complex pair: both of modulus r².
    EXPECT_GT(std::abs(orbit.multipliers[0].imag()), 1e-3);
    for (const auto& m : orbit.multipliers) EXPECT_NEAR(std::abs(m), r * r, 1e-12);
    EXPECT_TRUE(orbit.stable);
  } else {
    EXPECT_FALSE(orbit.stable);
  }
  // The multipliers against those of quad finite differences of the map.
  const Eigen::MatrixXd fd = QuadFiniteDifferences(sys, scene, orbit.section_time, orbit.X, orbit.V, 1);
  const auto mu_fd = Eigenvalues(fd), mu = Eigenvalues(orbit.monodromy);
  for (const auto& m : mu) {  // each against the nearest of the other set (conjugates tie in modulus)
    double d = 1e300;
    for (const auto& f : mu_fd) d = std::min(d, std::abs(m - f));
    EXPECT_LT(d, 1e-9 * (1 + std::abs(m))) << m;
  }
  EXPECT_LT((orbit.monodromy - fd).cwiseAbs().maxCoeff(), 1e-9 * (1 + fd.cwiseAbs().maxCoeff()))
      << "analytic\n" << orbit.monodromy << "\nquad finite differences\n" << fd;
}

TEST(ContactsOrbit, TwoSidedSymmetricOrbitMatchesTheClosedFormAndQuadFiniteDifferences) {
  CheckSymmetricOrbit(1, 1, 1, 0.8, 2.5, true);   // multipliers −0.48042 ± 0.42285i
  CheckSymmetricOrbit(1, 1, 1, 0.8, 2.5, false);  // 8.846 and 0.0463
  CheckSymmetricOrbit(1.3, 1.5, 0.5, 0.6, 2, true);
}

// The orbit each shipped scene settles on (a 200-period transient, then Newton): its analytic DF
// against quad finite differences. Every one of these orbits chatters into sticking on at least one
// contact (accumulation maps), some with impacts of one contact while another sticks.
TEST(ContactsOrbit, JacobianMatchesQuadFiniteDifferencesOnEveryShippedScene) {
  struct Case {
    const char* file;
    const char* sequence;
  };
  for (const Case& c : {Case{"contacts_two_sided_1dof.toml",
                             "0:impact*16 0:accumulation 0:stick 0:release 1:impact*16 1:accumulation 1:stick 1:release"},
                        Case{"contacts_preload_clearance_1dof.toml", "0:impact*30 0:accumulation 0:stick 0:release 1:impact"},
                        Case{"contacts_chain2.toml", "0:impact*13 0:accumulation 0:stick 1:impact*2 0:release"},
                        Case{"contacts_impact_pair.toml",
                             "0:impact*24 0:accumulation 0:stick 0:release 1:impact*24 1:accumulation 1:stick 1:release"},
                        Case{"contacts_beam3.toml", nullptr}}) {
    SCOPED_TRACE(c.file);
    const Scene scene = Shipped(c.file);
    const System sys(scene);
    OrbitRequest req;
    req.kind = OrbitKind::kSticking;
    const OrbitResult o = FindOrbit(sys, scene, req);
    ASSERT_EQ(o.status, "converged") << o.message;
    if (c.sequence) {
      EXPECT_EQ(o.sequence, c.sequence);
    }
    EXPECT_FALSE(o.sequence.empty());
    EXPECT_TRUE(o.no_jacobian.empty());
    // h = 1e-6: the beam's map curves strongly along one mode (a contact sequence change lies
    // about 1e-3 away: the stencil with h = 1e-4 is off by 2e-4 there, with 1e-5 by 2e-8, with
    // 1e-6 by 5e-11); rounding of the double outputs is then ~1e-16/h = 1e-10.
    const Eigen::MatrixXd fd = QuadFiniteDifferences(sys, scene, o.section_time, o.X, o.V, o.period, 1e-6);
    const double err = (o.monodromy - fd).cwiseAbs().maxCoeff(), scale = 1 + fd.cwiseAbs().maxCoeff();
    EXPECT_LT(err, 1e-9 * scale) << "analytic\n" << o.monodromy << "\nquad finite differences\n" << fd;
    std::printf("[          ] %s: |DF − FD_quad|∞ = %.2e (|DF|∞ = %.3g)\n", c.file, err, scale - 1);
  }
}

// A 2-DOF chain with a plastic stop below mass 0 and an impact pair (1, 0) above it: W_01 = −1, so
// an impact of the pair while mass 0 sticks takes the 2 × 2 law with both impulses, and a plastic
// impact that leaves at once projects the velocity (a zero multiplier).
// lift: the pair (0, 1) instead, whose impact pushes mass 0 off its stop (W_01 = +1: liftoff, the
// held contact's release at the impact).
Scene HeldChain(double amplitude, double frequency, bool lift = false) {
  Scene s;
  Eigen::MatrixXd K(2, 2);
  K << 2, -1, -1, 1;
  s.physical = PhysicalStructureSpec{Eigen::MatrixXd::Identity(2, 2), K, 0, 0};
  s.damping_ratios = Eigen::VectorXd::Constant(2, 0.05);
  s.contacts = {ContactSpec{0, -1, Side::kBelow, -0.2, 0.0},
                lift ? ContactSpec{0, 1, Side::kBelow, -0.3, 0.6} : ContactSpec{1, 0, Side::kBelow, -0.3, 0.6}};
  s.frequency = frequency;
  s.amplitude = amplitude;
  s.run.periods = 50;
  s.run.samples_per_period = 0;
  return s;
}

TEST(ContactsOrbit, ImpactsWhileACoupledContactSticksMatchQuadFiniteDifferences) {
  struct Case {
    double amplitude, frequency;
    bool lift;
    const char* sequence;
  };
  for (const Case& c : {Case{0.5, 0.8, false, "0:impact 0:stick 1:impact 0:release"},
                        Case{2, 0.5, false, "0:impact 0:stick 1:impact*2 0:release 1:impact"},
                        Case{1, 1.2, false, "0:impact 1:impact 0:impact 1:impact"},
                        // The pair's impact lifts mass 0 off (its release at the same instant).
                        Case{0.7, 0.4, true, "0:impact*2 0:stick 1:impact 0:release 1:impact*2"}}) {
    SCOPED_TRACE(testing::Message() << "a = " << c.amplitude << ", ω = " << c.frequency << (c.lift ? ", liftoff" : ""));
    const Scene scene = HeldChain(c.amplitude, c.frequency, c.lift);
    const System sys(scene);
    ASSERT_NEAR(sys.delassus()(0, 1), c.lift ? 1.0 : -1.0, 1e-12);
    OrbitRequest req;
    req.kind = OrbitKind::kAuto;
    const OrbitResult o = SolveOrbit(sys, scene, req);
    ASSERT_EQ(o.status, "converged") << o.message;
    EXPECT_EQ(o.sequence, c.sequence);
    const Eigen::MatrixXd fd = QuadFiniteDifferences(sys, scene, o.section_time, o.X, o.V, o.period, 1e-5);
    EXPECT_LT((o.monodromy - fd).cwiseAbs().maxCoeff(), 1e-9 * (1 + fd.cwiseAbs().maxCoeff()))
        << "analytic\n" << o.monodromy << "\nquad finite differences\n" << fd;
  }
}

// Three masses in a symmetric chain, the middle one forced, so that the outer two move alike.
// contacts = "pairs": impact pairs between the middle mass and each neighbour (W_01 = 1/m_1 ≠ 0);
// "stops": stops below the outer masses (W_01 = 0).
Scene SymmetricTriple(bool pairs, double amplitude, double frequency, double damping) {
  Scene s;
  Eigen::MatrixXd K(3, 3);
  K << 2, -1, 0, -1, 2, -1, 0, -1, 2;
  s.physical = PhysicalStructureSpec{Eigen::MatrixXd::Identity(3, 3), K, 1, 0};
  if (damping > 0) s.damping_ratios = Eigen::VectorXd::Constant(3, damping);
  if (pairs)
    s.contacts = {ContactSpec{1, 0, Side::kBelow, -0.3, 0.7}, ContactSpec{1, 2, Side::kBelow, -0.3, 0.7}};
  else
    s.contacts = {ContactSpec{0, -1, Side::kBelow, -0.3, 0.7}, ContactSpec{2, -1, Side::kBelow, -0.3, 0.7}};
  s.frequency = frequency;
  s.amplitude = amplitude;
  s.run.periods = 20;
  s.run.samples_per_period = 0;
  return s;
}

TEST(ContactsOrbit, SimultaneousImpactsOfCoupledContactsLeaveTheOrbitWithoutMultipliers) {
  const Scene scene = SymmetricTriple(true, 3, 1.6, 0.05);
  const System sys(scene);
  ASSERT_NE(sys.delassus()(0, 1), 0.0);
  OrbitRequest req;
  req.kind = OrbitKind::kImpact;
  const OrbitResult o = FindOrbit(sys, scene, req);
  ASSERT_EQ(o.status, "converged") << o.message;
  EXPECT_EQ(o.sequence, "0+1:impact");
  EXPECT_EQ(o.no_jacobian,
            "the orbit passes through a simultaneous impact of coupled contacts: the map has no Jacobian there");
  EXPECT_TRUE(o.multipliers.empty());
  // The map is indeed discontinuous there (docs/contacts.md, "Periodic orbits"): breaking the
  // symmetry by 1e-12 turns the simultaneous impact into a cascade of sequential impacts and moves
  // the image by far more than 1e-12 times any Jacobian could.
  // The outer masses no longer move alike: every mode moved by ~1e-12, the antisymmetric one too.
  Eigen::VectorXd X = o.X;
  for (Eigen::Index i = 0; i < X.size(); ++i) X[i] += (i % 2 == 0 ? 1e-12 : -2e-12) * static_cast<double>(i + 1);
  const auto n = sys.dof();
  Eigen::VectorXd z(2 * n), here(2 * n), there(2 * n);
  z << o.X, o.V;
  const MapValue a = StroboscopicMap(sys, scene, o.section_time, o.X, o.V, 1);
  here << a.X, a.V;
  const MapValue b = StroboscopicMap(sys, scene, o.section_time, X, o.V, 1);
  there << b.X, b.V;
  EXPECT_GT((here - there).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_FALSE(a.undefined.empty());
}

TEST(ContactsOrbit, SimultaneousImpactsOfDecoupledContactsHaveTheProductSaltation) {
  const Scene scene = SymmetricTriple(false, 1, 1.2, 0);
  const System sys(scene);
  EXPECT_NEAR(sys.delassus()(0, 1), 0.0, 1e-14);  // different masses: W_01 = 0 up to the modes' rounding
  OrbitRequest req;
  req.kind = OrbitKind::kImpact;
  const OrbitResult o = FindOrbit(sys, scene, req);
  ASSERT_EQ(o.status, "converged") << o.message;
  EXPECT_EQ(o.sequence, "0+1:impact");
  EXPECT_TRUE(o.no_jacobian.empty());
  // Undamped, two impacts of r = 0.7: det DF = r⁴.
  EXPECT_NEAR(o.monodromy.determinant(), std::pow(0.7, 4), 1e-12);
  const Eigen::MatrixXd fd = QuadFiniteDifferences(sys, scene, o.section_time, o.X, o.V, o.period);
  EXPECT_LT((o.monodromy - fd).cwiseAbs().maxCoeff(), 1e-8 * (1 + fd.cwiseAbs().maxCoeff()))
      << "analytic\n" << o.monodromy << "\nquad finite differences\n" << fd;
}

// The 2-DOF impact pair's orbit (damped; both contacts stick in turn, collapsing the same relative
// direction): the Lyapunov exponents of a 4000-period run from the orbit are ln|μ_i|/(qT) of its
// two multipliers (a complex pair: equal moduli), and −∞ twice.
TEST(ContactsOrbit, FloquetMultipliersOfATwoDofOrbitMatchItsLyapunovExponents) {
  Scene scene = Shipped("contacts_impact_pair.toml");
  const System sys(scene);
  const OrbitResult o = FindOrbit(sys, scene, {});
  ASSERT_EQ(o.status, "converged") << o.message;
  ASSERT_EQ(o.multipliers.size(), 2u);
  const double qT = o.period * sys.period();
  const double want = std::log(std::abs(o.multipliers[0])) / qT;
  EXPECT_NEAR(std::log(std::abs(o.multipliers[1])) / qT, want, 1e-12);
  scene.run.periods = 4000;
  scene.initial_time = o.section_time;
  LyapunovObserver ly(sys, scene);
  const InitialOverride start{o.section_time, o.X, o.V};
  SimulationOptions opt;
  opt.initial = &start;
  opt.observers = {&ly};
  const RunResult r = vibro::Simulate(sys, scene, opt);
  ASSERT_EQ(r.status, RunStatus::kOk) << r.message;
  const LyapunovSpectrum s = ly.Spectrum();
  ASSERT_TRUE(s.undefined.empty()) << s.undefined;
  ASSERT_EQ(s.exponents.size(), 4u);
  // The pair's sum converges like 1/periods; each of a complex pair too, oscillating.
  EXPECT_NEAR(s.exponents[0] + s.exponents[1], 2 * want, 2e-5);
  EXPECT_NEAR(s.exponents[0], want, 1e-4);
  EXPECT_NEAR(s.exponents[1], want, 1e-4);
  EXPECT_TRUE(std::isinf(s.exponents[2]) && s.exponents[2] < 0);
  EXPECT_TRUE(std::isinf(s.exponents[3]) && s.exponents[3] < 0);
}

const CheckRow* Row(const CheckReport& rep, const std::string& name) {
  for (const auto& row : rep.rows)
    if (row.quantity == name) return &row;
  return nullptr;
}

// `vibro check` lists the impacts of the symmetric orbit from contact 0 (the canonical rotation
// of "0:impact 1:impact"), whichever stop each method's record starts after, and every method
// agrees: the phases of (T1)-(T2), φ + π on the lower stop (contact 0) and φ on the upper one.
TEST(ContactsOrbit, CheckComparesTheImpactsOfASymmetricOrbitCyclically) {
  // The reproduction (a = 4, r = 0.8, ω = 2.5) and another symmetric orbit that is the
  // attractor from rest.
  for (const auto& [w1, a, delta, r, w] : {std::array<double, 5>{1, 4, 1, 0.8, 2.5}, std::array<double, 5>{1.3, 1.5, 0.5, 0.6, 2}}) {
    SCOPED_TRACE(testing::Message() << "(ω1, a, Δ, r, ω) = (" << w1 << ", " << a << ", " << delta << ", " << r << ", " << w << ")");
    const auto orbits = SymmetricOrbits(w1, a, delta, r, w);
    ASSERT_FALSE(orbits.empty());
    Scene scene = TwoSided(w1, a, delta, r, w);
    scene.run.periods = 200;
    const CheckReport rep = CrossCheck(System(scene), scene);
    std::string failed;
    for (const auto& row : rep.rows)
      if (!row.ok) failed += row.quantity + ": " + row.note + "\n";
    EXPECT_TRUE(rep.ok) << failed;
    const CheckRow* lower = Row(rep, "impact 1 (contact 0) phase");
    const CheckRow* upper = Row(rep, "impact 2 (contact 1) phase");
    ASSERT_TRUE(lower && upper && lower->exact && upper->exact && lower->orbit && upper->orbit);
    EXPECT_NEAR(*lower->exact, Wrap(orbits[0].phi + M_PIl), 1e-9);
    EXPECT_NEAR(*upper->exact, Wrap(orbits[0].phi), 1e-9);
    EXPECT_NEAR(*lower->orbit, Wrap(orbits[0].phi + M_PIl), 1e-11);
    EXPECT_NEAR(*upper->orbit, Wrap(orbits[0].phi), 1e-11);
    for (const char* v : {"impact 1 (contact 0) velocity before", "impact 2 (contact 1) velocity before"}) {
      const CheckRow* row = Row(rep, v);
      ASSERT_TRUE(row && row->exact) << v;
      EXPECT_NEAR(*row->exact, static_cast<double>(-orbits[0].V), 1e-9) << v;
    }
  }
}

// A tube in a loose support (issue 37, scene E): the scene is symmetric under q → −q, so its
// period-1 orbit hits the stops at −0.1 (contact 0) and +0.1 (contact 1) half a period apart with
// the same speed; `vibro check` agrees across methods whichever stop each record starts after.
TEST(ContactsOrbit, CheckAgreesOnTheSymmetricOrbitOfATubeInALooseSupport) {
  Scene s;
  Eigen::MatrixXd M(2, 2), K(2, 2);
  M << 2, 0, 0, 1;
  K << 4, -1, -1, 1;
  s.physical = PhysicalStructureSpec{M, K, 0, 0};
  s.damping_ratios = Eigen::VectorXd::Constant(2, 0.02);
  s.contacts = {ContactSpec{1, -1, Side::kBelow, -0.1, 0.7}, ContactSpec{1, -1, Side::kAbove, 0.1, 0.7}};
  s.amplitude = 0.3;
  s.frequency = 0.9;
  s.run.samples_per_period = 0;
  const CheckReport rep = CrossCheck(System(s), s);
  std::string failed;
  for (const auto& row : rep.rows)
    if (!row.ok) failed += row.quantity + ": " + row.note + "\n";
  EXPECT_TRUE(rep.ok) << failed;
  const CheckRow *p0 = Row(rep, "impact 1 (contact 0) phase"), *p1 = Row(rep, "impact 2 (contact 1) phase");
  const CheckRow *v0 = Row(rep, "impact 1 (contact 0) velocity before"),
                 *v1 = Row(rep, "impact 2 (contact 1) velocity before");
  ASSERT_TRUE(p0 && p1 && v0 && v1 && p0->orbit && p1->orbit && v0->orbit && v1->orbit);
  EXPECT_NEAR(Wrap(*p0->orbit - *p1->orbit), M_PI, 1e-10);
  EXPECT_NEAR(*v0->orbit, *v1->orbit, 1e-10);
}

// The cyclic comparison finds the same orbit in any rotation, and only the same orbit: the
// record of the mirrored orbit (the stops swapped: contact 0 at the phase of contact 1), of the
// orbit half a period later with the contacts kept, or with another event, stays different.
TEST(ContactsOrbit, CyclicComparisonTellsADifferentOrbit) {
  const auto o = SymmetricOrbits(1, 4, 1, 0.8, 2.5).at(0);
  const double up = Wrap(o.phi), down = Wrap(o.phi + M_PIl), V = -static_cast<double>(o.V);
  const std::vector<CyclicEvent> truth{{1, up, V}, {0, down, V}};  // as a record after the lower stop lists it
  const auto ref = CanonicalCyclic(truth);
  ASSERT_EQ(ref.size(), 2u);
  EXPECT_EQ(ref[0].contact, 0);
  EXPECT_EQ(ref[0].a, down);
  const auto largest = [&](const std::vector<CyclicEvent>& v) {
    double d = 0;
    for (size_t i = 0; i < ref.size(); ++i) {
      if (v[i].contact != ref[i].contact) return 1e300;
      d = std::max({d, std::abs(std::remainder(v[i].a - ref[i].a, 2 * M_PI)), std::abs(v[i].b - ref[i].b)});
    }
    return d;
  };
  // The same orbit, listed from either stop, with phases counted 2π later.
  EXPECT_EQ(largest(AlignedCyclic(ref, truth, false)), 0.0);
  EXPECT_EQ(largest(AlignedCyclic(ref, {{0, down + 2 * M_PI, V}, {1, up, V}}, false)), 0.0);
  // The mirrored orbit: the same phases on the other stops.
  EXPECT_NEAR(largest(AlignedCyclic(ref, {{0, up, V}, {1, down, V}}, false)), M_PI, 1e-12);
  // Another orbit with the same contacts: impacts 0.3 later.
  EXPECT_NEAR(largest(AlignedCyclic(ref, {{1, up + 0.3, V}, {0, down + 0.3, V}}, false)), 0.3, 1e-12);
  // Another speed.
  EXPECT_NEAR(largest(AlignedCyclic(ref, {{1, up, V * 1.01}, {0, down, V * 1.01}}, false)), 0.01 * -V, 1e-12);
  // Two impacts on the same stop: no rotation has the contacts of the orbit.
  EXPECT_EQ(largest(AlignedCyclic(ref, {{0, up, V}, {0, down, V}}, false)), 1e300);
  // A third impact: not rotated (the check reports it missing in that method).
  EXPECT_EQ(AlignedCyclic(ref, {{1, up, V}, {0, down, V}, {0, down + 0.1, V}}, false).size(), 3u);
}

}  // namespace
}  // namespace vibro::test
