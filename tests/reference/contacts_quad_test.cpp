// Several contacts: the double engine against the quad (113-bit) engine, event by event, on seeded
// random scenes of 1 to 3 DOFs with 1 to 4 contacts (stops below and above, on one DOF or between
// two: impact pairs), preloaded and with clearance, damped and not, elastic and plastic
// (docs/contacts.md, "Checked against"). The quad engine runs the same automaton on 113-bit
// closed forms, so its events are the truth for the double engine's rounding: every event must
// agree in kind and contact, and in time within 1e-10 T, up to the first near-grazing contact (the
// event map has a square-root singularity there, and a rounding-level difference may change the
// sequence legitimately).
#include <cstdio>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "support.hpp"
#include "vibro/scene_toml.hpp"

namespace vibro::test {
namespace {

struct Agreement {
  double worst = 0;
  int compared = 0, simultaneous = 0, sticks = 0, multi_contact_events = 0;
  bool complete = false;
};

Agreement Compare(const Outcome& dbl, const Outcome& quad, double T, double tol, const std::string& name) {
  const auto& a = dbl.log.events;
  const auto& b = quad.log.events;
  Agreement g;
  size_t i = 0, j = 0;
  for (; i < a.size() && j < b.size(); ++i, ++j) {
    if (!AlignChatteringTails(a, i, b, j)) break;
    if ((b[j].kind == EventKind::kImpact || b[j].kind == EventKind::kGrazing) && std::abs(b[j].v_before) < 1e-4)
      return g;  // near grazing: the sequences may part legitimately
    EXPECT_EQ(a[i].kind, b[j].kind) << fmt::format("{} event {}/{}: double {} at {:.17g}, quad {} at {:.17g}",
                                                   name, i, j, ToString(a[i].kind), a[i].t,
                                                   ToString(b[j].kind), b[j].t);
    EXPECT_EQ(a[i].contact, b[j].contact) << fmt::format("{} event {} at {:.17g}", name, i, a[i].t);
    if (a[i].kind != b[j].kind || a[i].contact != b[j].contact) return g;
    const double dt = std::abs(a[i].t - b[j].t) / T;
    g.worst = std::max(g.worst, dt);
    EXPECT_LE(dt, tol) << fmt::format("{} event {} ({} at contact {}, {:.17g} vs {:.17g})", name, i,
                                      ToString(a[i].kind), a[i].contact, a[i].t, b[j].t);
    ++g.compared;
    g.simultaneous += a[i].simultaneous;
    g.sticks += a[i].kind == EventKind::kStick;
    g.multi_contact_events += a[i].contact > 0;
  }
  g.complete = i == a.size() && j == b.size();
  return g;
}

TEST(ContactsQuad, RandomMultiContactScenesAgreeWithTheDoubleEngine) {
  std::mt19937_64 rng(20261127);
  int valid = 0, compared_scenes = 0, complete = 0, events = 0, simultaneous = 0, sticks = 0, other = 0;
  int both_undetermined = 0;
  double worst = 0;
  for (int k = 0; k < 400; ++k) {
    const Scene s = RandomContactsScene(rng);
    if (!Validate(s).empty()) continue;
    if (std::getenv("VIBRO_DUMP_SCENE")) {
      std::fprintf(stderr, "scene %d\n", k);
      if (std::atoi(std::getenv("VIBRO_DUMP_SCENE")) == k) std::fprintf(stderr, "%s\n", ResolvedSceneToml(s).c_str());
    }
    ++valid;
    Scene q = s;
    q.run.precision = Precision::kQuad;
    const Outcome dbl = Simulate(s);
    const Outcome quad = Simulate(q);
    const std::string name = fmt::format("random scene {} ({} DOF, {} contacts)", k,
                                         s.physical->mass.rows(), s.contacts.size());
    // A failure of either run (two contacts stuck at once is reported undetermined) ends the
    // comparison at its events; a failure of quad alone would be a defect of the quad engine.
    if (dbl.result.status == RunStatus::kOk) {
      EXPECT_NE(quad.result.status, RunStatus::kNumericalFailure) << name << ": " << quad.result.message;
    }
    both_undetermined += dbl.result.status != RunStatus::kOk && quad.result.status != RunStatus::kOk;
    if (std::getenv("VIBRO_DUMP_SCENE") && std::atoi(std::getenv("VIBRO_DUMP_SCENE")) == k) {
      std::printf("%s\n", ResolvedSceneToml(s).c_str());
      for (const Outcome* o : {&dbl, &quad})
        for (const Event& e : o->log.events)
          std::printf("%s %d %.17g %.6g %.6g\n", ToString(e.kind), e.contact, e.t, e.v_before, e.v_after);
    }
    const Agreement g = Compare(dbl, quad, 2.0 * M_PI / s.frequency, 1e-10, name);
    ++compared_scenes;
    complete += g.complete && dbl.result.status == RunStatus::kOk;
    worst = std::max(worst, g.worst);
    events += g.compared;
    simultaneous += g.simultaneous;
    sticks += g.sticks;
    other += g.multi_contact_events;
  }
  std::printf("random multi-contact scenes: %d valid, %d compared to the end, %d both stopped, %d events "
              "(%d at contacts >= 1, %d sticks, %d simultaneous), worst |dt|/T %.3g\n",
              valid, complete, both_undetermined, events, other, sticks, simultaneous, worst);
  EXPECT_GE(valid, 200);
  EXPECT_GE(complete, 150);
  EXPECT_GE(other, 500);
  EXPECT_GE(sticks, 50);
}

}  // namespace
}  // namespace vibro::test
