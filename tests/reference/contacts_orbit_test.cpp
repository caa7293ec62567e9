// Periodic orbits with several contacts (docs/contacts.md, "Periodic orbits") against truths that
// do not share the tangent map:
//  * the symmetric two-sided 1-DOF oscillator's period-1 orbit with one impact on each stop: its
//    impact phases and speeds from the closed form (T1)-(T2) of docs/contacts.md ("Checked
//    against"), det DF = r⁴ (two impacts, det of each saltation r²: a complex pair has modulus r²);
//  * the analytic DF against central finite differences of the stroboscopic map computed by the
//    quad engine (each evaluation exact to ~1e-30, rounded once to double: a five-point stencil
//    with h = 1e-4 has truncation ~h⁴ and rounding ~1e-16/h, both below 1e-11), on the shipped
//    scenes with several contacts that have a periodic orbit;
//  * the Floquet multipliers of a 2-DOF orbit against the Lyapunov exponents of a run on it, which
//    re-orthonormalise the same tangent every period instead of taking eigenvalues;
//  * simultaneous impacts: coupled contacts (W_jk ≠ 0) leave the map without a Jacobian, which
//    the orbit says instead of multipliers; decoupled ones (W_jk = 0) give the product of the
//    single impacts' saltations, checked against quad finite differences.
#include <algorithm>
#include <cmath>
#include <complex>

#include <gtest/gtest.h>

#include "support.hpp"
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
  ASSERT_EQ(all.size(), 2u);
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
  EXPECT_TRUE(orbit.sequence == "0:impact 1:impact" || orbit.sequence == "1:impact 0:impact") << orbit.sequence;
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
  for (size_t k = 0; k < 2; ++k)
    EXPECT_LT(std::abs(mu[k] - mu_fd[k]), 1e-9 * (1 + std::abs(mu_fd[k]))) << mu[k] << " vs " << mu_fd[k];
  EXPECT_LT((orbit.monodromy - fd).cwiseAbs().maxCoeff(), 1e-9 * (1 + fd.cwiseAbs().maxCoeff()))
      << "analytic\n" << orbit.monodromy << "\nquad finite differences\n" << fd;
}

TEST(ContactsOrbit, TwoSidedSymmetricOrbitMatchesTheClosedFormAndQuadFiniteDifferences) {
  CheckSymmetricOrbit(1, 1, 1, 0.8, 2.5, true);   // multipliers −0.48042 ± 0.42285i
  CheckSymmetricOrbit(1, 1, 1, 0.8, 2.5, false);  // 8.846 and 0.0463
  CheckSymmetricOrbit(1.3, 1.5, 0.5, 0.6, 2, true);
}

}  // namespace
}  // namespace vibro::test
