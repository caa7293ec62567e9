// Continuation: the end of the sticking branch against f_free-flight of docs/model.md §6.3, branch points
// against direct orbit solves, and a Neimark–Sacker point bracketed by direct solves.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <thread>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/continuation.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

// The continuation of the period-1 one-impact orbit of `at` from `from` to `to`.
Branch ImpactBranch(std::function<Scene(double)> at, double from, double to, int max_points = 1000) {
  ContinuationRequest req;
  req.scene_at = std::move(at);
  req.from = from;
  req.to = to;
  req.max_points = max_points;
  req.orbit.kind = OrbitKind::kImpact;
  req.orbit.period = 1;
  return Continue(req);
}

TEST(Continuation, StickingBranchInAmplitudeEndsAtTheFreeFlightLimit) {
  // 1-DOF, r = 0: the period-1 sticking branch in f ends (sticking-lost) at
  // f_ff(ω, 1) = √(1 + ω² tan²(π/ω)) (docs/model.md §6.3, valid where tan(π/ω) > 0).
  for (double w : {2.8, 5.0, 10.0}) {
    SCOPED_TRACE(w);
    const double fff = std::sqrt(1.0 + w * w * std::pow(std::tan(M_PI / w), 2));
    ContinuationRequest req;
    req.scene_at = [w](double f) { return OneDof(0.0, w, f, 1.0, 50); };
    req.from = 1.5;
    req.to = fff + 2.0;
    const Branch b = Continue(req);
    ASSERT_EQ(b.status, "ok");
    EXPECT_EQ(b.end, "sticking-lost");
    ASSERT_FALSE(b.bifurcations.empty());
    EXPECT_EQ(b.bifurcations.back().kind, "sticking-lost");
    EXPECT_NEAR(b.bifurcations.back().value, fff, 1e-10);
    // SP decreases along the branch and every point is a stable (superstable) sticking orbit.
    for (size_t i = 1; i < b.points.size(); ++i) {
      EXPECT_LT(*b.points[i].summary.sticking_fraction, *b.points[i - 1].summary.sticking_fraction);
      EXPECT_TRUE(b.points[i].stable);
    }
  }
}

TEST(Continuation, BranchPointsAreOrbitsOfTheDirectSolver) {
  const std::string path = std::string(VIBRO_SCENES_DIR) + "/chain2.toml";
  const auto at = [&](double f) {
    return LoadScene(path, {"run.samples_per_period=0", fmt::format("excitation.amplitude={:.17g}", f)})
        .scene;
  };
  ContinuationRequest req;
  req.scene_at = at;
  req.from = 0.8;
  req.to = 0.9;
  req.max_points = 12;
  const Branch b = Continue(req);
  ASSERT_EQ(b.status, "ok") << b.end;
  ASSERT_GE(b.points.size(), 3u);
  for (size_t i = 1; i < b.points.size(); i += 2) {
    const auto& pt = b.points[i];
    // A direct solve at the same parameter (λ as printed to 6 digits is not λ: rebuild exactly).
    const Scene s = LoadScene(path, {"run.samples_per_period=0",
                                     fmt::format("excitation.amplitude={:.17g}", pt.value)}).scene;
    const System sys(s);
    const OrbitResult o = FindOrbit(sys, s, {});
    ASSERT_EQ(o.status, "converged");
    EXPECT_NEAR(*o.summary.sticking_fraction, *pt.summary.sticking_fraction, 1e-10) << pt.value;
    ASSERT_EQ(o.multipliers.size(), pt.multipliers.size());
    EXPECT_NEAR(std::abs(o.multipliers.front()), std::abs(pt.multipliers.front()), 1e-8);
  }
}

TEST(Continuation, FoldOfTheFig5ImpactOrbitIsPassedLocatedAndConfirmedBySimulation) {
  // Fig. 5: the stable single-impact period-1 orbit, continued down in f, meets its unstable
  // partner at a fold; the branch passes it and comes back on the unstable side.
  const auto at = [](double f) { return OneDof(0.75, 10.0, f, 1.0, 200); };
  const Branch b = ImpactBranch(at, 1.1, 0.3, 20);
  ASSERT_EQ(b.status, "ok") << b.end;
  const Bifurcation* fold = nullptr;
  for (const auto& x : b.bifurcations)
    if (x.kind == "fold") fold = &x;
  ASSERT_NE(fold, nullptr);
  // The closed form of the 1-DOF one-impact period-1 orbits (ẍ + x = f sin ωt, x ≥ x0 = 1,
  // τ = tan(π/ω)): (1−r)τx0 = P[(1−r)τ sin θ − (1+r)ω cos θ], P = f/(1−ω²); they exist while
  // |(1−r)τx0| ≤ |P|·√((1−r)²τ² + (1+r)²ω²), and the two meet at the equality: the fold.
  {
    const double w = 10.0, r = 0.75, tau = std::tan(M_PI / w);
    const double f_fold = std::abs(1 - w * w) * (1 - r) * tau / std::hypot((1 - r) * tau, (1 + r) * w);
    EXPECT_NEAR(fold->value, f_fold, 1e-10);
  }
  // Every point of the branch lies on the side f ≥ fold.
  for (const auto& pt : b.points) EXPECT_GE(pt.value, fold->value - 1e-9);
  // The branch's unstable side: a multiplier above 1 after the fold.
  EXPECT_FALSE(b.points.back().stable);
  // Simulation on each side, from a state on the stable orbit just above the fold: above it the
  // motion stays on a one-impact period-1 orbit; below it the orbit is gone.
  const auto orbit_state = [&](double f) {
    const Scene s = at(f);
    const System sys(s);
    OrbitRequest r;
    r.kind = OrbitKind::kImpact;
    r.period = 1;
    r.transient_periods = 400;
    return FindOrbit(sys, s, r);
  };
  const OrbitResult above = orbit_state(fold->value + 2e-3);
  ASSERT_EQ(above.status, "converged") << above.message;
  EXPECT_TRUE(above.stable);
  for (double df : {1e-3, -1e-3}) {
    Scene s = at(fold->value + df);
    s.initial_time = above.section_time;
    s.run.periods = 600;
    const InitialOverride start{above.section_time, above.X, above.V};
    const Attractor a = Simulate(s, &start).attractor;
    const bool one_impact = a.kind == "impact-periodic" && a.period == 1 && a.impacts_per_period == 1;
    EXPECT_EQ(one_impact, df > 0) << "f = fold " << df << ": " << a.kind;
  }
}

// Trace of DP of the 1-DOF one-impact period-1 orbit (impact phase θ, post-impact speed w+,
// acceleration a at the impact): tr = −2r cos T − r(1+r) a sin T / w+, det = r² (docs/model.md §5.6 by
// hand for the impact map; checked against vibro's multipliers below). Long double throughout.
long double OneImpactTrace(long double w, long double r, long double x0, long double f) {
  const long double T = 2 * M_PIl / w, tau = std::tan(T / 2), P = f / (1 - w * w);
  const long double a = (1 - r) * tau, b = (1 + r) * w;
  const long double th = std::atan2(b, a) + std::asin((1 - r) * tau * x0 / (P * std::hypot(a, b)));
  const long double wp = (x0 - P * std::sin(th)) * tau + P * w * std::cos(th);
  const long double acc = f * std::sin(th) - x0;
  return -2 * r * std::cos(T) - r * (1 + r) * acc * std::sin(T) / wp;
}

TEST(Continuation, FlipOfAOneImpactOrbitIsLocatedAtTheClosedFormAndConfirmedBySimulation) {
  // ω = 3, r = 0.5, x0 = 1: the one-impact period-1 orbit loses stability through μ = −1 where
  // tr DP = −(1 + r²) (det = r²); the closed form's root by bisection in long double.
  const double w = 3.0, r = 0.5;
  long double lo = 6.0L, hi = 7.6L;
  for (int i = 0; i < 200; ++i) {
    const long double mid = 0.5L * (lo + hi);
    (OneImpactTrace(w, r, 1.0L, mid) + 1 + r * r > 0 ? lo : hi) = mid;
  }
  const double f_flip = static_cast<double>(0.5L * (lo + hi));
  const auto at = [&](double f) { return OneDof(r, w, f, 1.0, 400); };
  const Branch b = ImpactBranch(at, 7.0, 7.6);
  ASSERT_EQ(b.status, "ok") << b.end;
  // The multipliers of vibro's orbit at the start: sum and product as the closed form says.
  const auto& mu = b.points.front().multipliers;
  ASSERT_EQ(mu.size(), 2u);
  EXPECT_NEAR((mu[0] + mu[1]).real(), static_cast<double>(OneImpactTrace(w, r, 1.0L, 7.0L)), 1e-9);
  EXPECT_NEAR((mu[0] * mu[1]).real(), r * r, 1e-9);
  const Bifurcation* flip = nullptr;
  for (const auto& x : b.bifurcations)
    if (x.kind == "flip") flip = &x;
  ASSERT_NE(flip, nullptr);
  EXPECT_NEAR(flip->value, f_flip, 1e-10);
  EXPECT_LT(flip->bracket, 1e-10);
  // Simulation on each side from the period-1 orbit, slightly perturbed: below the flip the
  // motion returns to it, above it the motion leaves for a period-2 orbit.
  for (double df : {-0.02, 0.02}) {
    const Scene s0 = at(f_flip + df);
    const System sys(s0);
    OrbitRequest o;
    o.kind = OrbitKind::kImpact;
    o.period = 1;
    const OrbitResult orbit = FindOrbit(sys, s0, o);
    ASSERT_EQ(orbit.status, "converged") << orbit.message;
    EXPECT_EQ(orbit.stable, df < 0);
    Scene s = s0;
    s.initial_time = orbit.section_time;
    s.run.periods = 4000;
    const InitialOverride start{orbit.section_time, orbit.X, orbit.V.array() + 1e-6};
    const Attractor a = Simulate(s, &start).attractor;
    EXPECT_EQ(a.kind, "impact-periodic");
    EXPECT_EQ(a.period.value_or(0), df < 0 ? 1 : 2) << "f = flip " << df;
  }
}

TEST(Continuation, RisingBifurcationOfATwoDofBranchIsLocatedFromBothSidesAndConfirmedBySimulation) {
  // 2-DOF chain, r = 0, ω = 0.4: along the period-1 sticking branch in f the reaction dips to zero
  // inside the sticking phase (docs/model.md §5.7), which splits in two.
  const std::string path = std::string(VIBRO_SCENES_DIR) + "/chain2.toml";
  const auto at = [&](double f) {
    return LoadScene(path, {"run.samples_per_period=0", "stop.restitution=0.0", "excitation.frequency=0.4",
                            "run.periods=400", fmt::format("excitation.amplitude={:.17g}", f)})
        .scene;
  };
  const auto rising = [&](double from, double to) {
    ContinuationRequest req;
    req.scene_at = at;
    req.from = from;
    req.to = to;
    req.step = 0.01;
    const Branch b = Continue(req);
    EXPECT_EQ(b.status, "ok") << b.end;
    for (const auto& x : b.bifurcations)
      if (x.kind == "rising") return x.value;
    ADD_FAILURE() << "no rising bifurcation between " << from << " and " << to;
    return 0.0;
  };
  const double up = rising(1.0, 1.26), down = rising(1.26, 1.2);
  EXPECT_NEAR(up, down, 1e-9);  // one sticking phase below it, two above: two different branches
  // Simulated from the scene's state just below and just above: one sticking phase, then two.
  for (double df : {-1e-7, 1e-7}) {
    const Outcome o = Simulate(at(up + df));
    ASSERT_EQ(o.result.status, RunStatus::kOk) << o.result.message;
    const Attractor& a = o.attractor;
    EXPECT_EQ(a.kind, "sticking-periodic");
    EXPECT_EQ(a.stick_phases.size(), df < 0 ? 1u : 2u) << "f = rising " << df;
  }
}

TEST(Continuation, NeimarkSackerPointIsBracketedByDirectSolves) {
  // 3-DOF chain, r = 0.5, ω = 2: along the one-impact period-1 family a complex pair leaves the
  // unit circle between f = 1.9 and 2.0.
  const std::string path = std::string(VIBRO_SCENES_DIR) + "/chain3.toml";
  const auto at = [&](double f) {
    return LoadScene(path, {"run.samples_per_period=0", "stop.restitution=0.5",
                            "excitation.frequency=2.0", fmt::format("excitation.amplitude={:.17g}", f)})
        .scene;
  };
  ContinuationRequest req;
  req.scene_at = at;
  req.from = 2.0;
  req.to = 1.8;
  req.orbit.kind = OrbitKind::kImpact;
  req.orbit.period = 1;
  const Branch b = Continue(req);
  ASSERT_EQ(b.status, "ok") << b.end;
  const Bifurcation* ns = nullptr;
  for (const auto& x : b.bifurcations)
    if (x.kind == "neimark-sacker") ns = &x;
  ASSERT_NE(ns, nullptr);
  // The branch's own points on either side of the located value straddle |μ| = 1 ...
  const auto pair = [](const BranchPoint& pt) {
    double m = 0;
    for (const auto& mu : pt.multipliers)
      if (std::abs(mu.imag()) > 1e-9) m = std::max(m, std::abs(mu));
    return m;
  };
  const BranchPoint* before = nullptr;
  const BranchPoint* after = nullptr;
  for (const auto& pt : b.points) {
    if (pt.value > ns->value && (!before || pt.value < before->value)) before = &pt;
    if (pt.value < ns->value && (!after || pt.value > after->value)) after = &pt;
  }
  ASSERT_NE(before, nullptr);
  ASSERT_NE(after, nullptr);
  EXPECT_LT((pair(*before) - 1) * (pair(*after) - 1), 0.0);
  // ... and so do direct solves just beside it, started from the impact of the nearest branch
  // point (other one-impact orbits coexist: the scene's own transient lands on one of them).
  // A short transient keeps Newton on the family: after 200 periods at |μ| ≈ 1 ± 1e-3 the start
  // drifts onto a coexisting orbit (pair 0.98), which one depending on the rounding of the engine.
  int checked = 0;
  double product = 1;
  for (const BranchPoint* side : {before, after}) {
    const double df = side == before ? 0.01 : -0.01;
    const Scene s = at(ns->value + df);
    const System sys(s);
    OrbitRequest r;
    r.kind = OrbitKind::kImpact;
    r.period = 1;
    ASSERT_EQ(side->summary.impact_phases.size(), 1u);
    r.guess_phase = side->summary.impact_phases[0];
    r.guess_velocity = -0.5 * side->summary.impact_velocities[0];
    r.transient_periods = 3;
    const OrbitResult o = FindOrbit(sys, s, r);
    if (o.status != "converged") continue;
    double m = 0;
    for (const auto& mu : o.multipliers)
      if (std::abs(mu.imag()) > 1e-9) m = std::max(m, std::abs(mu));
    // The family's pair, not a coexisting orbit's: 0.01 from the crossing, |μ| is within 1e-2 of 1.
    EXPECT_NEAR(m, 1.0, 1e-2);
    product *= (m - 1);
    ++checked;
  }
  EXPECT_EQ(checked, 2);
  EXPECT_LT(product, 0.0);
  // The located value sits where the complex pair has modulus 1 (to the accuracy of the bisection).
  const Branch close = [&] {
    ContinuationRequest c = req;
    c.to = ns->value;
    return Continue(c);
  }();
  ASSERT_FALSE(close.points.empty());
  EXPECT_NEAR(pair(close.points.back()), 1.0, 1e-3);
}

}  // namespace
}  // namespace vibro::test

namespace vibro::test {
namespace {

// SP of the 1-DOF, r = 0 period-q sticking orbit with one flight (docs/model.md §6.2), long double.
LD ClosedFormSp(LD w, LD f) {
  const LD t1 = ReleaseTime(w, f);
  const Flight1 fl{w, f, t1, 1, 0};
  const LD t0 = fl.Landing(1);  // skips the release: x − x0 ~ s³ there
  const LD theta = w * (t0 - t1) / (2 * M_PIl);
  return 1 - theta / std::ceil(theta);
}

TEST(Partition, OneDofPeriodTwoColumnsEndAtTheClosedFormBoundariesAndCrossLevelsWhereSpSays) {
  // ω = 5 and 10, q = 2: the one-flight sticking orbits live on (f_sticking, f_free-flight)
  // (docs/model.md §6.3, eqs. (36) and (38)); the partition's columns must end there and cross the
  // levels where the closed form's SP equals them.
  PartitionRequest req;
  req.scene_at = [](double w, double f) { return OneDof(0.0, w, f, 1.0, 50); };
  req.values1 = {5.0, 10.0};
  req.levels = {0.05, 0.1};
  req.orbit.period = 2;
  req.lo2 = 1.5;
  req.hi2 = 20.0;
  req.threads = 2;
  for (const auto& col : [&] {
         std::vector<PartitionColumn> cols;
         for (double w : req.values1) {
           PartitionRequest one = req;
           one.values1 = {w};
           // Start inside the band: between f_st and f_ff.
           one.start2 = w == 5.0 ? 10.0 : 6.0;
           const auto c = Partition(one);
           cols.insert(cols.end(), c.begin(), c.end());
         }
         return cols;
       }()) {
    const double w = col.value1;
    SCOPED_TRACE(w);
    ASSERT_EQ(col.status, "ok");
    const double f_ff = std::sqrt(1.0 + w * w * std::pow(std::tan(2 * M_PI / w), 2));
    long double lo = 1.0001L, hi = f_ff;  // (36): √(f²−1)/ω − tan(((2q−1)π/2 − asin(1/f))/ω) = 0
    const auto g = [w](long double f) {
      return std::sqrt(f * f - 1) / w - std::tan((1.5L * M_PIl - std::asin(1 / f)) / w);
    };
    for (int i = 0; i < 200; ++i) {
      const long double mid = 0.5L * (lo + hi);
      ((g(mid) > 0) == (g(lo) > 0) ? lo : hi) = mid;
    }
    const double f_st = static_cast<double>(lo);
    const auto find = [&](const std::string& kind, double near) {
      const Bifurcation* best = nullptr;
      for (const auto& b : col.bifurcations)
        if (b.kind == kind && (!best || std::abs(b.value - near) < std::abs(best->value - near))) best = &b;
      return best;
    };
    const auto* top = find("sticking-lost", f_ff);
    const auto* bottom = find("sticking-entry", f_st);
    ASSERT_NE(top, nullptr);
    ASSERT_NE(bottom, nullptr);
    EXPECT_NEAR(top->value, f_ff, 1e-10);
    EXPECT_NEAR(bottom->value, f_st, 1e-9);  // SP ~ |f − f_st|^(1/3) there (docs/model.md §6.3)
    // Crossings on the one-flight part (f_st, f_ff); below f_st the column goes on along orbits
    // with two flights per period (landing with R < 0 first), where the closed form does not apply.
    int checked = 0;
    for (const auto& x : col.crossings) {
      if (x.value <= f_st || x.value >= f_ff) continue;
      EXPECT_NEAR(static_cast<double>(ClosedFormSp(w, x.value)), x.level, 1e-9) << "f = " << x.value;
      ++checked;
    }
    EXPECT_EQ(checked, 2);
  }
}


// The sticking fraction and the largest |μ| of the stable period-1 orbit at the scene's λ, both by
// direct simulation from the branch point `near`: 300 periods to settle on the orbit, then the
// monodromy matrix by central differences of one-period runs from the settled section state
// (±1e-6 in each coordinate), independent of the Poincaré solver's analytic Jacobian.
struct Measured {
  double sp, mu;
};
Measured MeasureBySimulation(Scene sc, const BranchPoint& near) {
  sc.initial_time = near.section_time;
  sc.run.periods = 300;
  const InitialOverride from{near.section_time, near.X, near.V};
  const Outcome settle = Simulate(sc, &from);
  EXPECT_EQ(settle.result.status, RunStatus::kOk) << settle.result.message;
  EXPECT_EQ(settle.attractor.kind, "sticking-periodic");
  EXPECT_EQ(settle.attractor.period.value_or(0), 1);
  const auto& last = settle.log.sections.back();
  const auto n = last.X.size();
  Eigen::VectorXd z(2 * n);
  z << last.X, last.V;
  sc.initial_time = last.t;
  sc.run.periods = 1;
  const auto one_period = [&](const Eigen::VectorXd& z0) {
    const InitialOverride s{last.t, z0.head(n), z0.tail(n)};
    const Outcome o = Simulate(sc, &s);
    EXPECT_EQ(o.result.status, RunStatus::kOk);
    Eigen::VectorXd out(2 * n);
    out << o.log.sections.back().X, o.log.sections.back().V;
    return out;
  };
  Eigen::MatrixXd DF(2 * n, 2 * n);
  const double eps = 1e-6;
  for (Eigen::Index j = 0; j < 2 * n; ++j) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(2 * n);
    e[j] = eps;
    DF.col(j) = (one_period(z + e) - one_period(z - e)) / (2 * eps);
  }
  return {settle.attractor.sticking_fraction.value_or(-1), DF.eigenvalues().cwiseAbs().maxCoeff()};
}

TEST(Continuation, RegroupedChatteringIsARelabelNotABifurcationAndTheOrbitIsSmoothThere) {
  // Issue 24: the damped 3-DOF clearance chain, continued in ω at f = 0.8. Four times the second
  // impact of the chattering sequence becomes faster than its first (CR ↔ CRI): the same events,
  // grouped differently. No non-smooth bifurcation may be reported there, and direct simulation
  // shows the sticking fraction and the largest |μ| smooth across each point.
  const std::string path = std::string(VIBRO_TEST_SCENES_DIR) + "/damped3_clearance.toml";
  const auto at = [&](double w) {
    return LoadScene(path, {"run.samples_per_period=0", "excitation.amplitude=0.8",
                            fmt::format("excitation.frequency={:.17g}", w)})
        .scene;
  };
  ContinuationRequest req;
  req.scene_at = at;
  req.from = 0.3;
  req.to = 0.6;
  const Branch b = Continue(req);
  ASSERT_EQ(b.status, "ok");
  EXPECT_EQ(b.end, "sticking-lost");
  for (const auto& x : b.bifurcations) {
    EXPECT_NE(x.kind, "non-smooth") << x.value << ": " << x.detail;
    EXPECT_TRUE(x.kind == "flip" || x.kind == "sticking-lost") << x.kind << " at " << x.value;
  }
  const double expected[] = {0.30357, 0.32693, 0.39129, 0.42794};
  ASSERT_EQ(b.relabels.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    const Relabel& r = b.relabels[i];
    EXPECT_NEAR(r.value, expected[i], 1e-5);
    EXPECT_EQ(r.from, i % 2 == 0 ? "CR" : "CRI");
    EXPECT_EQ(r.to, i % 2 == 0 ? "CRI" : "CR");
    // Smooth across the point: the slopes of SP and of the largest |μ| on each side meet without a jump,
    // where a non-smooth point would make them jump by O(1); both measured by direct simulation.
    const auto near = std::min_element(b.points.begin(), b.points.end(), [&](const auto& p, const auto& q) {
      return std::abs(p.value - r.value) < std::abs(q.value - r.value);
    });
    const double h = 1e-5;
    Measured m[6];
    for (int j = 0; j < 6; ++j) m[j] = MeasureBySimulation(at(r.value + (j < 3 ? j - 3 : j - 2) * h), *near);
    for (double Measured::*q : {&Measured::sp, &Measured::mu}) {
      // Slopes on [−3h, −2h], [−2h, −h] and [h, 2h], [2h, 3h]: the left ones, extended linearly,
      // predict the right ones up to O(h²) (the third derivative); a kink at the point adds its
      // jump of slope.
      const double l1 = (m[1].*q - m[0].*q) / h, l2 = (m[2].*q - m[1].*q) / h;
      const double r1 = (m[4].*q - m[3].*q) / h, r2 = (m[5].*q - m[4].*q) / h;
      const double jump = r1 - (l2 + 3 * (l2 - l1));
      SCOPED_TRACE(fmt::format("relabel at {}: slopes {} {} | {} {}", r.value, l1, l2, r1, r2));
      EXPECT_LT(std::abs(jump), 0.05 * std::max({std::abs(l2), std::abs(r1), 1e-3}));
    }
    // The measured largest |μ| is the branch's at its nearest point.
    double lead = 0;
    for (const auto& mu : near->multipliers) lead = std::max(lead, std::abs(mu));
    EXPECT_NEAR(MeasureBySimulation(at(near->value), *near).mu, lead, 1e-6);
  }
}

// The tube (data/scenes/tube_loose_support.toml) continued in ω from 0.9 to 1.5 as the library's
// caller BM_ProveTubeGrazing does (run.samples_per_period = 0, ω set in code, so no validation of
// the trial values): before the fix a corrector iterate at ω = −0.863 reached the simulator, whose
// clock then looped without end (the merge ea4a9ea was reverted for it). The continuation must
// return, its branch must meet the grazing near 1.3646 (docs/orbits.md, "Through a grazing") and
// name the branch point just before it. Watched: a stop is requested after 120 s (an interrupted
// branch fails the test) and a continuation that still has not returned 30 s later ends the
// binary (exit 1): the old loop polled nothing.
TEST(Continuation, TubeFrom09To15EndsWithEveryMapEvaluationBounded) {
  const std::string file = std::string(VIBRO_SCENES_DIR) + "/tube_loose_support.toml";
  ContinuationRequest req;
  req.scene_at = [&](double w) {
    auto scene = LoadScene(file, {"run.samples_per_period=0"}).scene;
    scene.frequency = w;
    return scene;
  };
  req.orbit.kind = OrbitKind::kImpact;
  req.from = 0.9;
  req.to = 1.5;
  std::atomic<bool> stop{false};
  req.stop_requested = &stop;
  std::packaged_task<Branch()> task([&] { return Continue(req); });
  auto result = task.get_future();
  std::thread worker(std::move(task));
  if (result.wait_for(std::chrono::seconds(120)) != std::future_status::ready) {
    stop = true;
    if (result.wait_for(std::chrono::seconds(30)) != std::future_status::ready) {
      std::fprintf(stderr, "FAILED: Continue did not return 30 s after a stop request (an endless map evaluation)\n");
      std::fflush(stderr);
      std::_Exit(1);
    }
  }
  worker.join();
  const Branch b = result.get();
  ASSERT_EQ(b.status, "ok") << b.end;
  ASSERT_GE(b.points.size(), 2u);
  const Bifurcation* graze = nullptr;
  for (const auto& x : b.bifurcations)
    if (x.kind == "grazing" && (!graze || std::abs(x.value - 1.3646) < std::abs(graze->value - 1.3646))) graze = &x;
  ASSERT_NE(graze, nullptr);
  EXPECT_NEAR(graze->value, 1.3646, 1e-3);
  ASSERT_GE(graze->point, 0);
  ASSERT_LT(graze->point, static_cast<long long>(b.points.size()));
  // The point before the grazing lies on the side the branch came from (ω below it) and near it.
  const BranchPoint& before = b.points[static_cast<size_t>(graze->point)];
  EXPECT_LT(before.value, graze->value);
  EXPECT_GT(before.value, graze->value - 0.1);
}

}  // namespace
}  // namespace vibro::test
