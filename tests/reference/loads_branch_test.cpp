// Contact loads stored along a continuation branch and over a partition (docs/loads.md, "Along
// branches and over partitions") against independent truths:
// - every point's mean contact force holds the orbit's mean deflection, the momentum balance over
//   one orbit period computed from positions (a separate dense run from the point's stored state,
//   ∫X dt by the trapezoid rule), not from impulses:
//     ω_i² ∫X_i dt + [Ẋ_i] + 2ζ_iω_i [X_i] = Σ_j T_j,i F̄_j qT   (forcing: ∫ sin ωt = 0 over qT);
// - a point's loads are those of `vibro orbit` at its parameter value: the orbit found afresh by
//   the Poincaré solver from the scene's transient, and its OrbitLoads;
// - a partition cell's loads are OrbitLoads of the orbit found afresh at (value1, value2).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/continuation.hpp"
#include "vibro/loads.hpp"
#include "vibro/orbit_from_state.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

std::string ScenePath(const std::string& name) { return std::string(VIBRO_SCENES_DIR) + "/" + name; }

Scene At(const std::string& name, std::vector<std::string> sets, const std::string& key, double v) {
  sets.push_back(fmt::format("{}={:.17g}", key, v));
  return LoadScene(ScenePath(name), sets).scene;
}

// The momentum balance of the orbit through (t0, X, V) of period q forcing periods, with the mean
// contact forces `loads`: a run of 2q periods sampled `spp` times per period, integrated over the
// q periods from its first sample. Returns the worst residual relative to the terms' sizes.
double MomentumResidual(const Scene& scene, double t0, const Eigen::VectorXd& X, const Eigen::VectorXd& V, int q,
                        const std::vector<ContactLoads>& loads, int spp) {
  Scene s = scene;
  s.run.periods = 2 * q;
  s.run.samples_per_period = spp;
  s.run.lyapunov = false;
  const System sys(s);
  Log log;
  SimulationOptions opt;
  opt.observers = {&log};
  const InitialOverride start{t0, X, V};
  opt.initial = &start;
  const RunResult r = Simulate(sys, s, opt);
  EXPECT_EQ(r.status, RunStatus::kOk) << r.message;
  const double Tq = q * sys.period(), h = sys.period() / spp;
  const auto& smp = log.samples;
  EXPECT_GT(smp.size(), static_cast<size_t>(q * spp));
  if (smp.size() <= static_cast<size_t>(q * spp)) return INFINITY;
  // Uniform samples: the window [t_a, t_a + qT] is q·spp steps.
  const size_t a = 0, b = static_cast<size_t>(q * spp);
  EXPECT_NEAR(smp[b].t - smp[a].t, Tq, 1e-9 * Tq);
  const int n = sys.dof();
  Eigen::VectorXd integral = 0.5 * h * (smp[a].X + smp[b].X);
  for (size_t k = a + 1; k < b; ++k) integral += h * smp[k].X;
  double worst = 0;
  for (int i = 0; i < n; ++i) {
    const double w = sys.omega()[i], z = sys.damping()[i];
    const double lhs = w * w * integral[i] + (smp[b].V[i] - smp[a].V[i]) + 2 * z * w * (smp[b].X[i] - smp[a].X[i]);
    double rhs = 0, scale = std::abs(w * w * integral[i]);
    for (size_t j = 0; j < sys.contacts().size(); ++j) {
      const double J = loads.at(j).mean_force * Tq;
      rhs += sys.contacts()[j].contact[i] * J;
      scale += std::abs(sys.contacts()[j].contact[i] * J);
    }
    worst = std::max(worst, std::abs(lhs - rhs) / scale);
  }
  return worst;
}

// Two loads equal to `rel` of their size (and `tiny` absolutely: a work rate that vanishes at the
// branch's sticking-entry end).
void ExpectSameLoads(const std::vector<ContactLoads>& got, const std::vector<ContactLoads>& want, double rel,
                     double tiny) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t j = 0; j < got.size(); ++j) {
    const auto& g = got[j];
    const auto& w = want[j];
    EXPECT_EQ(g.contact, w.contact);
    EXPECT_EQ(g.impacts_per_period, w.impacts_per_period);
    const double vals[][2] = {{g.impulse_per_period, w.impulse_per_period},
                              {g.reaction_integral_per_period, w.reaction_integral_per_period},
                              {g.mean_force, w.mean_force},
                              {g.dissipated_power, w.dissipated_power},
                              {g.work_rate, w.work_rate},
                              {g.contact_fraction, w.contact_fraction}};
    const char* names[] = {"impulse_per_period", "reaction_integral_per_period", "mean_force",
                           "dissipated_power", "work_rate", "contact_fraction"};
    for (int k = 0; k < 6; ++k)
      EXPECT_NEAR(vals[k][0], vals[k][1], rel * std::abs(vals[k][1]) + tiny) << names[k] << " of contact " << j;
  }
}

// `vibro orbit` at a parameter value: the Poincaré solver from the scene's transient, and the
// orbit's loads.
LoadsSummary OrbitLoadsAt(const Scene& scene) {
  const System sys(scene);
  OrbitRequest req;
  req.kind = OrbitKind::kAuto;
  const OrbitResult orbit = SolveOrbit(sys, scene, req);
  EXPECT_EQ(orbit.status, "converged") << orbit.message;
  return OrbitLoads(sys, scene, orbit);
}

struct Case {
  std::string scene;
  std::vector<std::string> sets;
  std::string key;
  double from, to;
  int max_points;
};

Branch BranchOf(const Case& c) {
  ContinuationRequest req;
  req.scene_at = [&c](double v) { return At(c.scene, c.sets, c.key, v); };
  req.from = c.from;
  req.to = c.to;
  req.max_points = c.max_points;
  req.orbit.kind = OrbitKind::kAuto;
  return Continue(req);
}

const Case kCases[] = {
    // Fig. 8 (r = 0.75, ω = 2.8): sticking orbits with a chattering sequence, from f → 1⁺ to f_max.
    {"fig08_preload.toml", {"run.samples_per_period=0"}, "excitation.amplitude", 1.001, 1.4, 80},
    // The 2-DOF chain (r = 0, ω = 0.4), two modes against one stop, short of its fold.
    {"chain2.toml", {"run.samples_per_period=0", "stop.restitution=0.0", "excitation.frequency=0.4"},
     "excitation.amplitude", 1.0, 1.2, 30},
    // The 3-DOF chain (r = 0) stuck with a moving held flow, continued in ω.
    {"chain3.toml", {"run.samples_per_period=0"}, "excitation.frequency", 0.8, 0.85, 12},
};

TEST(LoadsAlongBranch, EveryPointBalancesMomentumFromPositions) {
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.scene);
    const Branch b = BranchOf(c);
    ASSERT_EQ(b.status, "ok") << b.end;
    ASSERT_GE(b.points.size(), 5u) << b.end;
    double worst = 0;
    for (const auto& pt : b.points) {
      ASSERT_EQ(pt.loads.size(), 1u) << pt.loads_note;
      EXPECT_TRUE(pt.loads_note.empty()) << pt.loads_note;
      const Scene s = At(c.scene, c.sets, c.key, pt.value);
      const double res = MomentumResidual(s, pt.section_time, pt.X, pt.V, b.period, pt.loads, 4000);
      EXPECT_LT(res, 2e-6) << c.key << " = " << pt.value;
      worst = std::max(worst, res);
    }
    ::testing::Test::RecordProperty(c.scene + "_worst_relative_residual", fmt::format("{:.3e} over {} points", worst, b.points.size()));
  }
}

TEST(LoadsAlongBranch, PointEqualsOrbitAtItsValue) {
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.scene);
    const Branch b = BranchOf(c);
    ASSERT_EQ(b.status, "ok") << b.end;
    ASSERT_GE(b.points.size(), 5u);
    // Points well inside the branch (at its ends a transient settles slowly or elsewhere).
    for (size_t i = b.points.size() / 5; i < b.points.size() * 4 / 5; i += std::max<size_t>(1, b.points.size() / 5)) {
      const auto& pt = b.points[i];
      SCOPED_TRACE(fmt::format("{} = {:.17g}", c.key, pt.value));
      const LoadsSummary fresh = OrbitLoadsAt(At(c.scene, c.sets, c.key, pt.value));
      ExpectSameLoads(pt.loads, fresh.contacts, 1e-8, 1e-14);
    }
  }
}

TEST(LoadsOverPartition, CellEqualsOrbitThere) {
  // The Fig. 9 plane (ω, f) of the Fig. 8 scene, two columns.
  const std::vector<std::string> sets{"run.samples_per_period=0"};
  PartitionRequest req;
  req.scene_at = [&](double w, double f) {
    auto with = sets;
    with.push_back(fmt::format("excitation.frequency={:.17g}", w));
    with.push_back(fmt::format("excitation.amplitude={:.17g}", f));
    return LoadScene(ScenePath("fig08_preload.toml"), with).scene;
  };
  req.values1 = {2.8, 6.0};
  req.start2 = 1.02;
  req.lo2 = 1.0;
  req.hi2 = 1.4;
  req.levels = {0.5};
  req.threads = 1;
  const auto columns = Partition(req);
  ASSERT_EQ(columns.size(), 2u);
  for (const auto& col : columns) {
    SCOPED_TRACE(fmt::format("ω = {}", col.value1));
    ASSERT_EQ(col.status, "ok") << col.end_down << " / " << col.end_up;
    ASSERT_GE(col.points.size(), 10u);
    // The cells run through the column in increasing f (a sticking branch has no fold in f),
    // once each, from its lower end to its upper one.
    for (size_t i = 1; i < col.points.size(); ++i) EXPECT_GT(col.points[i].value2, col.points[i - 1].value2);
    EXPECT_LT(col.points.front().value2, req.start2);
    EXPECT_GT(col.points.back().value2, 1.25);
    for (size_t i = col.points.size() / 5; i < col.points.size() * 4 / 5; i += col.points.size() / 5) {
      const auto& cell = col.points[i];
      SCOPED_TRACE(fmt::format("f = {:.17g}", cell.value2));
      const Scene s = req.scene_at(col.value1, cell.value2);
      const LoadsSummary fresh = OrbitLoadsAt(s);
      ExpectSameLoads(cell.loads, fresh.contacts, 1e-8, 1e-14);
    }
  }
}

}  // namespace
}  // namespace vibro::test
