// Several contacts against closed forms (docs/contacts.md, "Checked against"): the symmetric
// two-sided 1-DOF oscillator ẍ + ω_1² x = a sin ωt with stops at x = ∓Δ.
//  * the symmetric period-1 orbit with one impact on each stop, 0 < r < 1: its impact speed V
//    solves (k1² + k2²) V² − 2Δ k1 V + Δ² − U² = 0 and its phase U sin φ = Δ − k1 V,
//    U cos φ = k2 V (derived by matching the closed-form flight over T/2; both roots, the stable
//    and the unstable one);
//  * r = 0 with sticking: release where the reaction a sin ωt − ω_1²Δ vanishes, landing on the
//    other stop at the first root of the flight from rest, sticking proportion 1 − ω s_l/π;
//  * the lower limit of that orbit, √(a² − ω_1⁴Δ²) = ω ω_1 Δ cot(ω_1π/(2ω)), where the sticking
//    proportion vanishes, and its sign trap (a spurious value when the cotangent is negative);
//  * reductions: a second stop that is never reached gives the single stop's events to the bit;
//  * the CVODE engine on the symmetric orbit, within its tolerance (docs/engines.md).
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "support.hpp"

namespace vibro::test {
namespace {

// The 1-DOF oscillator (unit mass, stiffness ω_1²) with stops at −Δ (below) and +Δ (above).
Scene TwoSided(double w1, double a, double delta, double r, double w, long long periods) {
  Scene s;
  s.physical = PhysicalStructureSpec{Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Constant(1, 1, w1 * w1), 0, 0};
  s.contacts = {ContactSpec{0, -1, Side::kBelow, -delta, r}, ContactSpec{0, -1, Side::kAbove, delta, r}};
  s.frequency = w;
  s.amplitude = a;
  s.run.periods = periods;
  s.run.samples_per_period = 0;
  return s;
}

Outcome From(Scene s, double t0, double x, double v) {
  s.initial_time = t0;
  s.initial_displacement = Eigen::VectorXd::Constant(1, x);
  s.initial_velocity = Eigen::VectorXd::Constant(1, v);
  return Simulate(s);
}

double Elapsed(const Event& e, double t0) { return e.t - t0; }

struct Orbit2 {
  LD V, phi;
};

// The two impact speeds of the symmetric orbit and their phases at the upper stop.
std::vector<Orbit2> SymmetricOrbits(LD w1, LD a, LD delta, LD r, LD w) {
  const LD U = a / (w1 * w1 - w * w), theta = w1 * M_PIl / w;
  const LD k1 = (1 + r) * std::tan(theta / 2) / (2 * w1), k2 = (1 - r) / (2 * w);
  const LD A = k1 * k1 + k2 * k2, B = -2 * delta * k1, C = delta * delta - U * U;
  const LD disc = B * B - 4 * A * C;
  std::vector<Orbit2> out;
  if (disc < 0) return out;
  for (const LD V : {(-B + std::sqrt(disc)) / (2 * A), (-B - std::sqrt(disc)) / (2 * A)}) {
    if (!(V > 0)) continue;
    out.push_back({V, std::atan2((delta - k1 * V) / U, k2 * V / U)});
  }
  return out;
}

TEST(ContactsClosedForms, SymmetricOrbitRootsReproduceTheModelValues) {
  const auto o = SymmetricOrbits(1, 1, 1, 0.8L, 2.5L);
  ASSERT_EQ(o.size(), 2u);
  EXPECT_NEAR(static_cast<double>(o[0].V), 1.79902274247141, 1e-13);
  EXPECT_NEAR(static_cast<double>(o[1].V), 1.24820079806749, 1e-13);
}

// Every impact of the run alternates between the stops every T/2 with the closed form's speed.
void CheckSymmetricOrbit(double w1, double a, double delta, double r, double w, int periods) {
  const auto orbits = SymmetricOrbits(w1, a, delta, r, w);
  ASSERT_FALSE(orbits.empty());
  for (const Orbit2& o : orbits) {
    SCOPED_TRACE(testing::Message() << "(ω1, a, Δ, r, ω) = (" << w1 << ", " << a << ", " << delta
                                    << ", " << r << ", " << w << "), V = " << static_cast<double>(o.V));
    const double T = 2 * M_PI / w;
    LD phi = o.phi;
    if (phi < 0) phi += 2 * M_PIl;
    const double t0 = static_cast<double>(phi / w);
    // Just after the impact at +Δ: ẋ = −rV (moving away from the upper stop).
    const Outcome run = From(TwoSided(w1, a, delta, r, w, periods), t0, delta, static_cast<double>(-r * o.V));
    ASSERT_EQ(run.result.status, RunStatus::kOk) << run.result.message;
    const auto impacts = run.log.Of(EventKind::kImpact);
    // One impact per half period (the last one may fall on the end of the run).
    ASSERT_GE(static_cast<int>(impacts.size()), 2 * periods - 1);
    for (size_t k = 0; k < impacts.size(); ++k) {
      const Event& e = impacts[k];
      SCOPED_TRACE(testing::Message() << "impact " << k);
      EXPECT_EQ(e.contact, k % 2 == 0 ? 0 : 1) << "alternately below, above";
      EXPECT_NEAR(Elapsed(e, t0), (static_cast<double>(k) + 1) * T / 2, 1e-12 * T);
      // Gap rates (docs/contacts.md): −V before, rV after, on either stop.
      EXPECT_NEAR(e.v_before, static_cast<double>(-o.V), 1e-12 * static_cast<double>(o.V));
      EXPECT_NEAR(e.v_after, static_cast<double>(r * o.V), 1e-12 * static_cast<double>(o.V));
      EXPECT_NEAR(e.x_B, k % 2 == 0 ? -delta : delta, 1e-14);
      EXPECT_FALSE(e.simultaneous);
    }
    ASSERT_EQ(run.result.contact_counts.size(), 2u);
    EXPECT_EQ(run.result.contact_counts[0].impacts + run.result.contact_counts[1].impacts,
              static_cast<long long>(impacts.size()));
    EXPECT_EQ(run.result.contact_counts[0].impacts, static_cast<long long>(periods));
  }
}

TEST(ContactsClosedForms, SymmetricPeriodOneOrbitStableAndUnstable) {
  // The unstable orbit's multiplier (8.85 at the first set) amplifies rounding: 2 periods keep it
  // within the 1e-12 of the check; the stable one is followed for 20.
  CheckSymmetricOrbit(1, 1, 1, 0.8, 2.5, 2);
  CheckSymmetricOrbit(1, 2, 1, 0.8, 3, 2);
  CheckSymmetricOrbit(1.3, 1.5, 0.5, 0.6, 2, 2);
  CheckSymmetricOrbit(1, 0.6, 1, 0.8, 0.9, 2);
}

TEST(ContactsClosedForms, StableSymmetricOrbitHoldsOverManyPeriods) {
  const auto o = SymmetricOrbits(1, 1, 1, 0.8L, 2.5L)[0];
  const double w = 2.5, T = 2 * M_PI / w, t0 = static_cast<double>(o.phi / w);
  const Outcome run = From(TwoSided(1, 1, 1, 0.8, w, 50), t0, 1, static_cast<double>(-0.8L * o.V));
  ASSERT_EQ(run.result.status, RunStatus::kOk);
  const auto impacts = run.log.Of(EventKind::kImpact);
  ASSERT_GE(impacts.size(), 99u);
  for (size_t k = 0; k < impacts.size(); ++k) {
    EXPECT_NEAR(Elapsed(impacts[k], t0), (static_cast<double>(k) + 1) * T / 2, 1e-12 * T);
    EXPECT_NEAR(impacts[k].v_before, static_cast<double>(-o.V), 1e-12);
  }
}

// The CVODE engine on the same orbit (docs/engines.md): rtol = 1e-12, atol = 1e-14. Each flight
// of T/2 is integrated to a local error of ≈ rtol per step and its landing located to that error
// divided by the closing speed V ≈ 1.8; the stable orbit (multiplier < 1) keeps the errors from
// growing over the periods. Measured over 20 periods: impact times within 7.8e-13 T, speeds
// within 2.1e-12 relative; kCvodeTime and kCvodeSpeed leave a margin of ten.
constexpr double kCvodeTime = 1e-11, kCvodeSpeed = 2e-11;

TEST(ContactsClosedForms, CvodeFollowsTheSymmetricOrbit) {
  const auto o = SymmetricOrbits(1, 1, 1, 0.8L, 2.5L)[0];
  const double w = 2.5, T = 2 * M_PI / w, t0 = static_cast<double>(o.phi / w);
  Scene s = TwoSided(1, 1, 1, 0.8, w, 20);
  s.run.engine = Engine::kCvode;
  s.run.rtol = 1e-12;
  s.run.atol = 1e-14;
  const Outcome run = From(s, t0, 1, static_cast<double>(-0.8L * o.V));
  ASSERT_EQ(run.result.status, RunStatus::kOk) << run.result.message;
  const auto impacts = run.log.Of(EventKind::kImpact);
  ASSERT_GE(impacts.size(), 39u);
  double worst_t = 0, worst_v = 0;
  for (size_t k = 0; k < impacts.size(); ++k) {
    SCOPED_TRACE(testing::Message() << "impact " << k);
    EXPECT_EQ(impacts[k].contact, k % 2 == 0 ? 0 : 1) << "alternately below, above";
    const double dt = std::abs(Elapsed(impacts[k], t0) - (static_cast<double>(k) + 1) * T / 2) / T;
    const double dv = std::abs(impacts[k].v_before + static_cast<double>(o.V)) / static_cast<double>(o.V);
    EXPECT_LE(dt, kCvodeTime);
    EXPECT_LE(dv, kCvodeSpeed);
    worst_t = std::max(worst_t, dt);
    worst_v = std::max(worst_v, dv);
  }
  std::printf("CVODE on the symmetric orbit, 20 periods: worst |dt|/T %.3g, |dV|/V %.3g\n", worst_t, worst_v);
}

// r = 0: stuck on +Δ until the reaction a sin ωt − Δ vanishes (ω_1 = 1), free flight from rest
// (the flight of docs/model.md §2 with x = Δ, ẋ = 0 at the release), landing on −Δ.
struct StickingOrbit {
  LD phi_r, s_l, sp;
};

StickingOrbit RZeroOrbit(LD a, LD delta, LD w) {
  const LD phi_r = M_PIl - std::asin(delta / a);
  const Flight1 flight{w, a, phi_r / w, delta, 0};
  const LD landing = flight.Landing(-delta);
  const LD s_l = landing - phi_r / w;
  return {phi_r, s_l, 1 - w * s_l / M_PIl};
}

void CheckRZeroSticking(double a, double delta, double w) {
  SCOPED_TRACE(testing::Message() << "(a, Δ, ω) = (" << a << ", " << delta << ", " << w << ")");
  const StickingOrbit o = RZeroOrbit(a, delta, w);
  const double T = 2 * M_PI / w;
  // Preconditions of the orbit: it lands before the next release and sticks there.
  ASSERT_LT(o.s_l, T / 2);
  ASSERT_GT(-delta - a * std::sin(static_cast<double>(o.phi_r + w * o.s_l)), 0) << "λ_l > 0";
  // Start stuck on +Δ at phase π/2, where the reaction a − Δ is largest.
  const double t0 = M_PI / 2 / w;
  const Outcome run = From(TwoSided(1, a, delta, 0, w, 8), t0, delta, 0);
  ASSERT_EQ(run.result.status, RunStatus::kOk) << run.result.message;
  const auto releases = run.log.Of(EventKind::kRelease);
  const auto sticks = run.log.Of(EventKind::kStick);
  ASSERT_GE(releases.size(), 15u);
  for (size_t k = 0; k < releases.size(); ++k) {
    SCOPED_TRACE(testing::Message() << "release " << k);
    const Event& rel = releases[k];
    // Release k at φ_r + kπ, alternately from +Δ (contact 1) and −Δ (contact 0).
    EXPECT_EQ(rel.contact, k % 2 == 0 ? 1 : 0);
    const double t_rel = static_cast<double>((o.phi_r + static_cast<LD>(k) * M_PIl) / w);
    EXPECT_NEAR(rel.t, t_rel, 1e-12 * T);
    // The landing that follows: a plastic impact and a stick at release + s_l.
    const Event* st = nullptr;
    for (const Event& e : sticks)
      if (e.t > rel.t) {
        st = &e;
        break;
      }
    if (st == nullptr) continue;  // the run ended in flight
    EXPECT_EQ(st->contact, k % 2 == 0 ? 0 : 1);
    EXPECT_NEAR(st->t - rel.t, static_cast<double>(o.s_l), 1e-12 * T);
  }
}

TEST(ContactsClosedForms, RZeroStickingOrbitReleasesAndLandings) {
  CheckRZeroSticking(4, 1, 1.4);
  CheckRZeroSticking(3, 1, 1.2);
  CheckRZeroSticking(1.5, 1, 1.4);
}

// The lower limit (T4): below it the flight from one release lands after the next.
LD LowerLimit(LD w, LD delta = 1) {
  const LD c = 1 / std::tan(M_PIl / (2 * w));
  return std::sqrt(w * w * delta * delta * c * c + delta * delta);
}

TEST(ContactsClosedForms, LowerLimitOfTheStickingOrbit) {
  const LD w = 1.4L;
  const LD a_lim = LowerLimit(w);
  EXPECT_NEAR(static_cast<double>(a_lim), 1.20604795195716, 1e-13);
  // The closed form's sticking proportion crosses zero there, linearly; the engine's, measured
  // on the run's attractor, extrapolated to zero from two points above it, gives a_lim.
  const auto sp_of_run = [&](double a) {
    const Outcome run = From(TwoSided(1, a, 1, 0, static_cast<double>(w), 20), M_PI / 2 / static_cast<double>(w), 1, 0);
    EXPECT_EQ(run.result.status, RunStatus::kOk) << run.result.message;
    EXPECT_TRUE(run.attractor.sticking_fraction.has_value());
    return run.attractor.sticking_fraction.value_or(-1);
  };
  const double a1 = static_cast<double>(a_lim * (1 + 1e-6L)), a2 = static_cast<double>(a_lim * (1 + 2e-6L));
  const double sp1 = sp_of_run(a1), sp2 = sp_of_run(a2);
  EXPECT_NEAR(sp1, static_cast<double>(RZeroOrbit(a1, 1, w).sp), 1e-12);
  ASSERT_GT(sp1, 0);
  ASSERT_GT(sp2, sp1);
  const double a_est = a1 - sp1 * (a2 - a1) / (sp2 - sp1);
  EXPECT_NEAR(a_est, static_cast<double>(a_lim), 1e-10);
}

TEST(ContactsClosedForms, LowerLimitSignTrap) {
  // ω = 0.8: cot(π/1.6) < 0 and (T4) returns a value where nothing vanishes: the orbit there
  // keeps a sticking proportion far from 0.
  const LD w = 0.8L;
  ASSERT_LT(1 / std::tan(M_PIl / (2 * w)), 0);
  const double a = static_cast<double>(LowerLimit(w));
  const StickingOrbit o = RZeroOrbit(a, 1, w);
  EXPECT_GT(std::abs(static_cast<double>(o.sp)), 1e-3);
}

// A second stop that is never reached changes no bit of the single stop's events (MODEL §11.10),
// with either engine (CVODE: its root functions never cross, and a root return at one of their
// rate roots leaves CVODE's steps unchanged).
TEST(ContactsReductions, UnreachedSecondStopGivesTheSingleStopEventsToTheBit) {
  for (const bool damped : {false, true}) {
    for (const Engine engine : {Engine::kExact, Engine::kCvode}) {
      SCOPED_TRACE(testing::Message() << (damped ? "damped chain" : "undamped chain")
                                      << (engine == Engine::kCvode ? ", cvode" : ", exact"));
      Scene single = Chain(2, 1.0, 0.5, 0.8, 0.8);
      single.run.periods = 60;
      single.run.engine = engine;
      if (damped) single.damping_ratios = Eigen::VectorXd::Constant(2, 0.02);
      Scene two = single;
      two.contacts = {ContactSpec{1, -1, Side::kBelow, 1.0, 0.5}, ContactSpec{0, -1, Side::kAbove, 50.0, 0.7}};
      const Outcome a = Simulate(single), b = Simulate(two);
      ASSERT_EQ(a.result.status, RunStatus::kOk);
      ASSERT_EQ(b.result.status, RunStatus::kOk) << b.result.message;
      ASSERT_EQ(a.log.events.size(), b.log.events.size());
      ASSERT_GT(a.log.events.size(), 100u);
      for (size_t k = 0; k < a.log.events.size(); ++k) {
        const Event &x = a.log.events[k], &y = b.log.events[k];
        ASSERT_EQ(x.kind, y.kind) << k;
        ASSERT_EQ(x.clock.period, y.clock.period) << k;
        ASSERT_EQ(x.clock.offset, y.clock.offset) << k;
        ASSERT_EQ(x.x_B, y.x_B) << k;
        ASSERT_EQ(x.v_before, y.v_before) << k;
        ASSERT_EQ(x.v_after, y.v_after) << k;
        ASSERT_EQ(y.contact, 0);
      }
    }
  }
}

}  // namespace
}  // namespace vibro::test
