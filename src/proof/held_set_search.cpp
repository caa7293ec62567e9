// The sticking orbit held on sets of contacts as the simulator finds it (held_set_proof.hpp): the
// Poincaré solver's orbit, followed over two periods; its landings and releases cut one period into
// segments, and the state at each segment's start is carried from the section by the held flows.
#include <algorithm>
#include <cmath>
#include <set>

#include <fmt/format.h>

#include "proof/held_set_proof.hpp"
#include "proof/sticking_search.hpp"
#include "vibro/observer.hpp"
#include "vibro/orbit_from_state.hpp"

namespace vibro::proof {
namespace {

struct Item {
  EventKind kind;
  int contact;
  double t;
  bool simultaneous;
};

class EventRecorder final : public Observer {
 public:
  void OnEvent(const Event& e) override { items.push_back({e.kind, e.contact, e.t, e.simultaneous}); }
  std::vector<Item> items;
};

struct Transition {
  HeldSetTransition end;
  double t;
};

Eigen::MatrixXd MidOf(const IntervalMatrix& a) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(a.size()), static_cast<Eigen::Index>(a.size()));
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < a.size(); ++j) m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = a[i][j].mid();
  return m;
}

// W_jk = σ_jσ_k w_jᵀM⁻¹w_k from the scene's matrices as exact decimals (all modes kept), or c_jᵀT_k
// of the modal data.
void Coupling(const System& sys, const Scene& scene, const IntervalModel& model, HeldSetGuess& g) {
  const std::size_t J = model.contacts.size();
  g.coupling.assign(J, std::vector<Interval>(J));
  if (scene.physical && sys.dof() == scene.physical->mass.rows()) {
    const auto& M = scene.physical->mass;
    const auto N = static_cast<std::size_t>(M.rows());
    IntervalMatrix Mi(N, std::vector<Interval>(N)), Minv;
    for (std::size_t a = 0; a < N; ++a)
      for (std::size_t b = 0; b < N; ++b)
        Mi[a][b] = Interval::Decimal(fmt::format("{}", M(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b))));
    if (InvertSmall(Mi, Minv)) {
      const auto contacts = Contacts(scene);
      const auto w = [&](std::size_t j) {
        std::vector<Interval> v(N);
        const auto& c = contacts[j];
        const double s = c.side == Side::kBelow ? 1.0 : -1.0;
        v[static_cast<std::size_t>(c.dof)] += Interval(s);
        if (c.partner >= 0) v[static_cast<std::size_t>(c.partner)] -= Interval(s);
        return v;
      };
      for (std::size_t j = 0; j < J; ++j)
        for (std::size_t k = 0; k < J; ++k) {
          const auto a = w(j), b = w(k);
          Interval s(0.0);
          for (std::size_t x = 0; x < N; ++x)
            for (std::size_t y = 0; y < N; ++y) s += a[x] * Minv[x][y] * b[y];
          g.coupling[j][k] = s;
        }
      g.coupling_source = "structure";
      return;
    }
  }
  for (std::size_t j = 0; j < J; ++j)
    for (std::size_t k = 0; k < J; ++k)
      for (int i = 0; i < model.n; ++i)
        g.coupling[j][k] += model.contacts[j].shape[static_cast<std::size_t>(i)] * model.contacts[k].contact[static_cast<std::size_t>(i)];
  g.coupling_source = "modal";
}

}  // namespace

FoundHeldSet FindHeldSetOrbit(const System& sys, const Scene& scene, const IntervalModel& model,
                              const ProofRequest& request, const Budget& budget) {
  FoundHeldSet f;
  EventRecorder rec;
  const StickingSearch found = FollowStickingOrbit(sys, scene, request, budget, rec);
  if (found.stopped || !found.failure.empty()) {
    f.stopped = found.stopped;
    f.failure = found.failure;
    return f;
  }
  const OrbitResult& orbit = found.orbit;
  // The events as landings (an impact, then a stick at the same instant, or not) and releases.
  std::vector<Transition> tr;
  const auto& it = rec.items;
  for (const Item& e : it)
    if (e.kind == EventKind::kAccumulation) {
      f.failure = "sticking orbits with chattering (an accumulation of impacts) of a model with several contacts are "
                  "not proven by this version";
      return f;
    }
  for (std::size_t k = 0; k < it.size(); ++k) {
    const Item& e = it[k];
    if (e.kind == EventKind::kGrazing) {
      f.failure = "the orbit found grazes a stop: a grazing orbit cannot be proven";
      return f;
    }
    if (e.simultaneous) {
      f.failure = "the orbit found has a simultaneous impact of two contacts: an orbit through a simultaneous impact "
                  "is not proven (the impact map has no derivative there, docs/prove.md)";
      return f;
    }
    if (e.kind == EventKind::kImpact) {
      if (model.contacts[static_cast<std::size_t>(e.contact)].restitution.hi() > 0) {
        f.failure = "impacts with r > 0 in a sticking orbit of several contacts are not proven by this version";
        return f;
      }
      const bool sticks = k + 1 < it.size() && it[k + 1].kind == EventKind::kStick && it[k + 1].contact == e.contact &&
                          std::abs(it[k + 1].t - e.t) <= 1e-9 * (1 + std::abs(e.t));
      tr.push_back({{true, e.contact, sticks}, e.t});
      if (sticks) ++k;
    } else if (e.kind == EventKind::kRelease) {
      tr.push_back({{false, e.contact, false}, e.t});
    } else {
      f.failure = "the sticking orbit found has a stick without a landing (a tangential arrival) the prover cannot "
                  "follow";
      return f;
    }
  }
  const double T = sys.period(), qT = orbit.period * T;
  std::size_t r0 = 0;
  while (r0 < tr.size() && tr[r0].end.landing) ++r0;
  std::size_t r1 = r0 + 1;
  while (r1 < tr.size() && !(!tr[r1].end.landing && tr[r1].end.contact == tr[r0].end.contact &&
                             std::abs(tr[r1].t - tr[r0].t - qT) <= 1e-6 * T))
    ++r1;
  if (r0 >= tr.size() || r1 >= tr.size()) {
    f.failure = "the sticking orbit found is not a sequence of landings and releases repeating after its period";
    return f;
  }
  const std::size_t m = r1 - r0;
  // The set held just before release r0: the contacts whose first event in the period is a release.
  std::set<int> held, seen;
  for (std::size_t k = r0; k < r1; ++k) {
    const int c = tr[k].end.contact;
    if (seen.insert(c).second && !tr[k].end.landing) held.insert(c);
  }
  auto& g = f.guess;
  g.period = orbit.period;
  const double shift = std::floor(tr[r0].t / T) * T;
  held.erase(tr[r0].end.contact);
  for (std::size_t k = 0; k < m; ++k) {
    g.times.push_back(tr[r0 + k].t - shift);
    g.held.emplace_back(held.begin(), held.end());
    const auto& e = tr[r0 + k + 1].end;
    g.ends.push_back(e);
    if (e.landing && e.sticks) held.insert(e.contact);
    if (!e.landing) held.erase(e.contact);
  }
  // The states at the segments' starts, carried from the section state by the held flows.
  const auto mi = static_cast<int>(m);
  std::vector<SetFlow> flows(m);
  for (std::size_t k = 0; k < m; ++k) {
    std::string why;
    if (!MakeSetFlow(model, g.held[k], flows[k], why)) {
      f.failure = why;
      return f;
    }
  }
  double ts = orbit.section_time - shift;
  while (ts < g.times[0]) ts += qT;
  while (ts >= g.times[0] + qT) ts -= qT;
  int k = 0;
  while (k + 1 < mi && g.times[static_cast<std::size_t>(k + 1)] <= ts) ++k;
  const auto n = static_cast<Eigen::Index>(model.n);
  Eigen::VectorXd z(2 * n + 2);
  z << orbit.X, orbit.V, std::sin(sys.frequency() * ts), std::cos(sys.frequency() * ts);
  g.X.assign(m, Eigen::VectorXd());
  g.V.assign(m, Eigen::VectorXd());
  double t = ts;
  for (int step = 0; step < mi; ++step, k = (k + 1) % mi) {
    const auto ks = static_cast<std::size_t>(k);
    const double tend = k + 1 < mi ? g.times[ks + 1] : g.times[0] + qT;
    double s = tend - t;
    while (s < 0) s += qT;
    z = MidOf(HeldExp(flows[ks].h, Interval(s))) * z;
    const auto& e = g.ends[ks];
    if (e.landing) {
      auto Z = g.held[ks];
      Z.push_back(e.contact);
      std::sort(Z.begin(), Z.end());
      // V ← V − T_Z W_ZZ⁻¹ C_Z V (in double).
      const auto p = static_cast<Eigen::Index>(Z.size());
      Eigen::MatrixXd Cz(p, n), Tz(n, p);
      for (Eigen::Index r = 0; r < p; ++r)
        for (Eigen::Index i = 0; i < n; ++i) {
          Cz(r, i) = model.contacts[static_cast<std::size_t>(Z[static_cast<std::size_t>(r)])].shape[static_cast<std::size_t>(i)].mid();
          Tz(i, r) = model.contacts[static_cast<std::size_t>(Z[static_cast<std::size_t>(r)])].contact[static_cast<std::size_t>(i)].mid();
        }
      const Eigen::VectorXd v = z.segment(n, n);
      z.segment(n, n) = v - Tz * (Cz * Tz).inverse() * (Cz * v);
    }
    const auto next = static_cast<std::size_t>((k + 1) % mi);
    g.X[next] = z.head(n);
    g.V[next] = z.segment(n, n);
    t = tend;
    if (k + 1 == mi) t -= qT;
  }
  Coupling(sys, scene, model, g);
  return f;
}

}  // namespace vibro::proof
