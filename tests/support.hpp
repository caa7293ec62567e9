// Shared helpers of the test suite: scenes built in code, an observer that logs everything, and
// the independent 1-DOF closed forms of docs/model.md §6 evaluated in long double.
#pragma once

#include <cmath>
#include <limits>
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
