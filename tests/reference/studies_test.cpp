// Studies: the coexisting attractors of Fig. 5, labels that re-simulate to their attractor, and
// results independent of the thread count.
#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/continuation.hpp"
#include "vibro/studies.hpp"

namespace vibro::test {
namespace {

Scene Fig5() {
  Scene s = OneDof(0.75, 10.0, 1.1, 1.0, 100);
  return s;
}

TEST(Studies, Fig5BothAttractorsAreFoundWithTheirBasins) {
  const Scene s = Fig5();
  const System sys(s);
  const Coordinate x{"x_B", 1.0, 3.0}, v{"v_B", -2.0, 2.0};
  const auto study = RunStudy(sys, s, x, v, GridPoints(x, v, 24, 24), {});
  bool sticking = false, impact = false;
  for (const auto& a : study.attractors) {
    if (a.attractor.kind == "sticking-periodic" && a.attractor.period == 1) {
      sticking = true;
      EXPECT_NEAR(*a.attractor.sticking_fraction, 0.530620922, 1e-8);
      EXPECT_GT(a.basin_fraction, 0.05);
    }
    if (a.attractor.kind == "impact-periodic" && a.attractor.period == 1 &&
        a.attractor.impacts_per_period == 1) {
      impact = true;
      EXPECT_GT(a.basin_fraction, 0.05);
    }
    EXPECT_GT(a.basin_fraction_error, 0.0);
    EXPECT_LT(a.basin_fraction_error, 0.05);
  }
  EXPECT_TRUE(sticking);
  EXPECT_TRUE(impact);
  // Every labelled cell, simulated again alone, lands on its attractor (checked on a stride).
  const auto pts = GridPoints(x, v, 24, 24);
  for (size_t i = 0; i < pts.size(); i += 37) {
    if (study.labels[i] < 0) continue;
    const std::vector<std::pair<double, double>> one{pts[i]};
    const auto again = RunStudy(sys, s, x, v, one, {});
    ASSERT_EQ(again.attractors.size(), 1u);
    const auto& want = study.attractors[static_cast<size_t>(study.labels[i])].attractor;
    EXPECT_EQ(again.attractors[0].attractor.kind, want.kind);
    EXPECT_EQ(again.attractors[0].attractor.period, want.period);
  }
}

TEST(Studies, SameLabelsForOneAndTwoThreads) {
  const Scene s = Fig5();
  const System sys(s);
  const Coordinate x{"x_B", 1.0, 3.0}, v{"v_B", -2.0, 2.0};
  const auto pts = GridPoints(x, v, 16, 16);
  StudyOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const auto a = RunStudy(sys, s, x, v, pts, one), b = RunStudy(sys, s, x, v, pts, two);
  EXPECT_EQ(a.labels, b.labels);
  ASSERT_EQ(a.attractors.size(), b.attractors.size());
  for (size_t k = 0; k < a.attractors.size(); ++k) {
    EXPECT_EQ(a.attractors[k].cells, b.attractors[k].cells);
    EXPECT_EQ(a.attractors[k].example, b.attractors[k].example);
  }
}

TEST(Studies, SweepAcrossTheFreeFlightLimitLosesStickingWhereContinuationSays) {
  // 1-DOF, r = 0, ω = 2.8: sticking ends at f_ff (MODEL §6.3); the brute-force sweep, up and down,
  // switches between the two steps that bracket the continuation's sticking-lost point.
  const auto at = [](double f) { return OneDof(0.0, 2.8, f, 1.0, 30); };
  SweepRequest req;
  req.scene_at = at;
  req.from = 5.85;
  req.to = 5.95;
  req.steps = 10;
  const auto sweep = Sweep(req);
  ASSERT_EQ(sweep.size(), 21u);
  ContinuationRequest cont;
  cont.scene_at = at;
  cont.from = 5.5;
  cont.to = 6.5;
  const Branch b = Continue(cont);
  ASSERT_EQ(b.end, "sticking-lost");
  const double lost = b.bifurcations.back().value;
  for (const auto& p : sweep) {
    const bool sticks = p.attractor.kind == "sticking-periodic";
    EXPECT_EQ(sticks, p.value < lost) << p.value << (p.upward ? " up" : " down");
    EXPECT_EQ(p.x_B.size(), 16u);
  }
}

}  // namespace
}  // namespace vibro::test
