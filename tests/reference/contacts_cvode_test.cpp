// Several contacts with the CVODE engine (docs/contacts.md, docs/engines.md) against the exact
// engine, the independent truth for CVODE: on every shipped multi-contact scene, event by event,
// the same kinds at the same contacts, at the same times within a tolerance set by rtol.
//
// Tolerance: CVODE's local error is ≈ rtol of the state per step; an event time inherits it
// divided by the closing speed, and the errors accumulate over the 15 to 20 periods of a scene.
// Measured at rtol = 1e-12 (atol = 1e-14), worst |Δt|/T over every event: beam3 2.2e-10,
// impact_pair 6.4e-11, chain2 8.0e-12, two_sided_1dof 1.6e-12, preload_clearance_1dof 5.5e-13;
// at rtol = 1e-10 they are 20 to 400 times larger (4.6e-9, 2.4e-8, 6.2e-10, 1.4e-10, 1.1e-11),
// so the worst error is ≈ 250·rtol·T at either rtol (beam3 at 1e-12, impact_pair at 1e-10).
// kTimeTolerance = 2e-9 T = 2000·rtol: about ten times the worst.
// At this rtol both engines follow the same chattering impacts (CVODE switches to the
// accumulation prediction at √rtol = 1e-6 of a sequence's first impact speed, the exact engine at
// its own error estimate); where they do not, the tails are aligned as the quad comparisons do
// (tests/support.hpp, AlignChatteringTails).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/scene_toml.hpp"

namespace vibro::test {
namespace {

constexpr double kTimeTolerance = 2e-9;  // |Δt|/T, CVODE at rtol 1e-12 against the exact engine

Scene WithEngine(Scene s, Engine e, double rtol = 1e-12) {
  s.run.engine = e;
  s.run.rtol = rtol;
  s.run.atol = rtol * 1e-2;
  return s;
}

std::vector<std::string> MultiContactScenes() {
  std::vector<std::string> out;
  for (const auto& entry : std::filesystem::directory_iterator(VIBRO_SCENES_DIR)) {
    const std::string name = entry.path().filename().string();
    if (entry.path().extension() == ".toml" && name.rfind("contacts_", 0) == 0) out.push_back(entry.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

struct Agreement {
  double worst = 0;  // |Δt|/T
  int compared = 0, other_contacts = 0, sticks = 0, releases = 0;
  bool complete = false;
};

// Every event of the exact run (a) and the CVODE run (b), walked together.
Agreement Compare(const std::vector<Event>& a, const std::vector<Event>& b, double T, const std::string& name) {
  Agreement g;
  size_t i = 0, j = 0;
  for (; i < a.size() && j < b.size(); ++i, ++j) {
    if (!AlignChatteringTails(a, i, b, j)) break;
    EXPECT_EQ(a[i].kind, b[j].kind) << fmt::format("{} event {}/{}: exact {} at {:.17g}, cvode {} at {:.17g}",
                                                   name, i, j, ToString(a[i].kind), a[i].t,
                                                   ToString(b[j].kind), b[j].t);
    EXPECT_EQ(a[i].contact, b[j].contact) << fmt::format("{} event {} at {:.17g}", name, i, a[i].t);
    if (a[i].kind != b[j].kind || a[i].contact != b[j].contact) return g;
    const double dt = std::abs(a[i].t - b[j].t) / T;
    g.worst = std::max(g.worst, dt);
    EXPECT_LE(dt, kTimeTolerance) << fmt::format("{} event {} ({} at contact {}: exact {:.17g}, cvode {:.17g})",
                                                 name, i, ToString(a[i].kind), a[i].contact, a[i].t, b[j].t);
    ++g.compared;
    g.other_contacts += a[i].contact > 0;
    g.sticks += a[i].kind == EventKind::kStick;
    g.releases += a[i].kind == EventKind::kRelease;
  }
  // What is left of either log may only be impacts of a chattering sequence the other predicted.
  const auto only_impacts = [](const std::vector<Event>& e, size_t from) {
    return std::all_of(e.begin() + static_cast<std::ptrdiff_t>(std::min(from, e.size())), e.end(),
                       [](const Event& x) { return x.kind == EventKind::kImpact; });
  };
  g.complete = only_impacts(a, i) && only_impacts(b, j);
  return g;
}

TEST(ContactsCvode, AgreesWithTheExactEngineOnEveryShippedMultiContactScene) {
  const auto scenes = MultiContactScenes();
  ASSERT_EQ(scenes.size(), 5u);
  double worst = 0;
  for (const auto& path : scenes) {
    SCOPED_TRACE(path);
    const Scene scene = LoadScene(path, {"run.samples_per_period=0"}).scene;
    ASSERT_GT(scene.contacts.size(), 1u);
    const Outcome exact = Simulate(WithEngine(scene, Engine::kExact));
    const Outcome cvode = Simulate(WithEngine(scene, Engine::kCvode));
    ASSERT_EQ(exact.result.status, RunStatus::kOk) << exact.result.message;
    ASSERT_EQ(cvode.result.status, RunStatus::kOk) << cvode.result.message;
    const double T = 2 * M_PI / scene.frequency;
    const std::string name = std::filesystem::path(path).filename().string();
    const Agreement g = Compare(exact.log.events, cvode.log.events, T, name);
    std::printf("%s: %d events compared (%d at contacts >= 1, %d sticks, %d releases), worst |dt|/T %.3g%s\n",
                name.c_str(), g.compared, g.other_contacts, g.sticks, g.releases, g.worst,
                g.complete ? "" : " (incomplete)");
    EXPECT_TRUE(g.complete) << name << ": the event logs part";
    EXPECT_GE(g.compared, 20) << name;
    EXPECT_GT(g.other_contacts, 0) << name << ": no event at a second contact";
    // Every contact's counts agree (the chattering impacts aside: compare the sticks, releases
    // and accumulations per contact).
    ASSERT_EQ(exact.result.contact_counts.size(), cvode.result.contact_counts.size());
    for (size_t j = 0; j < exact.result.contact_counts.size(); ++j) {
      EXPECT_EQ(exact.result.contact_counts[j].sticks, cvode.result.contact_counts[j].sticks) << j;
      EXPECT_EQ(exact.result.contact_counts[j].releases, cvode.result.contact_counts[j].releases) << j;
    }
    worst = std::max(worst, g.worst);
  }
  std::printf("CVODE (rtol 1e-12) against exact on the multi-contact scenes: worst |dt|/T %.3g\n", worst);
}

// The seeded random scenes of the quad comparison (1 to 3 DOFs, 1 to 4 contacts, stops below
// and above, impact pairs, preload and clearance, damped and not, elastic and plastic:
// tests/support.hpp), CVODE at rtol 1e-12 against the exact engine: every event in kind and
// contact, up to the first near-grazing contact (the event map has a square-root singularity
// there, and an rtol-level difference may change the sequence legitimately), and in time within
// kRandomTolerance. Some random motions amplify an error along the run by up to 1e6 (the quad
// comparison allows 1e-10 T for the 1e-16 rounding of double); CVODE's error per step is rtol, so
// the same amplification allows 1e6·rtol = 1e-6 T. Measured: worst 6.2e-8 T (scene 209, one
// contact, a motion whose impact times drift apart geometrically), all other scenes within
// kTimeTolerance. CVODE alone stops 3 of the runs as undetermined (never a numerical failure):
// from rest, a gap whose contact DOF is not forced has a rate and an acceleration that round to
// exactly 0 over CVODE's root tolerance, which CVODE refuses as a root "at and very near" the
// step's start (scene 46 has one contact: the single-stop engine has the same limit).
constexpr double kRandomTolerance = 1e-6;

TEST(ContactsCvode, RandomMultiContactScenesAgreeWithTheExactEngine) {
  std::mt19937_64 rng(20261127);
  int valid = 0, complete = 0, events = 0, other = 0, sticks = 0, cvode_stopped = 0, beyond = 0;
  double worst = 0;
  for (int k = 0; k < 400; ++k) {
    const Scene s = RandomContactsScene(rng);
    if (!Validate(s).empty()) continue;
    ++valid;
    const Outcome exact = Simulate(WithEngine(s, Engine::kExact));
    const Outcome cvode = Simulate(WithEngine(s, Engine::kCvode));
    const std::string name = fmt::format("random scene {} ({} DOF, {} contacts)", k, s.physical->mass.rows(),
                                         s.contacts.size());
    if (exact.result.status == RunStatus::kOk) {
      EXPECT_NE(cvode.result.status, RunStatus::kNumericalFailure) << name << ": " << cvode.result.message;
    }
    cvode_stopped += exact.result.status == RunStatus::kOk && cvode.result.status != RunStatus::kOk;
    if (std::getenv("VIBRO_DUMP_SCENE") && std::atoi(std::getenv("VIBRO_DUMP_SCENE")) == k) {
      std::printf("%s\nexact: %s\ncvode: %s\n", ResolvedSceneToml(s).c_str(), exact.result.message.c_str(),
                  cvode.result.message.c_str());
      for (const Outcome* o : {&exact, &cvode})
        for (const Event& e : o->log.events)
          std::printf("%s %d %.17g %.6g %.6g\n", ToString(e.kind), e.contact, e.t, e.v_before, e.v_after);
    }
    const auto& a = exact.log.events;
    const auto& b = cvode.log.events;
    const double T = 2 * M_PI / s.frequency;
    size_t i = 0, j = 0;
    bool parted = false;
    for (; i < a.size() && j < b.size(); ++i, ++j) {
      if (!AlignChatteringTails(a, i, b, j)) break;
      if ((a[i].kind == EventKind::kImpact || a[i].kind == EventKind::kGrazing) && std::abs(a[i].v_before) < 1e-4) {
        parted = true;  // near grazing: the sequences may part legitimately
        break;
      }
      EXPECT_EQ(a[i].kind, b[j].kind) << fmt::format("{} event {}/{}: exact {} at {:.17g}, cvode {} at {:.17g}", name,
                                                     i, j, ToString(a[i].kind), a[i].t, ToString(b[j].kind), b[j].t);
      EXPECT_EQ(a[i].contact, b[j].contact) << fmt::format("{} event {} at {:.17g}", name, i, a[i].t);
      if (a[i].kind != b[j].kind || a[i].contact != b[j].contact) {
        parted = true;
        break;
      }
      const double dt = std::abs(a[i].t - b[j].t) / T;
      worst = std::max(worst, dt);
      EXPECT_LE(dt, kRandomTolerance) << fmt::format("{} event {} ({} at contact {}: exact {:.17g}, cvode {:.17g})",
                                                     name, i, ToString(a[i].kind), a[i].contact, a[i].t, b[j].t);
      beyond += dt > kTimeTolerance;
      ++events;
      other += a[i].contact > 0;
      sticks += a[i].kind == EventKind::kStick;
    }
    complete += !parted && exact.result.status == RunStatus::kOk && cvode.result.status == RunStatus::kOk;
  }
  std::printf("random multi-contact scenes, CVODE against exact: %d valid, %d compared to the end, %d stopped by "
              "CVODE alone, %d events (%d at contacts >= 1, %d sticks), worst |dt|/T %.3g, %d events beyond %.0e\n",
              valid, complete, cvode_stopped, events, other, sticks, worst, beyond, kTimeTolerance);
  EXPECT_GE(valid, 200);
  EXPECT_GE(complete, 150);
  EXPECT_GE(other, 500);
  EXPECT_GE(sticks, 50);
}

// The error falls with rtol: the agreement is CVODE's accuracy, not a coincidence of one setting.
TEST(ContactsCvode, ErrorFallsWithRtolOnTheChain) {
  const Scene scene =
      LoadScene(std::string(VIBRO_SCENES_DIR) + "/contacts_chain2.toml", {"run.samples_per_period=0", "run.periods=5"}).scene;
  const Outcome exact = Simulate(WithEngine(scene, Engine::kExact));
  ASSERT_EQ(exact.result.status, RunStatus::kOk);
  const double T = 2 * M_PI / scene.frequency;
  std::vector<double> worst;
  for (double rtol : {1e-8, 1e-10, 1e-12}) {
    const Outcome cvode = Simulate(WithEngine(scene, Engine::kCvode, rtol));
    ASSERT_EQ(cvode.result.status, RunStatus::kOk) << rtol << ": " << cvode.result.message;
    // Milestones only (first impact of each contact's sequence, sticks, releases): the number of
    // chattering impacts followed depends on rtol.
    double w = 0;
    const auto a = exact.log.events, b = cvode.log.events;
    size_t i = 0, j = 0;
    for (; i < a.size() && j < b.size(); ++i, ++j) {
      if (!AlignChatteringTails(a, i, b, j)) break;
      ASSERT_EQ(a[i].kind, b[j].kind) << rtol << " event " << i;
      ASSERT_EQ(a[i].contact, b[j].contact) << rtol << " event " << i;
      w = std::max(w, std::abs(a[i].t - b[j].t) / T);
    }
    std::printf("contacts_chain2, 5 periods, rtol %.0e: worst |dt|/T %.3g\n", rtol, w);
    worst.push_back(w);
  }
  EXPECT_GT(worst[0], 10 * worst[1]);
  EXPECT_GT(worst[1], 10 * worst[2]);
}

}  // namespace
}  // namespace vibro::test
