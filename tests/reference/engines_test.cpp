// The CVODE engine against the exact engine (the independent truth for CVODE), its order in rtol,
// near-grazing, no tunnelling through the stop during chattering, long runs, thread safety and
// every failure path.
#include <cmath>
#include <filesystem>
#include <thread>

#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/scene_file.hpp"

namespace vibro::test {
namespace {

Scene WithEngine(Scene s, Engine e, double rtol = 1e-10) {
  s.run.engine = e;
  s.run.rtol = rtol;
  s.run.atol = rtol * 1e-2;
  return s;
}

std::vector<std::string> ShippedScenes() {
  std::vector<std::string> out;
  for (const auto& entry : std::filesystem::directory_iterator(VIBRO_SCENES_DIR))
    if (entry.path().extension() == ".toml" && !entry.is_symlink()) out.push_back(entry.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

// Observed on the shipped scenes at rtol = 1e-10: stick phases and sticking fractions agree with
// the exact engine to ≈ 50 rtol^(2/3) (chattering scenes; r = 0 scenes agree to ≈ rtol).
constexpr double kPhaseTolerance = 1e-5;

TEST(Engines, CvodeAgreesWithExactOnEveryScene) {
  // The engines follow a different number of impacts in a chattering sequence (CVODE switches to
  // the accumulation prediction at √rtol of the first impact speed, docs/model.md §5.4), so the events
  // compared one to one are the first impact and the sticks, releases and accumulations.
  const auto milestones = [](const std::vector<Event>& events) {
    std::vector<Event> out;
    bool first_impact = true;
    for (const auto& e : events) {
      if (e.kind != EventKind::kImpact || first_impact) out.push_back(e);
      if (e.kind == EventKind::kImpact) first_impact = false;
    }
    return out;
  };
  for (const auto& path : ShippedScenes()) {
    SCOPED_TRACE(path);
    const Scene scene = LoadScene(path, {"run.samples_per_period=0"}).scene;
    // Several contacts: compared event by event, at rtol 1e-12, in ContactsCvode
    // (contacts_cvode_test.cpp).
    if (scene.contacts.size() > 1) continue;
    const Outcome exact = Simulate(WithEngine(scene, Engine::kExact));
    const Outcome cvode = Simulate(WithEngine(scene, Engine::kCvode));
    ASSERT_EQ(cvode.result.status, RunStatus::kOk) << cvode.result.message;
    const double T = 2 * M_PI / scene.frequency;
    auto a = milestones(exact.log.events), b = milestones(cvode.log.events);
    // A motion of impacts alone, without chattering (data/scenes/two_harmonics_chain2.toml): every
    // impact is compared.
    if (a.size() < 4 && exact.log.events.size() >= 4) {
      a = exact.log.events;
      b = cvode.log.events;
    }
    size_t n = std::min<size_t>({a.size(), b.size(), 40});
    // A motion that is not periodic (the undamped stiff chain) is sensitive to its initial
    // state: the engines are compared over its first forcing period only.
    if (exact.attractor.kind == "not-periodic")
      while (n > 0 && a[n - 1].t > T) --n;
    ASSERT_GT(n, 3u);
    for (size_t i = 0; i < n; ++i) {
      EXPECT_EQ(a[i].kind, b[i].kind) << i;
      EXPECT_NEAR(a[i].t, b[i].t, kPhaseTolerance * T) << i;
    }
    EXPECT_EQ(exact.attractor.kind, cvode.attractor.kind);
    if (exact.attractor.kind != "sticking-periodic") continue;
    EXPECT_EQ(exact.attractor.period, cvode.attractor.period);
    EXPECT_NEAR(*exact.attractor.sticking_fraction, *cvode.attractor.sticking_fraction, kPhaseTolerance);
    ASSERT_EQ(exact.attractor.stick_phases.size(), cvode.attractor.stick_phases.size());
    for (size_t i = 0; i < exact.attractor.stick_phases.size(); ++i) {
      EXPECT_NEAR(exact.attractor.stick_phases[i].first, cvode.attractor.stick_phases[i].first, kPhaseTolerance);
      EXPECT_NEAR(exact.attractor.stick_phases[i].second, cvode.attractor.stick_phases[i].second, kPhaseTolerance);
    }
  }
}

TEST(Engines, CvodeErrorFallsWithRtol) {
  // Fig. 5 (chattering, r = 0.75) and the 2-DOF chain (chattering while mass 1 moves).
  for (const char* file : {"fig05_coexistence.toml", "chain2.toml"}) {
    SCOPED_TRACE(file);
    const Scene scene =
        LoadScene(std::string(VIBRO_SCENES_DIR) + "/" + file, {"run.samples_per_period=0"}).scene;
    const double truth = *Simulate(WithEngine(scene, Engine::kExact)).attractor.sticking_fraction;
    std::vector<double> errors;
    for (double rtol : {1e-6, 1e-8, 1e-10, 1e-12}) {
      const Outcome o = Simulate(WithEngine(scene, Engine::kCvode, rtol));
      ASSERT_TRUE(o.attractor.sticking_fraction.has_value()) << rtol;
      const double err = std::abs(*o.attractor.sticking_fraction - truth);
      SCOPED_TRACE(testing::Message() << "rtol " << rtol << " error " << err);
      EXPECT_LT(err, 100 * std::pow(rtol, 2.0 / 3.0));  // the observed law, with margin
      errors.push_back(err);
    }
    EXPECT_GT(errors[0], 10 * errors[1]);  // falls with rtol (down to ~1e-10 on this case)
    EXPECT_GT(errors[1], 5 * errors[2]);
    EXPECT_LT(errors[3], 1e-8);
  }
}

TEST(Engines, CvodeCatchesTheNearGrazingImpact) {
  // The flight of ExactEngine.NearGrazingPenetrationWindowOf1e8IsFound dips below the stop for
  // 1e-8: the velocity root ends a step at the gap minimum, so the crossing is seen.
  const double x0 = -std::ldexp(1.0, -20);
  const double X0 = x0 + std::ldexp(1.0, -41);
  const LD A = -static_cast<LD>(x0) * (1 / std::cos(0.5e-8L)), aX = -static_cast<LD>(X0);
  const double v0 = static_cast<double>(-std::sqrt((A - aX) * (A + aX)));
  Scene s = OneDof(0.5, 1.0, 0.0, x0, 1);
  s.initial_displacement = Eigen::VectorXd::Constant(1, X0);
  s.initial_velocity = Eigen::VectorXd::Constant(1, v0);
  const Outcome exact = Simulate(WithEngine(s, Engine::kExact));
  // The flight is 1e-6 in size: atol must be scaled to it (the dip is 1e-23 deep).
  Scene sc = WithEngine(s, Engine::kCvode, 1e-12);
  sc.run.atol = 1e-30;
  const Outcome cvode = Simulate(sc);
  const auto ei = exact.log.Of(EventKind::kImpact), ci = cvode.log.Of(EventKind::kImpact);
  ASSERT_FALSE(ei.empty());
  ASSERT_FALSE(ci.empty()) << "CVODE missed the near-grazing impact";
  EXPECT_NEAR(ci.front().t, ei.front().t, 1e-8);
}

TEST(Engines, ChatteringNeverTunnelsThroughTheStop) {
  for (double r : {0.5, 0.75, 0.95}) {
    for (double rtol : {1e-6, 1e-10}) {
      // f = 1.05 for r = 0.95: at f = 1.2 that restitution gives no sticking orbit.
      Scene s = WithEngine(OneDof(r, 2.8, r > 0.9 ? 1.05 : 1.2, 1.0, 30), Engine::kCvode, rtol);
      s.run.samples_per_period = 500;
      const Outcome o = Simulate(s);
      ASSERT_EQ(o.result.status, RunStatus::kOk);
      EXPECT_GT(o.result.counts.accumulations, 20);
      double lowest = 1e300;
      for (const auto& row : o.log.samples) lowest = std::min(lowest, row.x_B);
      EXPECT_GE(lowest, 1.0 - 10 * rtol) << "r = " << r << ", rtol = " << rtol;
      for (const auto& e : o.log.events) EXPECT_GE(e.x_B, 1.0 - 10 * rtol);
    }
  }
}

TEST(Engines, LongCvodeRunKeepsItsAccuracy) {
  // 10⁵ periods of the q = 2 subharmonic orbit (Fig. 4): the release and landing phases at the
  // end agree with the exact engine as well as at the start.
  Scene s = OneDof(0.0, 10.0, 6.0, 1.0, 100000);
  const Outcome exact = Simulate(WithEngine(s, Engine::kExact));
  const Outcome cvode = Simulate(WithEngine(s, Engine::kCvode, 1e-10));
  ASSERT_EQ(cvode.result.status, RunStatus::kOk);
  const auto ce = cvode.log.Of(EventKind::kImpact), ee = exact.log.Of(EventKind::kImpact);
  ASSERT_EQ(ce.size(), ee.size());
  const double T = 2 * M_PI / 10.0;
  const double first = std::abs(ce.front().clock.offset - ee.front().clock.offset);
  const double last = std::abs(ce.back().clock.offset - ee.back().clock.offset);
  EXPECT_EQ(ce.back().clock.period, ee.back().clock.period);
  EXPECT_LT(last, 1e-8 * T);
  EXPECT_LE(last, first + 1e-12 * T);
}

TEST(Engines, ParallelThreadsGiveTheSameBitsAsAlone) {
  const Scene a = WithEngine(LoadScene(std::string(VIBRO_SCENES_DIR) + "/chain2.toml",
                                       {"run.periods=40", "run.samples_per_period=0"}).scene,
                             Engine::kCvode);
  const Scene b = WithEngine(OneDof(0.75, 10.0, 1.1, 1.0, 40), Engine::kCvode);
  const Outcome alone_a = Simulate(a), alone_b = Simulate(b);
  Outcome par_a, par_b;
  std::thread ta([&] { par_a = Simulate(a); });
  std::thread tb([&] { par_b = Simulate(b); });
  ta.join();
  tb.join();
  for (const auto& [x, y] : {std::pair{&alone_a, &par_a}, std::pair{&alone_b, &par_b}}) {
    ASSERT_EQ(x->log.events.size(), y->log.events.size());
    for (size_t i = 0; i < x->log.events.size(); ++i) {
      EXPECT_EQ(x->log.events[i].clock.offset, y->log.events[i].clock.offset);
      EXPECT_EQ(x->log.events[i].v_before, y->log.events[i].v_before);
    }
  }
}

TEST(Engines, EveryCvodeFailureReturnsAStatusAndKeepsTheEvents) {
  // Too many steps in a segment: the stick and release before the failing flight are kept.
  Scene s = WithEngine(OneDof(0.75, 2.8, 1.2, 1.0, 10), Engine::kCvode);
  s.run.max_steps = 30;
  Outcome o = Simulate(s);
  EXPECT_EQ(o.result.status, RunStatus::kNumericalFailure);
  EXPECT_NE(o.result.message.find("run.max_steps"), std::string::npos) << o.result.message;
  EXPECT_NE(o.result.message.find("free flight"), std::string::npos) << o.result.message;
  EXPECT_GE(o.log.events.size(), 2u);
  // A maximum step too small for the work limit fails in CVODE itself (CV_TOO_MUCH_WORK).
  s.run.max_steps = 1000;
  s.run.max_step = 1e-6;
  o = Simulate(s);
  EXPECT_EQ(o.result.status, RunStatus::kNumericalFailure);
  EXPECT_NE(o.result.message.find("CV_TOO_MUCH_WORK"), std::string::npos) << o.result.message;
  EXPECT_NE(o.result.message.find("t = "), std::string::npos) << o.result.message;
  // A failure in the sticking flow (2-DOF): the message names the mode.
  Scene c = WithEngine(Chain(2, 1.0, 0.5, 0.8, 0.8), Engine::kCvode);
  c.run.periods = 5;
  c.run.max_steps = 100;
  c.run.max_step = 1e-3;
  o = Simulate(c);
  EXPECT_EQ(o.result.status, RunStatus::kNumericalFailure);
  EXPECT_NE(o.result.message.find("sticking"), std::string::npos) << o.result.message;
  EXPECT_FALSE(o.log.events.empty());  // the initial stick is kept
}

}  // namespace
}  // namespace vibro::test
