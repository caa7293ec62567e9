// Continuation: the end of the sticking branch against f_free-flight of MODEL §6.3, branch points
// against direct orbit solves, and a Neimark–Sacker point bracketed by direct solves.
#include <cmath>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/continuation.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

TEST(Continuation, StickingBranchInAmplitudeEndsAtTheFreeFlightLimit) {
  // 1-DOF, r = 0: the period-1 sticking branch in f ends (sticking-lost) at
  // f_ff(ω, 1) = √(1 + ω² tan²(π/ω)) (MODEL §6.3, valid where tan(π/ω) > 0).
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
  ContinuationRequest req;
  req.scene_at = at;
  req.from = 1.1;
  req.to = 0.3;
  req.max_points = 20;
  req.orbit.kind = OrbitKind::kImpact;
  req.orbit.period = 1;
  const Branch b = Continue(req);
  ASSERT_EQ(b.status, "ok") << b.end;
  const Bifurcation* fold = nullptr;
  for (const auto& x : b.bifurcations)
    if (x.kind == "fold") fold = &x;
  ASSERT_NE(fold, nullptr);
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
    const System sys(s);
    AttractorRecorder rec(sys, s);
    const InitialOverride start{above.section_time, above.X, above.V};
    SimulationOptions opt;
    opt.initial = &start;
    opt.observers = {&rec};
    vibro::Simulate(sys, s, opt);
    const Attractor a = rec.Classify();
    const bool one_impact = a.kind == "impact-periodic" && a.period == 1 && a.impacts_per_period == 1;
    EXPECT_EQ(one_impact, df > 0) << "f = fold " << df << ": " << a.kind;
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
  // ... and so do direct solves just beside it, started from the scene's transient (when that
  // transient lands on this family; a coexisting sticking orbit may attract it instead).
  int checked = 0;
  double product = 1;
  for (double df : {0.01, -0.01}) {
    const Scene s = at(ns->value + df);
    const System sys(s);
    OrbitRequest r;
    r.kind = OrbitKind::kImpact;
    r.period = 1;
    const OrbitResult o = FindOrbit(sys, s, r);
    if (o.status != "converged") continue;
    double m = 0;
    for (const auto& mu : o.multipliers)
      if (std::abs(mu.imag()) > 1e-9) m = std::max(m, std::abs(mu));
    product *= (m - 1);
    ++checked;
  }
  if (checked == 2) {
    EXPECT_LT(product, 0.0);
  }
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
