// Studies: the coexisting attractors of Fig. 5, labels that re-simulate to their attractor, and
// results independent of the thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "support.hpp"
#include "vibro/continuation.hpp"
#include "vibro/simulator.hpp"
#include "vibro/studies.hpp"

namespace vibro::test {
namespace {

Scene Fig5() {
  Scene s = OneDof(0.75, 10.0, 1.1, 1.0, 100);
  return s;
}

// Phases (mod 2π) and sticking fractions of two classifications agree to `tol`.
void ExpectSameAttractor(const Attractor& got, const Attractor& want, double tol, const std::string& where) {
  EXPECT_EQ(got.kind, want.kind) << where;
  EXPECT_EQ(got.period, want.period) << where;
  EXPECT_EQ(got.impacts_per_period, want.impacts_per_period) << where;
  if (got.sticking_fraction && want.sticking_fraction) {
    EXPECT_NEAR(*got.sticking_fraction, *want.sticking_fraction, tol) << where;
  }
  const auto folded = [](std::vector<double> v) {
    for (double& x : v) x = std::fmod(std::fmod(x, 2 * M_PI) + 2 * M_PI, 2 * M_PI);
    std::sort(v.begin(), v.end());
    return v;
  };
  std::vector<double> gs, ws;
  for (const auto& p : got.stick_phases) gs.push_back(p.first);
  for (const auto& p : want.stick_phases) ws.push_back(p.first);
  for (const auto& [g, w] : {std::pair{folded(gs), folded(ws)},
                             std::pair{folded(got.impact_phases), folded(want.impact_phases)}}) {
    ASSERT_EQ(g.size(), w.size()) << where;
    for (size_t i = 0; i < g.size(); ++i) {
      const double d = std::abs(g[i] - w[i]);
      EXPECT_LT(std::min(d, 2 * M_PI - d), tol) << where;
    }
  }
}

// The attractor reached from a cell's initial state by a plain simulation of `periods` periods
// (no early stop, no known orbits): the independent truth for a study's labels.
Attractor FullRun(const Scene& scene, double x_B, double v_B, long long periods) {
  Scene s = scene;
  s.run.periods = periods;
  const System sys(s);
  InitialOverride init{s.initial_time, sys.static_shape() * x_B, sys.contact() * (v_B / sys.s_B())};
  AttractorRecorder rec(sys, s);
  SimulationOptions opt;
  opt.initial = &init;
  opt.observers = {&rec};
  EXPECT_EQ(Simulate(sys, s, opt).status, RunStatus::kOk);
  return rec.Classify();
}

TEST(Studies, Fig5BothAttractorsAreFoundWithTheirBasins) {
  const Scene s = Fig5();
  const System sys(s);
  const Coordinate x{"x_B", 1.0, 3.0}, v{"v_B", -2.0, 2.0};
  const auto pts = GridPoints(x, v, 24, 24);
  const auto study = RunStudy(sys, s, x, v, pts, {});
  bool sticking = false, impact = false;
  for (const auto& a : study.attractors) {
    if (a.attractor.kind == "sticking-periodic" && a.attractor.period == 1) {
      sticking = true;
      EXPECT_NEAR(*a.attractor.sticking_fraction, 0.530620922, 1e-8);
      EXPECT_GT(a.basin_fraction, 0.05);
      // The Poincaré solver: a 1-DOF sticking orbit is superstable (no multipliers).
      EXPECT_EQ(a.orbit.status, "converged");
      EXPECT_TRUE(a.orbit.multipliers.empty());
      EXPECT_EQ(a.orbit.stable, true);
    }
    if (a.attractor.kind == "impact-periodic" && a.attractor.period == 1 &&
        a.attractor.impacts_per_period == 1) {
      impact = true;
      EXPECT_GT(a.basin_fraction, 0.05);
      // The one-impact 1-DOF map has det = r² (docs/model.md §5.6): both multipliers of modulus r.
      EXPECT_EQ(a.orbit.status, "converged");
      ASSERT_EQ(a.orbit.multipliers.size(), 2u);
      for (const auto& m : a.orbit.multipliers) EXPECT_NEAR(std::abs(m), 0.75, 1e-9);
      EXPECT_EQ(a.orbit.stable, true);
    }
    EXPECT_GT(a.basin_fraction_error, 0.0);
    EXPECT_LT(a.basin_fraction_error, 0.05);
  }
  EXPECT_TRUE(sticking);
  EXPECT_TRUE(impact);
  double total = study.unresolved_fraction + study.inadmissible_fraction;
  for (const auto& a : study.attractors) total += a.basin_fraction;
  EXPECT_NEAR(total, 1.0, 1e-12);
  // Every label, checked on its first cells and on a stride: the cell simulated alone for 400
  // periods without any early stop lands on the attractor of its label.
  std::vector<int> seen(study.attractors.size(), 0);
  for (size_t i = 0; i < pts.size(); ++i) {
    const int l = study.labels[i];
    if (l < 0 || (seen[static_cast<size_t>(l)]++ >= 3 && i % 29 != 0)) continue;
    ExpectSameAttractor(FullRun(s, pts[i].first, pts[i].second, 400),
                        study.attractors[static_cast<size_t>(l)].attractor, 1e-6,
                        "cell " + std::to_string(i));
  }
}

TEST(Studies, EarlyStopsChangeNoLabelAndSaveMostPeriods) {
  // The same grid with every cell run for all its periods (no early stop, no known orbits): each
  // cell that this resolves has the same attractor in the fast study (to 1e-5 in phase: a cell
  // just resolved after 100 periods, within run.period_tolerance = 1e-7 of periodic, is itself
  // that far from its orbit). On a stride, and for cells still in their transient after 100
  // periods, the fast study's attractor is that of a 400-period run to 1e-6.
  const Scene s = Fig5();
  const System sys(s);
  const Coordinate x{"x_B", 1.0, 3.0}, v{"v_B", -2.0, 2.0};
  const auto pts = GridPoints(x, v, 20, 20);
  StudyOptions full_opt;
  full_opt.settle_remainder = 0;
  full_opt.solve_orbits = false;
  std::vector<CellResult> fast(pts.size()), full(pts.size());
  std::vector<size_t> all(pts.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  StudyOptions fast_opt;
  fast_opt.known = KnownOrbits(sys, s, x, v, fast_opt);
  ASSERT_GE(fast_opt.known.size(), 2u);
  RunCells(sys, s, x, v, pts, all, fast, fast_opt);
  RunCells(sys, s, x, v, pts, all, full, full_opt);
  long long periods = 0, resolved_late = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    ASSERT_EQ(fast[i].state, CellResult::State::kClassified);
    ASSERT_EQ(full[i].state, CellResult::State::kClassified);
    EXPECT_EQ(full[i].periods, 100);
    periods += fast[i].periods;
    if (full[i].attractor.kind != "not-periodic") {
      ExpectSameAttractor(fast[i].attractor, full[i].attractor, 1e-5, "cell " + std::to_string(i));
      if (i % 13 == 0)
        ExpectSameAttractor(FullRun(s, pts[i].first, pts[i].second, 400), fast[i].attractor, 1e-6,
                            "cell " + std::to_string(i));
    } else if (fast[i].attractor.kind != "not-periodic" && resolved_late++ % 5 == 0) {
      ExpectSameAttractor(FullRun(s, pts[i].first, pts[i].second, 400), fast[i].attractor, 1e-6,
                          "late cell " + std::to_string(i));
    }
  }
  // Most of the work is saved (a count of periods, not a time).
  EXPECT_LT(static_cast<double>(periods), 0.6 * 100.0 * static_cast<double>(pts.size()));
}

TEST(Studies, ClassesWithTheSameSolvedOrbitAreMerged) {
  // Run for all 100 periods, slow transients towards the period-2 impact orbit are classified
  // with phases that still differ by more than 1e-6 (several classes); the Poincaré solver
  // finds one orbit for them, and they are merged into one label.
  const Scene s = Fig5();
  const System sys(s);
  const Coordinate x{"x_B", 1.0, 3.0}, v{"v_B", -2.0, 2.0};
  const auto pts = GridPoints(x, v, 32, 32);
  StudyOptions opt;
  opt.settle_remainder = 0;
  opt.solve_orbits = false;
  std::vector<CellResult> cells(pts.size());
  std::vector<size_t> all(pts.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  RunCells(sys, s, x, v, pts, all, cells, opt);
  const StudyResult raw = LabelCells(sys, s, pts, cells, opt);
  opt.solve_orbits = true;
  const StudyResult merged = LabelCells(sys, s, pts, cells, opt);
  ASSERT_GT(raw.attractors.size(), merged.attractors.size());
  int classes = 0;
  for (const auto& a : merged.attractors) classes += a.orbit.merged;
  EXPECT_EQ(classes, static_cast<int>(raw.attractors.size()));
  // A merge only joins cells: two cells with one raw label keep one merged label, and cells that
  // share a merged label have raw attractors whose solved orbits agree (checked via the label's
  // kind, period and number of impacts).
  for (size_t i = 0; i < pts.size(); ++i) {
    ASSERT_EQ(raw.labels[i] < 0, merged.labels[i] < 0);
    if (raw.labels[i] < 0) continue;
    const auto& r = raw.attractors[static_cast<size_t>(raw.labels[i])].attractor;
    const auto& m = merged.attractors[static_cast<size_t>(merged.labels[i])].attractor;
    EXPECT_EQ(r.kind, m.kind);
    EXPECT_EQ(r.impacts_per_period, m.impacts_per_period);
  }
  for (size_t i = 0; i + 1 < pts.size(); ++i)
    if (raw.labels[i] >= 0 && raw.labels[i] == raw.labels[i + 1]) {
      EXPECT_EQ(merged.labels[i], merged.labels[i + 1]);
    }
  // The period-2 orbit: stable, and (1 DOF, undamped: the flows preserve area, each impact
  // scales it by r, docs/model.md §5.6) det DF = μ1 μ2 = r^(2k) for k impacts per orbit period.
  bool p2 = false;
  for (const auto& a : merged.attractors) {
    if (a.attractor.kind != "impact-periodic" || a.attractor.period != 2) continue;
    p2 = true;
    EXPECT_GT(a.orbit.merged, 1);
    EXPECT_EQ(a.orbit.stable, true);
    ASSERT_EQ(a.orbit.multipliers.size(), 2u);
    EXPECT_NEAR(std::abs(a.orbit.multipliers[0] * a.orbit.multipliers[1]),
                std::pow(0.75, 2.0 * static_cast<double>(*a.attractor.impacts_per_period)), 1e-9);
  }
  EXPECT_TRUE(p2);
}

TEST(Studies, CellResultsPackBitExactly) {
  CellResult c;
  c.state = CellResult::State::kClassified;
  c.attractor.kind = "impact-periodic";
  c.attractor.period = 2;
  c.attractor.impacts_per_period = 3;
  c.attractor.sticking_fraction = 0.1 + 0.2;
  c.attractor.stick_phases = {{1.0 / 3, 7.0 / 3}};
  c.attractor.impact_phases = {0.1, 0.7, 1.9};
  c.attractor.impact_velocities = {-1e-300, -2.0, -M_PI};
  c.periods = 57;
  c.stop = 2;
  c.z = Eigen::VectorXd::LinSpaced(4, -1.0 / 7, 5.0 / 7);
  CellResult none;  // a pending cell: no period, no impacts, no sticking fraction
  std::vector<double> buf;
  PackCell(c, buf);
  PackCell(none, buf);
  const double* p = buf.data();
  const CellResult a = UnpackCell(p), b = UnpackCell(p);
  EXPECT_EQ(p, buf.data() + buf.size());
  EXPECT_EQ(a.attractor.kind, c.attractor.kind);
  EXPECT_EQ(a.attractor.period, c.attractor.period);
  EXPECT_EQ(a.attractor.impacts_per_period, c.attractor.impacts_per_period);
  EXPECT_EQ(a.attractor.sticking_fraction, c.attractor.sticking_fraction);
  EXPECT_EQ(a.attractor.stick_phases, c.attractor.stick_phases);
  EXPECT_EQ(a.attractor.impact_phases, c.attractor.impact_phases);
  EXPECT_EQ(a.attractor.impact_velocities, c.attractor.impact_velocities);
  EXPECT_EQ(a.periods, 57);
  EXPECT_EQ(a.stop, 2);
  EXPECT_EQ(a.z, c.z);
  EXPECT_EQ(b.state, CellResult::State::kPending);
  EXPECT_FALSE(b.attractor.period || b.attractor.impacts_per_period || b.attractor.sticking_fraction);
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
  // 1-DOF, r = 0, ω = 2.8: sticking ends at f_ff (docs/model.md §6.3); the brute-force sweep, up and down,
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
