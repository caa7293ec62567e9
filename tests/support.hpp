// Shared helpers of the test suite: scenes built in code, an observer that logs everything, and
// the independent 1-DOF closed forms of docs/model.md §6 evaluated in long double.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "vibro/attractor.hpp"
#include "vibro/observer.hpp"
#include "vibro/scene.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace vibro::test {

// The paper's non-dimensional 1-DOF oscillator (ω_1 = 1, T_A = T_B = 1, docs/model.md §1.4).
inline Scene OneDof(double r, double w, double f, double x0 = 1.0, long long periods = 100) {
  Scene s;
  s.modal = ModalStructureSpec{Eigen::VectorXd::Ones(1), Eigen::VectorXd::Ones(1),
                               Eigen::VectorXd::Ones(1)};
  s.restitution = r;
  s.frequency = w;
  s.amplitude = f;
  s.stop_position = x0;
  s.run.periods = periods;
  s.run.samples_per_period = 0;
  return s;
}

inline Scene Chain(int n, double x0, double r, double w, double f) {
  Scene s;
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(n, n), K = Eigen::MatrixXd::Zero(n, n);
  K(0, 0) = 1.0;
  for (int i = 1; i < n; ++i) {
    K(i - 1, i - 1) += 1.0;
    K(i, i) += 1.0;
    K(i - 1, i) -= 1.0;
    K(i, i - 1) -= 1.0;
  }
  s.physical = PhysicalStructureSpec{M, K, 0, n - 1};
  s.stop_position = x0;
  s.restitution = r;
  s.frequency = w;
  s.amplitude = f;
  s.run.samples_per_period = 0;
  return s;
}

struct Log final : Observer {
  struct Row {
    Clock clock;
    double t, x_B;
    Eigen::VectorXd X, V;
    Mode mode;
  };
  std::vector<Event> events;
  std::vector<Row> samples, sections;
  void OnEvent(const Event& e) override { events.push_back(e); }
  void OnSample(const Sample& s) override {
    samples.push_back({s.clock, s.t, s.x_B, s.X, s.V, s.mode});
  }
  void OnSection(const Sample& s) override {
    sections.push_back({s.clock, s.t, s.x_B, s.X, s.V, s.mode});
  }
  std::vector<Event> Of(EventKind k) const {
    std::vector<Event> out;
    for (const auto& e : events)
      if (e.kind == k) out.push_back(e);
    return out;
  }
};

struct Outcome {
  RunResult result;
  Attractor attractor;
  Log log;
};

// Two event logs of one scene walked together (i in a, j in b): an engine that follows more
// impacts of a chattering tail before its prediction is certain (quad) has impacts where the other
// has its accumulation; skips them. False when a log ends there.
inline bool AlignChatteringTails(const std::vector<Event>& a, size_t& i, const std::vector<Event>& b, size_t& j) {
  if (a[i].kind == EventKind::kAccumulation && b[j].kind == EventKind::kImpact) {
    while (j < b.size() && b[j].kind == EventKind::kImpact) ++j;
    return j < b.size();
  }
  if (b[j].kind == EventKind::kAccumulation && a[i].kind == EventKind::kImpact) {
    while (i < a.size() && a[i].kind == EventKind::kImpact) ++i;
    return i < a.size();
  }
  return true;
}

// Several contacts (docs/contacts.md): a random structure, a chain of n masses on springs (with a spring to the ground at each end),
// forced on one DOF; contacts placed around the start state so that it opens every gap.
inline Scene RandomContactsScene(std::mt19937_64& rng) {
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

// Runs the scene (from `from` when given, e.g. a point of an orbit) and classifies its end.
inline Outcome Simulate(const Scene& scene, const InitialOverride* from = nullptr) {
  const System sys(scene);
  Outcome run;
  AttractorRecorder rec(sys, scene);
  SimulationOptions opt;
  opt.initial = from;
  opt.observers = {&rec, &run.log};
  run.result = vibro::Simulate(sys, scene, opt);
  run.attractor = rec.Classify();
  return run;
}

// --- docs/model.md §6 closed forms (1-DOF, ω_1 = 1, T_A = 1, f sin ωt), long double ----------------------
using LD = long double;

// Free flight (docs/model.md §2) from (x_a, v_a) at t_a: x(t) = U(t) + (x_a − U(t_a)) cos(t − t_a)
// + (v_a − U̇(t_a)) sin(t − t_a), U = f sin ωt / (1 − ω²).
struct Flight1 {
  LD w, f, ta, xa, va;
  LD U(LD t) const { return f * std::sin(w * t) / (1 - w * w); }
  LD dU(LD t) const { return f * w * std::cos(w * t) / (1 - w * w); }
  LD x(LD t) const {
    return U(t) + (xa - U(ta)) * std::cos(t - ta) + (va - dU(ta)) * std::sin(t - ta);
  }
  LD v(LD t) const {
    return dU(t) - (xa - U(ta)) * std::sin(t - ta) + (va - dU(ta)) * std::cos(t - ta);
  }
  // First t > t_a + skip with x(t) = x0, by a fine scan and bisection (transversal roots only).
  LD Landing(LD x0, LD skip = 1e-3L, LD step = 1e-4L) const {
    LD a = ta + skip;
    LD ga = x(a) - x0;
    for (int i = 0; i < 10000000; ++i) {
      const LD b = a + step;
      const LD gb = x(b) - x0;
      if ((ga > 0) != (gb > 0)) {
        LD lo = a, hi = b;
        for (int it = 0; it < 200; ++it) {
          const LD mid = 0.5L * (lo + hi);
          if (((x(mid) - x0) > 0) == (ga > 0))
            lo = mid;
          else
            hi = mid;
        }
        return 0.5L * (lo + hi);
      }
      a = b;
      ga = gb;
    }
    return std::numeric_limits<LD>::quiet_NaN();
  }
};

// Release phase (32): sin φ_1 = x0/f, cos φ_1 > 0, as a time in [0, T).
inline LD ReleaseTime(LD w, LD f, LD x0 = 1) {
  LD phi = std::asin(x0 / f);
  if (phi < 0) phi += 2 * M_PIl;
  return phi / w;
}

}  // namespace vibro::test
