// The quad engine's damped sticking flow of two or more modes (docs/model.md §7; docs/engines.md),
// against three independent truths:
//  (a) two DOF: stuck on the stop the structure is one damped oscillator
//      ξ̈ + d ξ̇ + ν² ξ = F sin(φ + ωσ); its solution and its derivatives are written out by hand
//      (real exponentials and sinusoids, no eigen-decomposition) and the reaction
//      R = R_st + ρ ξ + ρ_v ξ̇ − κ f sin is formed from them; the quad flow, its reaction jet and the
//      certified release time must match to 1e-25 (relative);
//  (b) any number of modes: a Taylor-series integration of ż = G z + h sin(φ + ωσ) in quad, steps
//      of 1/4 of the fastest period with 80 terms (truncation below 1e-40), against which the
//      refined closed form must match to 1e-26;
//  (c) the double engine: on the shipped damped scene, a more heavily damped 2-DOF chain and a
//      damped 3-DOF clearance chain (2 % damping, mass 2 on the stop), the two engines' event logs
//      agree, kind and time, to 1e-12 T over 40 periods, every stick and release included: with
//      r = 0 (no chattering: plastic impacts and sticking only) at the default settings, and with
//      the scenes' r > 0 when both engines predict accumulations to the same target (1e-15 T), so
//      that what is compared is the sticking flow and not the accumulation prediction (whose own
//      error with damping is larger than its estimate: at the default target the double engine's
//      first accumulation on chain2_damped is 7.5e-12 T from quad's).
#include <cmath>
#include <complex>
#include <initializer_list>
#include <random>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "dynamics/exact_engine_quad.hpp"
#include "support.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

using detail::Quad;
using QR = detail::Real<Quad>;
using QVec = Eigen::Matrix<Quad, Eigen::Dynamic, 1>;
using QMat = Eigen::Matrix<Quad, Eigen::Dynamic, Eigen::Dynamic>;

double D(const Quad& x) { return QR::to_double(x); }

// The 2-DOF chain of data/scenes/chain2_damped.toml with heavier, unequal damping (so that the
// damping terms are far above 1e-25 of the motion) and a forcing that releases within a period.
Scene TwoDof() {
  Scene s = Chain(2, 1.0, 0.5, 0.8, 1.6);
  s.damping_ratios = Eigen::Vector2d(0.06, 0.15);
  return s;
}

// A damped 3-DOF clearance chain (mass 2 on the stop, force on mass 0, 2 % damping in every mode).
Scene ThreeDof(double f = 0.8, double w = 0.45) {
  Scene s;
  Eigen::MatrixXd M(3, 3), K(3, 3);
  M << 1.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.5;
  K << 2.5, -1.5, 0.0, -1.5, 2.3, -0.8, 0.0, -0.8, 0.8;
  s.physical = PhysicalStructureSpec{M, K, 0, 2};
  s.damping_ratios = Eigen::Vector3d(0.02, 0.02, 0.02);
  s.stop_position = -0.5;
  s.restitution = 0.6;
  s.amplitude = f;
  s.frequency = w;
  s.run.samples_per_period = 0;
  return s;
}

// R = R_st + ρᵀξ + ρ_vᵀξ̇ − κ f sin ψ: the reaction of the paper's eq. (5) with the damping term
// of docs/model.md §7, Σ_i c_i 2ζ_iω_i Ẋ_i / s_B, written in the constrained coordinates
// (Ẋ = V ξ̇), from the System's data converted to quad.
struct ReactionCoefficients {
  QVec rho, rho_v;
  Quad R_static, kappa_f;
};
ReactionCoefficients Coefficients(const System& sys) {
  const auto& cm = sys.constrained();
  ReactionCoefficients c;
  c.rho = cm.reaction.cast<Quad>();
  const Eigen::Index n = sys.dof(), k = cm.frequencies.size();
  c.rho_v = QVec::Zero(k);
  for (Eigen::Index j = 0; j < k; ++j)
    for (Eigen::Index i = 0; i < n; ++i)
      c.rho_v[j] += Quad(sys.contact_shape()[i]) * Quad(2) * Quad(sys.damping()[i]) *
                    Quad(sys.omega()[i]) * Quad(cm.vectors(i, j));
  c.rho_v /= Quad(sys.s_B());
  c.R_static = Quad(sys.stop()) / Quad(sys.flexibility());
  c.kappa_f = Quad(sys.s_A()) / Quad(sys.s_B()) * Quad(sys.amplitude());
  return c;
}

// (a) The single constrained damped oscillator in closed form, with its first three derivatives.
struct Oscillator1 {
  Quad nu, d, F, w, phase, alpha, beta, P, Q;
  std::complex<Quad> K, mu;  // homogeneous part Re(K e^{μσ}), μ = −α + iβ
  Oscillator1(const System& sys, const Quad& xi0, const Quad& dxi0, const Quad& phi) {
    const auto& cm = sys.constrained();
    nu = Quad(cm.frequencies[0]);
    d = Quad(cm.damping(0, 0));
    F = Quad(cm.modal_forcing[0]) * Quad(sys.amplitude());
    w = Quad(sys.frequency());
    phase = phi;
    alpha = d / 2;
    beta = QR::sqrt(nu * nu - alpha * alpha);
    const Quad det = (nu * nu - w * w) * (nu * nu - w * w) + d * w * d * w;
    P = F * (nu * nu - w * w) / det;  // ξ_p = P sin ψ + Q cos ψ
    Q = -F * d * w / det;
    const Quad A = xi0 - (P * QR::sin(phi) + Q * QR::cos(phi));
    const Quad B = (dxi0 - w * (P * QR::cos(phi) - Q * QR::sin(phi)) + alpha * A) / beta;
    K = std::complex<Quad>(A, -B);
    mu = std::complex<Quad>(-alpha, beta);
  }
  // d^n ξ / dσ^n, n = 0..3.
  Quad Derivative(int n, const Quad& s) const {
    const Quad psi = phase + w * s;
    // d^n/dσ^n (P sin ψ + Q cos ψ) = ω^n (P sin(ψ + nπ/2) + Q cos(ψ + nπ/2)).
    const Quad shift = psi + Quad(n) * QR::pi() / 2;
    Quad wn(1);
    std::complex<Quad> mun(Quad(1), Quad(0));
    for (int i = 0; i < n; ++i) {
      wn *= w;
      mun *= mu;
    }
    const std::complex<Quad> e(QR::exp(-alpha * s) * QR::cos(beta * s),
                               QR::exp(-alpha * s) * QR::sin(beta * s));
    return wn * (P * QR::sin(shift) + Q * QR::cos(shift)) + (K * mun * e).real();
  }
};

TEST(QuadDampedSticking, TwoDofMatchesTheHandDerivedOscillator) {
  const Scene scene = TwoDof();
  const System sys(scene);
  ASSERT_EQ(sys.constrained().frequencies.size(), 1);
  ASSERT_GT(std::abs(sys.constrained().damping(0, 0)), 0.05);
  const detail::ModelT<Quad> model(sys);
  const detail::DampedStickingT<Quad> probe_only(sys);
  ASSERT_TRUE(probe_only.ok());
  const ReactionCoefficients rc = Coefficients(sys);
  const Quad T = Quad(2) * QR::pi() / Quad(sys.frequency());

  // Start at rest on the stop with forcing phase 0 (R = R_st > 0 there): X = x0·static_shape.
  const QVec X = model.x0 * model.static_shape, V = QVec::Zero(2);
  // The engine's constrained start (ξ = L X, of order 1e-16 here, not exactly 0): the truth starts
  // from the same ξ.
  const QVec xi0 = model.stick_left * X, dxi0 = model.stick_left * V;
  const Oscillator1 truth(sys, xi0[0], dxi0[0], Quad(0));
  const auto truth_R = [&](int n, const Quad& s) {  // d^n R / dσ^n, n = 0..2
    const Quad psi = Quad(n) * QR::pi() / 2 + truth.w * s;
    Quad wn(1);
    for (int i = 0; i < n; ++i) wn *= truth.w;
    return (n == 0 ? rc.R_static : Quad(0)) + rc.rho[0] * truth.Derivative(n, s) +
           rc.rho_v[0] * truth.Derivative(n + 1, s) - rc.kappa_f * wn * QR::sin(psi);
  };

  detail::DampedStickingT<Quad> ds(sys);
  ds.Begin(xi0, dxi0, Quad(0));
  double worst = 0;
  for (const double s : {1e-9, 1e-3, 0.1, 0.7, 1.3, 2.9, 5.0, 7.6}) {
    const Quad sigma(s);
    QVec xi, dxi;
    ds.Evaluate(sigma, xi, dxi);
    const auto jet = ds.ReactionProbe(sigma).jet;
    // Scales: the motion's amplitude, and the reaction's.
    const Quad sx = QR::abs(truth.P) + QR::abs(truth.Q) + QR::abs(xi0[0]) + QR::abs(dxi0[0]);
    const Quad sR = rc.R_static + rc.kappa_f;
    const double e[] = {D(QR::abs(xi[0] - truth.Derivative(0, sigma)) / sx),
                        D(QR::abs(dxi[0] - truth.Derivative(1, sigma)) / sx),
                        D(QR::abs(jet.g - truth_R(0, sigma)) / sR),
                        D(QR::abs(jet.g1 - truth_R(1, sigma)) / sR),
                        D(QR::abs(jet.g2 - truth_R(2, sigma)) / sR)};
    for (const double x : e) {
      EXPECT_LE(x, 1e-25) << "σ = " << s;
      worst = std::max(worst, x);
    }
    // The truth's reaction is the model's (eq. (5) with §7's term) on the full modal state, to the
    // double rounding of the constrained modal data.
    const QVec Xs = model.x0 * model.static_shape + model.stick_vectors * xi;
    const QVec Vs = model.stick_vectors * dxi;
    EXPECT_LE(D(QR::abs(model.Reaction(Xs, Vs, truth.w * sigma) - truth_R(0, sigma)) / sR), 1e-14);
  }
  std::printf("2-DOF closed form: worst relative difference %.3g\n", worst);

  // The certified release: the engine's first sign change of R against Newton's root of the truth.
  detail::ExactEngineT<Quad> engine(sys, model);
  engine.Begin({Mode::kSticking, Quad(0), Quad(0), X, V, Quad(0), detail::FlightStart::kGeneric,
                detail::StickStart::kGeneric});
  const auto r = engine.Advance(Quad(3) * T, true, nullptr);
  ASSERT_EQ(r.end, detail::SegmentEnd::kRelease) << r.message;
  Quad root = r.sigma;
  for (int i = 0; i < 8; ++i) root -= truth_R(0, root) / truth_R(1, root);
  ASSERT_LT(truth_R(1, root), 0);  // R crosses to negative there: a release
  const double dt = D(QR::abs(r.sigma - root) / T);
  std::printf("2-DOF release at σ = %.20g, |Δσ|/T = %.3g\n", D(root), dt);
  EXPECT_LE(dt, 1e-25);
  EXPECT_GT(D(root), 0.05 * D(T));  // a real release, not the start
}

// (b) ż = G z + h sin(φ + ωσ) integrated by its Taylor series, in quad.
void TaylorFlow(const System& sys, const QVec& xi0, const QVec& dxi0, const Quad& phase,
                const Quad& sigma, QVec& xi, QVec& dxi) {
  const auto& cm = sys.constrained();
  const Eigen::Index k = cm.frequencies.size();
  QMat G = QMat::Zero(2 * k, 2 * k);
  G.topRightCorner(k, k).setIdentity();
  for (Eigen::Index j = 0; j < k; ++j)
    G(k + j, j) = -Quad(cm.frequencies[j]) * Quad(cm.frequencies[j]);
  G.bottomRightCorner(k, k) = -cm.damping.cast<Quad>();
  QVec h = QVec::Zero(2 * k);
  h.tail(k) = cm.modal_forcing.cast<Quad>() * Quad(sys.amplitude());
  const Quad w(sys.frequency());
  Quad fastest(w);
  for (Eigen::Index j = 0; j < k; ++j) fastest = std::max(fastest, Quad(cm.frequencies[j]));
  const int steps = static_cast<int>(std::ceil(D(sigma * fastest / (QR::pi() / 2)))) + 1;
  const Quad dt = sigma / Quad(steps);
  QVec z(2 * k);
  z << xi0, dxi0;
  for (int s = 0; s < steps; ++s) {
    const Quad psi = phase + w * dt * Quad(s);
    // z^{(n+1)} = G z^{(n)} + h ω^n sin(ψ + nπ/2).
    QVec dn = z, sum = z;
    Quad fac(1), wn(1);
    for (int n = 0; n < 80; ++n) {
      dn = G * dn + h * (wn * QR::sin(psi + Quad(n) * QR::pi() / 2));
      wn *= w;
      fac *= dt / Quad(n + 1);
      sum += dn * fac;
    }
    z = sum;
  }
  xi = z.head(k);
  dxi = z.tail(k);
}

void ExpectMatchesTaylor(const Scene& scene, const char* name,
                         std::initializer_list<double> sigmas = {0.01, 0.9, 3.7, 12.5}) {
  const System sys(scene);
  const Eigen::Index k = sys.constrained().frequencies.size();
  detail::DampedStickingT<Quad> ds(sys);
  ASSERT_TRUE(ds.ok()) << name;
  // The refined eigenpairs: G W = W Λ to quad rounding (the double start is ~1e-16).
  EXPECT_LE(D(ds.residual()), 1e-32) << name;
  std::printf("%s: eigen-residual %.3g after %d refinements\n", name, D(ds.residual()),
              ds.refinements());
  QVec xi0(k), dxi0(k);
  for (Eigen::Index j = 0; j < k; ++j) {
    xi0[j] = Quad(0.3) / Quad(j + 1);
    dxi0[j] = Quad(-0.2) * Quad(j + 1);
  }
  const Quad phase(0.7);
  ds.Begin(xi0, dxi0, phase);
  double worst = 0;
  for (const double s : sigmas) {
    QVec a, da, b, db;
    ds.Evaluate(Quad(s), a, da);
    TaylorFlow(sys, xi0, dxi0, phase, Quad(s), b, db);
    const Quad scale = xi0.cwiseAbs().maxCoeff() + dxi0.cwiseAbs().maxCoeff() +
                       a.cwiseAbs().maxCoeff() + da.cwiseAbs().maxCoeff();
    const double e = D(std::max((a - b).cwiseAbs().maxCoeff(), (da - db).cwiseAbs().maxCoeff()) / scale);
    EXPECT_LE(e, 1e-26) << name << " σ = " << s;
    worst = std::max(worst, e);
  }
  std::printf("%s: worst relative difference from the Taylor flow %.3g\n", name, worst);
}

TEST(QuadDampedSticking, ClosedFormMatchesTaylorFlow) {
  ExpectMatchesTaylor(TwoDof(), "2-DOF");
  ExpectMatchesTaylor(ThreeDof(), "3-DOF chain");
  Scene s4 = Chain(4, 1.0, 0.5, 0.8, 1.0);
  s4.damping_ratios = Eigen::Vector4d(0.01, 0.05, 0.2, 0.4);
  ExpectMatchesTaylor(s4, "4-DOF chain, unequal damping");
  // A star (mass B tied to three equal masses): the constrained pulsation 1 is triple, and so are
  // the eigenvalues of G with equal damping ratios (a repeated, non-defective eigenvalue); unequal
  // ratios split them.
  for (const Eigen::Vector4d& zeta : {Eigen::Vector4d(0.05, 0.05, 0.05, 0.05),
                                     Eigen::Vector4d(0.05, 0.02, 0.08, 0.05)}) {
    Scene star;
    Eigen::MatrixXd K(4, 4);
    K << 4, -1, -1, -1, -1, 1, 0, 0, -1, 0, 1, 0, -1, 0, 0, 1;
    star.physical = PhysicalStructureSpec{Eigen::MatrixXd::Identity(4, 4), K, 1, 0};
    star.damping_ratios = zeta;
    star.stop_position = 0.5;
    star.amplitude = 2.0;
    star.frequency = 0.7;
    ASSERT_NEAR(System(star).constrained().frequencies[0], System(star).constrained().frequencies[2], 1e-12);
    ExpectMatchesTaylor(star, zeta[1] == zeta[2] ? "star, triple eigenvalue" : "star, split eigenvalues");
  }
  // 49 constrained modes, ω'_max ≈ 1000 (G spans six decades): the Taylor steps are 1/4 of the
  // fastest period, so only short times.
  ExpectMatchesTaylor(LoadScene(std::string(VIBRO_SCENES_DIR) + "/large/beam50.toml", {}).scene,
                      "50-node beam", {0.001, 0.03, 0.1});
}

// (c) Quad against double, event by event, on the damped scenes.
struct Agreement {
  double worst = 0;
  int compared = 0, releases = 0;
  bool parted_at_grazing = false;
};

// Walks both logs event by event (kind, and time within tol · T). With stop_at_grazing, stops at the
// first near-grazing contact (|ẋ_B⁻| < 1e-4: the event map has a square-root singularity there and
// a rounding-level difference may legitimately change the sequence, as in quad_differential_test).
Agreement Compare(const Outcome& dbl, const Outcome& quad, double T, double tol,
                  const std::string& name, bool stop_at_grazing) {
  const auto& a = dbl.log.events;
  const auto& b = quad.log.events;
  Agreement g;
  size_t i = 0, j = 0;
  for (; i < a.size() && j < b.size(); ++i, ++j) {
    if (!AlignChatteringTails(a, i, b, j)) break;
    EXPECT_EQ(a[i].kind, b[j].kind) << fmt::format("{} event {}/{}: double {} at {:.17g}, quad {} at {:.17g}",
                                                   name, i, j, ToString(a[i].kind), a[i].t,
                                                   ToString(b[j].kind), b[j].t);
    if (a[i].kind != b[j].kind) return g;
    if (stop_at_grazing && (b[j].kind == EventKind::kImpact || b[j].kind == EventKind::kGrazing) &&
        std::abs(b[j].v_before) < 1e-4) {
      g.parted_at_grazing = true;
      return g;
    }
    const double dt = std::abs(a[i].t - b[j].t) / T;
    g.worst = std::max(g.worst, dt);
    EXPECT_LE(dt, tol) << fmt::format("{} event {} ({} at {:.17g} vs {:.17g})", name, i,
                                      ToString(a[i].kind), a[i].t, b[j].t);
    ++g.compared;
    g.releases += a[i].kind == EventKind::kRelease;
  }
  EXPECT_EQ(i == a.size(), j == b.size()) << name << ": one log has events the other lacks";
  return g;
}

void ExpectEnginesAgree(Scene s, const std::string& name, long long periods, bool plastic) {
  s.run.periods = periods;
  s.run.samples_per_period = 0;
  if (plastic) s.restitution = 0.0;
  Scene q = s;
  q.run.precision = Precision::kQuad;
  if (!plastic) s.run.chatter_tolerance = q.run.chatter_tolerance = 1e-15;
  const Outcome dbl = Simulate(s);
  const Outcome quad = Simulate(q);
  ASSERT_EQ(quad.result.status, RunStatus::kOk) << name << ": " << quad.result.message;
  ASSERT_EQ(dbl.result.status, RunStatus::kOk) << name << ": " << dbl.result.message;
  ASSERT_GT(quad.result.counts.sticks, 2) << name;
  const Agreement g = Compare(dbl, quad, 2.0 * M_PI / s.frequency, 1e-12, name, false);
  EXPECT_GT(g.releases, 2) << name;
  std::printf("%s: %d events compared (%d releases), worst |Δt|/T %.3g\n", name.c_str(), g.compared,
              g.releases, g.worst);
}

TEST(QuadDampedSticking, AgreesWithTheDoubleEngineOnTheDampedScenes) {
  for (const bool plastic : {true, false}) {
    const std::string r = plastic ? ", r = 0" : "";
    for (const char* f : {"chain2_damped.toml"}) {
      const Scene s = LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + f, {}).scene;
      ExpectEnginesAgree(s, f + r, 40, plastic);
    }
    ExpectEnginesAgree(TwoDof(), "2-DOF, ζ = (0.06, 0.15)" + r, 40, plastic);
    ExpectEnginesAgree(ThreeDof(), "damped 3-DOF chain" + r, 40, plastic);
  }
}

// Seeded random damped scenes of 2 and 3 modes (every mode damped, ζ up to 0.3), 4 periods from
// the default start, at equal accumulation targets: every event within 1e-12 T up to the first
// near-grazing contact, and sticking phases among them.
TEST(QuadDampedSticking, RandomDampedScenesAgreeWithTheDoubleEngine) {
  std::mt19937_64 rng(20261125);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int scenes_run = 0, with_sticking = 0, events = 0, releases = 0;
  double worst = 0;
  for (int k = 0; k < 200; ++k) {
    const int n = 2 + static_cast<int>(u(rng) * 2.0);
    Eigen::VectorXd w(n), TA(n), TB(n), zeta(n);
    double base = 0.5 + u(rng);
    for (int i = 0; i < n; ++i) {
      w[i] = base;
      base *= 1.3 + 2.0 * u(rng);
      TA[i] = 2.0 * u(rng) - 1.0;
      TB[i] = 0.2 + 1.3 * u(rng);
      zeta[i] = 0.3 * u(rng);
    }
    Scene s;
    s.modal = ModalStructureSpec{w, TA, TB};
    s.damping_ratios = zeta;
    s.restitution = u(rng) < 0.3 ? 0.0 : 0.9 * u(rng);
    s.stop_position = u(rng) < 0.7 ? 1.0 : -1.0;
    s.frequency = 0.5 + 4.0 * u(rng);
    s.amplitude = 0.3 + 4.0 * u(rng);
    s.run.periods = 4;
    s.run.samples_per_period = 0;
    s.run.chatter_tolerance = 1e-15;
    if (!Validate(s).empty()) continue;
    Scene q = s;
    q.run.precision = Precision::kQuad;
    const Outcome dbl = Simulate(s);
    const Outcome quad = Simulate(q);
    ASSERT_EQ(quad.result.status, RunStatus::kOk) << "scene " << k << ": " << quad.result.message;
    if (dbl.result.status != RunStatus::kOk) continue;  // undetermined: nothing to compare
    ++scenes_run;
    const Agreement g = Compare(dbl, quad, 2.0 * M_PI / s.frequency, 1e-12,
                                fmt::format("random scene {}", k), true);
    worst = std::max(worst, g.worst);
    events += g.compared;
    releases += g.releases;
    with_sticking += g.releases > 0;
  }
  std::printf("random damped scenes: %d run, %d with sticking, %d events (%d releases), worst "
              "|Δt|/T %.3g\n", scenes_run, with_sticking, events, releases, worst);
  EXPECT_GE(scenes_run, 150);
  EXPECT_GE(with_sticking, 40);
}

}  // namespace
}  // namespace vibro::test
