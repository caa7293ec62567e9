// Several contacts (docs/contacts.md): the cost per event on an 8-mass chain as the number of
// contacts grows (1, 2, 4, 8 stops, alternately below and above consecutive masses, each a
// clearance the forced motion reaches). The target: the cost per event grows at most
// linearly with the number of contacts (each free flight searches every gap). The single stop's
// event rate is BM_Events1Dof and the chains of simulate_bench.cpp.
#include <string>

#include <benchmark/benchmark.h>

#include "vibro/scene.hpp"
#include "vibro/simulator.hpp"
#include "vibro/system.hpp"

namespace {

vibro::Scene ChainWithContacts(int m) {
  const int n = 8;
  vibro::Scene s;
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(n, n), K = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    K(i, i) += 2.0;
    if (i + 1 < n) {
      K(i, i + 1) -= 1.0;
      K(i + 1, i) -= 1.0;
    }
  }
  s.physical = vibro::PhysicalStructureSpec{M, K, 0, 0};
  s.damping_ratios = Eigen::VectorXd::Constant(n, 0.02);
  for (int j = 0; j < m; ++j) {
    const int dof = (j * n) / m;
    const bool below = j % 2 == 0;
    s.contacts.push_back({dof, -1, below ? vibro::Side::kBelow : vibro::Side::kAbove, below ? -0.4 : 0.4, 0.7});
  }
  s.stop_position = s.contacts[0].position;
  s.restitution = s.contacts[0].restitution;
  s.frequency = 0.6;
  s.amplitude = 1.5;
  s.run.periods = 100;
  s.run.samples_per_period = 0;
  s.run.lyapunov = false;
  return s;
}

void BM_ChainContacts(benchmark::State& state) {
  const vibro::Scene scene = ChainWithContacts(static_cast<int>(state.range(0)));
  const vibro::System sys(scene);
  long long events = 0;
  for (auto _ : state) {
    const auto r = vibro::Simulate(sys, scene, {});
    if (r.status != vibro::RunStatus::kOk) {
      state.SkipWithError(r.message.c_str());
      break;
    }
    events += r.counts.impacts + r.counts.accumulations + r.counts.sticks + r.counts.releases;
  }
  state.counters["events/s"] = benchmark::Counter(static_cast<double>(events), benchmark::Counter::kIsRate);
  state.counters["s/event"] = benchmark::Counter(static_cast<double>(events),
                                                 benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_ChainContacts)->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Unit(benchmark::kMillisecond);

}  // namespace
