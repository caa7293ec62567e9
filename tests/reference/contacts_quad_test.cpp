// Several contacts: the double engine against the quad (113-bit) engine, event by event, on seeded
// random scenes of 1 to 3 DOFs with 1 to 4 contacts (stops below and above, on one DOF or between
// two: impact pairs), preloaded and with clearance, damped and not, elastic and plastic
// (docs/contacts.md, "Checked against"). The quad engine runs the same automaton on 113-bit
// closed forms, so its events are the truth for the double engine's rounding: every event must
// agree in kind and contact, and in time within 1e-10 T, up to the first near-grazing contact (the
// event map has a square-root singularity there, and a rounding-level difference may change the
// sequence legitimately).
#include <cstdio>
#include <random>

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

// A random structure: a chain of n masses on springs (with a spring to the ground at each end),
// forced on one DOF; contacts placed around the start state so that it opens every gap.
Scene RandomScene(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = 1 + static_cast<int>(u(rng) * 3.0);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n), K = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) M(i, i) = 0.5 + 1.5 * u(rng);
  for (int i = 0; i <= n; ++i) {
    const double k = 0.5 + 1.5 * u(rng);
    if (i > 0) K(i - 1, i - 1) += k;
    if (i < n) K(i, i) += k;
    if (i > 0 && i < n) {
      K(i - 1, i) -= k;
      K(i, i - 1) -= k;
    }
  }
  Scene s;
  s.physical = PhysicalStructureSpec{M, K, static_cast<int>(u(rng) * n), 0};
  s.frequency = 0.4 + 2.6 * u(rng);
  s.amplitude = 0.5 + 3.0 * u(rng);
  if (u(rng) < 0.5) {
    s.damping_ratios.resize(n);
    for (int i = 0; i < n; ++i) s.damping_ratios[i] = 0.01 + 0.15 * u(rng);
  }
  // The static response to the forcing amplitude sets the scale of the gaps.
  const Eigen::VectorXd q_static = K.ldlt().solve(Eigen::VectorXd::Unit(n, s.physical->forcing_dof)) * s.amplitude;
  const double scale = std::max(0.05, q_static.cwiseAbs().maxCoeff());
  const int m = 1 + static_cast<int>(u(rng) * 4.0);
  // Preload: the first contact a stop below with d > 0, the run starting on it at its static
  // equilibrium (the default start of a preloaded scene), the others placed around that state.
  const bool preload = u(rng) < 0.3;
  Eigen::VectorXd q0 = Eigen::VectorXd::Zero(n);
  for (int j = 0; j < m; ++j) {
    ContactSpec c;
    c.dof = static_cast<int>(u(rng) * n);
    if (n > 1 && u(rng) < 0.3) {
      c.partner = (c.dof + 1 + static_cast<int>(u(rng) * (n - 1))) % n;
    }
    c.side = u(rng) < 0.5 ? Side::kBelow : Side::kAbove;
    c.restitution = u(rng) < 0.25 ? 0.0 : 0.2 + 0.75 * u(rng);
    if (j == 0 && preload) {
      c.partner = -1;
      c.side = Side::kBelow;
      c.position = scale * (0.1 + 0.5 * u(rng));
      // Static equilibrium on the stop: K q = e_b R with q_b = d.
      const Eigen::VectorXd kb = K.ldlt().solve(Eigen::VectorXd::Unit(n, c.dof));
      q0 = kb * (c.position / kb[c.dof]);
    } else {
      const double at = q0[c.dof] - (c.partner >= 0 ? q0[c.partner] : 0.0);
      const double gap = scale * (0.2 + 1.5 * u(rng));
      c.position = c.side == Side::kBelow ? at - gap : at + gap;
    }
    s.contacts.push_back(c);
  }
  s.stop_position = s.contacts[0].position;
  s.restitution = s.contacts[0].restitution;
  s.physical->contact_dof = s.contacts[0].dof;
  s.run.samples_per_period = 0;
  s.run.periods = 6;
  s.run.chatter_tolerance = 1e-15;
  return s;
}

TEST(ContactsQuad, RandomMultiContactScenesAgreeWithTheDoubleEngine) {
  std::mt19937_64 rng(20261127);
  int valid = 0, compared_scenes = 0, complete = 0, events = 0, simultaneous = 0, sticks = 0, other = 0;
  int both_undetermined = 0;
  double worst = 0;
  for (int k = 0; k < 400; ++k) {
    const Scene s = RandomScene(rng);
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
