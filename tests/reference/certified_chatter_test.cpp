// Certified chattering (docs/model.md §5.4, docs/chattering.md) at the upper end of sticking, f → f_max,
// where the constant-R accumulation prediction used to invent sticking orbits.
//
// Truth: the quad-precision exact engine (113 bits, run.precision = "quad", accumulation error
// target 1e-28 T), which follows the chattering impacts explicitly until its own prediction is
// certain to 28 digits. f_max is located by bisecting, with that engine, the existence of the
// period-1 sticking orbit of the non-dimensional 1-DOF preload oscillator: for one DOF every
// motion that sticks once is periodic from its first release on (docs/model.md §5.5), so the orbit
// exists iff the body, released at the closed-form phase sin φ_1 = x0/f (docs/model.md §6.1), sticks
// again within one forcing period.
#include <cmath>
#include <optional>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/continuation.hpp"
#include "vibro/poincare.hpp"

namespace vibro::test {
namespace {

// What one period after the first release shows: whether the body sticks again and where.
struct Landing {
  RunStatus status;
  bool sticks = false;
  double stick_phase = 0;          // ωt of the stick event, in [0, 2π)
  double sticking_fraction = 0;    // (next release − stick) / T
  long long impacts = 0;
};

Scene PreloadRun(double r, double w, double f, Precision precision,
                 Engine engine = Engine::kExact, double rtol = 1e-10) {
  Scene s = OneDof(r, w, f, 1.0, 3);
  // At rest on the stop a quarter period before the release: R > 0 there.
  s.initial_time = static_cast<double>(ReleaseTime(w, f)) - 0.25 * 2.0 * M_PI / w;
  s.initial_displacement = Eigen::VectorXd::Ones(1);
  s.initial_velocity = Eigen::VectorXd::Zero(1);
  s.run.precision = precision;
  s.run.engine = engine;
  s.run.rtol = rtol;
  s.run.atol = rtol * 1e-2;
  return s;
}

Landing Land(const Scene& s) {
  const Outcome run = Simulate(s);
  Landing out{run.result.status};
  const double T = 2.0 * M_PI / s.frequency;
  const auto releases = run.log.Of(EventKind::kRelease);
  if (releases.empty()) return out;
  const double t_r = releases.front().t;
  for (const auto& e : run.log.events) {
    if (e.t <= t_r) continue;
    if (e.t > t_r + T) break;
    if (e.kind == EventKind::kImpact) ++out.impacts;
    if (e.kind == EventKind::kStick) {
      out.sticks = true;
      out.stick_phase = std::fmod(s.frequency * e.t, 2.0 * M_PI);
      out.sticking_fraction = (t_r + T - e.t) / T;
      break;
    }
  }
  return out;
}

struct Boundary {
  double lo, hi;  // the quad engine sticks at lo, not at hi
};

// f_max by bisection with the quad engine, from a scan in f.
std::optional<Boundary> QuadFmax(double r, double w) {
  double lo = 0, hi = 0;
  for (double f = 1.02; f < 12.0; f *= 1.02) {
    const Landing l = Land(PreloadRun(r, w, f, Precision::kQuad));
    if (l.status != RunStatus::kOk) return std::nullopt;
    if (l.sticks) {
      lo = f;
    } else if (lo > 0) {
      hi = f;
      break;
    }
  }
  if (hi == 0) return std::nullopt;
  while (hi - lo > 4e-13 * hi) {
    const double mid = 0.5 * (lo + hi);
    const Landing l = Land(PreloadRun(r, w, mid, Precision::kQuad));
    if (l.status != RunStatus::kOk) break;  // undetermined even in quad: the bracket is final
    (l.sticks ? lo : hi) = mid;
  }
  return Boundary{lo, hi};
}

struct Case {
  double r, w;
};

class UpperEndOfSticking : public testing::TestWithParam<Case> {};

TEST_P(UpperEndOfSticking, DoubleNeverInventsStickingAndAgreesBelowFmax) {
  const auto [r, w] = GetParam();
  const auto b = QuadFmax(r, w);
  ASSERT_TRUE(b.has_value()) << "no f_max found for r = " << r << ", ω = " << w;
  ASSERT_LT(b->hi - b->lo, 1e-11) << "the quad bisection stopped early";
  const double f_max = b->lo;
  std::printf("r = %.2f, ω = %.1f: f_max ∈ [%.15g, %.15g] (quad bisection)\n", r, w, b->lo, b->hi);

  // Above f_max the true motion never sticks within the period: the double engine must not
  // report it (an "undetermined" status is allowed, a stick is not).
  for (double d : {1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 3e-6, 1e-5}) {
    const Landing q = Land(PreloadRun(r, w, b->hi + d, Precision::kQuad));
    ASSERT_EQ(q.status, RunStatus::kOk);
    ASSERT_FALSE(q.sticks) << "quad sticks above its own f_max at +" << d;
    const Landing dbl = Land(PreloadRun(r, w, b->hi + d, Precision::kDouble));
    EXPECT_FALSE(dbl.sticks) << "double invents sticking at f_max + " << d << " (r = " << r
                             << ", ω = " << w << ")";
    if (d >= 1e-8) {
      EXPECT_EQ(dbl.status, RunStatus::kOk) << "at f_max + " << d;
    }
  }
  // Below f_max: sticking fraction to 1e-10 and stick phase to 1e-9 rad.
  for (double d : {1e-5, 1e-7}) {
    const double f = f_max - d;
    const Landing q = Land(PreloadRun(r, w, f, Precision::kQuad));
    ASSERT_EQ(q.status, RunStatus::kOk);
    ASSERT_TRUE(q.sticks);
    const Landing dbl = Land(PreloadRun(r, w, f, Precision::kDouble));
    ASSERT_EQ(dbl.status, RunStatus::kOk) << "f_max − " << d;
    ASSERT_TRUE(dbl.sticks) << "f_max − " << d;
    EXPECT_NEAR(dbl.sticking_fraction, q.sticking_fraction, 1e-10) << "f_max − " << d;
    EXPECT_NEAR(dbl.stick_phase, q.stick_phase, 1e-9) << "f_max − " << d;
    EXPECT_GT(q.sticking_fraction, 0.0);
    // CVODE at rtol 1e-12 under the same rule.
    const Landing cv = Land(PreloadRun(r, w, f, Precision::kDouble, Engine::kCvode, 1e-12));
    std::printf("  f_max − %g: CVODE rtol 1e-12 %s, |ΔSP| = %.3g, |Δphase| = %.3g\n", d,
                ToString(cv.status), std::abs(cv.sticking_fraction - q.sticking_fraction),
                std::abs(cv.stick_phase - q.stick_phase));
    if (cv.status == RunStatus::kOk) {
      ASSERT_TRUE(cv.sticks) << "CVODE, f_max − " << d;
      EXPECT_NEAR(cv.sticking_fraction, q.sticking_fraction, 1e-8) << "CVODE, f_max − " << d;
    } else {
      EXPECT_EQ(cv.status, RunStatus::kUndetermined) << "CVODE, f_max − " << d;
    }
  }
  // Above f_max CVODE never reports sticking either.
  for (double d : {1e-9, 1e-7, 1e-5}) {
    const Landing cv = Land(PreloadRun(r, w, b->hi + d, Precision::kDouble, Engine::kCvode, 1e-12));
    EXPECT_FALSE(cv.sticks) << "CVODE invents sticking at f_max + " << d;
  }
}

INSTANTIATE_TEST_SUITE_P(Preload, UpperEndOfSticking,
                         testing::Values(Case{0.3, 2.0}, Case{0.5, 2.8}, Case{0.75, 2.8},
                                         Case{0.9, 5.0}, Case{0.5, 10.0}, Case{0.75, 10.0},
                                         Case{0.3, 5.0}, Case{0.9, 2.0}),
                         [](const testing::TestParamInfo<Case>& i) {
                           return fmt::format("r{:.0f}_w{:.0f}", 100 * i.param.r, 10 * i.param.w);
                         });

// `vibro continue` ends the period-1 sticking branch (sticking-lost) at the quad engine's f_max.
TEST(StickingLost, ContinuationLocatesItAtTheQuadFmax) {
  for (const Case c : {Case{0.75, 2.8}, Case{0.5, 5.0}, Case{0.9, 2.0}, Case{0.3, 10.0}}) {
    SCOPED_TRACE(testing::Message() << "r = " << c.r << ", ω = " << c.w);
    const auto b = QuadFmax(c.r, c.w);
    ASSERT_TRUE(b.has_value());
    ContinuationRequest req;
    req.scene_at = [c](double f) { return OneDof(c.r, c.w, f, 1.0, 50); };
    req.from = 1.0 + 0.5 * (b->lo - 1.0);
    req.to = b->hi + 0.5;
    const Branch br = Continue(req);
    ASSERT_FALSE(br.bifurcations.empty()) << br.status << " " << br.end;
    EXPECT_EQ(br.bifurcations.back().kind, "sticking-lost");
    EXPECT_NEAR(br.bifurcations.back().value, b->lo, 1e-10)
        << fmt::format("continuation {:.15g}, quad [{:.15g}, {:.15g}]", br.bifurcations.back().value,
                       b->lo, b->hi);
  }
}

// The 2-DOF chain (data/scenes/chain2.toml: unit masses and springs, stop on mass 2 with preload
// x0 = 1, r = 0.5, ω = 0.8): its period-1 sticking branch in f ends (sticking-lost) near 1.2063.
// Truth: the quad engine simulating from a point of the double orbit just below the end (the
// orbit is stable: a transient from a nearby state settles on it), over 40 periods; the branch
// exists at f iff the motion then sticks once in each of the last 10 periods.
Scene Chain2At(double f, Precision precision, long long periods) {
  Scene s = Chain(2, 1.0, 0.5, 0.8, f);
  s.run.periods = periods;
  s.run.precision = precision;
  return s;
}

struct ChainSticking {
  RunStatus status;
  bool sticks_every_period = false;
  double sticking_fraction = 0;  // over the last 10 periods
};

ChainSticking ChainRun(double f, Precision precision, const InitialOverride& from, long long periods) {
  const Outcome run = Simulate(Chain2At(f, precision, periods), &from);
  ChainSticking out{run.result.status};
  const double T = 2.0 * M_PI / 0.8, t_end = from.time + static_cast<double>(periods) * T;
  int sticks = 0;
  double stuck = 0, since = -1;
  for (const auto& e : run.log.events) {
    if (e.t < t_end - 10 * T) continue;
    if (e.kind == EventKind::kStick) {
      ++sticks;
      since = e.t;
    }
    if (e.kind == EventKind::kRelease && since >= 0) {
      stuck += e.t - since;
      since = -1;
    }
  }
  out.sticks_every_period = sticks >= 10;
  out.sticking_fraction = stuck / (10 * T);
  return out;
}

TEST(StickingLost, TwoDofChainAgreesWithTheQuadEngine) {
  ContinuationRequest req;
  req.scene_at = [](double f) { return Chain2At(f, Precision::kDouble, 50); };
  req.from = 0.8;
  req.to = 2.0;
  const Branch br = Continue(req);
  ASSERT_FALSE(br.bifurcations.empty());
  ASSERT_EQ(br.bifurcations.back().kind, "sticking-lost");
  const double f_cont = br.bifurcations.back().value;
  // A start on the orbit 1e-4 below the end, for every quad run.
  const double f_start = f_cont - 1e-4;
  OrbitRequest oreq;
  oreq.kind = OrbitKind::kSticking;
  oreq.period = 1;
  const OrbitResult o = FindOrbit(System(Chain2At(f_start, Precision::kDouble, 50)),
                                  Chain2At(f_start, Precision::kDouble, 50), oreq);
  ASSERT_EQ(o.status, "converged") << o.message;
  const InitialOverride start{o.section_time, o.X, o.V};
  // Quad bisection of the end of the branch.
  double lo = f_start, hi = f_cont + 1e-4;
  ASSERT_TRUE(ChainRun(lo, Precision::kQuad, start, 40).sticks_every_period);
  ASSERT_FALSE(ChainRun(hi, Precision::kQuad, start, 40).sticks_every_period);
  while (hi - lo > 1e-12) {
    const double mid = 0.5 * (lo + hi);
    const ChainSticking c = ChainRun(mid, Precision::kQuad, start, 40);
    if (c.status != RunStatus::kOk) break;
    (c.sticks_every_period ? lo : hi) = mid;
  }
  std::printf("2-DOF chain: continuation %.15g, quad [%.15g, %.15g]\n", f_cont, lo, hi);
  EXPECT_LT(hi - lo, 1e-10);
  // Within 4e-10 of f_max the double engine's chattering tails reach the rounding floor of ẋ_B
  // before a prediction is good enough ("undetermined", never sticking where quad does not);
  // continuation then evaluates the map there with the quad engine, and must say so.
  EXPECT_NEAR(f_cont, lo, 1e-10);
  EXPECT_GT(br.quad_evaluations, 0) << "the double engine decided every tail up to the end";
  // Above the end the double engine sticks in no period either; below it the sticking fractions
  // agree with quad (both simulating from the same start until the transient has gone).
  for (double d : {1e-8, 1e-6, 1e-4}) {
    const ChainSticking c = ChainRun(hi + d, Precision::kDouble, start, 40);
    EXPECT_FALSE(c.sticks_every_period && c.status == RunStatus::kOk) << "f_max + " << d;
  }
  for (double d : {1e-5, 1e-7}) {
    const ChainSticking q = ChainRun(lo - d, Precision::kQuad, start, 200);
    const ChainSticking c = ChainRun(lo - d, Precision::kDouble, start, 200);
    ASSERT_EQ(c.status, RunStatus::kOk) << "f_max − " << d;
    ASSERT_TRUE(q.sticks_every_period && c.sticks_every_period);
    std::printf("  f_max − %g: SP double %.15g quad %.15g\n", d, c.sticking_fraction,
                q.sticking_fraction);
    EXPECT_NEAR(c.sticking_fraction, q.sticking_fraction, 1e-10) << "f_max − " << d;
  }
}

}  // namespace
}  // namespace vibro::test
