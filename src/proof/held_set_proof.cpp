// Proof of a sticking orbit held on sets of contacts with plastic landings (held_set_proof.hpp,
// docs/prove.md "Sticking orbits held on sets of contacts").
//
// Unknowns: per segment k = 0..m−1 its start (t_k, X_k, V_k), the state just after the event that
// ends segment k − 1 (segment 0 starts at a release). Equations (m(2n + 1) in as many unknowns),
// with Z(t_k + s) = e^{A_k s}Z_k the flow held on the set H_k of segment k (free: H_k empty):
//   the end event: c_jᵀX(t_{k+1}⁻) − e_j = 0 (landing of j) or λ_j(t_{k+1}⁻) = 0 (release of j),
//   X(t_{k+1}⁻) − X_{k+1} = 0,  J(Ẋ(t_{k+1}⁻)) − V_{k+1} = 0  (J = P_{H_k ∪ {j}} at a landing, else I),
// with t_m = t_0 + qT, block m = block 0. At a zero every contact held at a segment's start is on its
// stop at rest: it landed (gap 0, its velocity projected to 0) earlier in the cycle and every flow
// since held it (each held contact is landed somewhere in the cycle: checked). Krawczyk's test proves
// one zero in the box; then over the box, segment by segment: every held contact's force λ_h > 0
// (subdivision, mean-value form with λ̇ = rateᵀZ) up to the end window of its release, over which
// λ̇_h < 0; every other gap > 0: from a release with g = g' = g'' = 0 on a start window where
// g''' = γᵀA³e^{As}Z > 0, from a departure (g = g' = 0) where g'' > 0, up to a landing on an end
// window where ġ < 0; the impulses of the held contacts at a landing ≥ 0 (the impact LCP's pattern) and
// the contact matrix W_ZZ of each landing a P-matrix (so the contact laws' solutions are unique). The
// monodromy is the product of the flows' blocks and the saltation matrices of the landings; its image
// lies in the subspace held at the section, where its multipliers are enclosed.
#include "proof/held_set_proof.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "proof/krawczyk.hpp"

namespace vibro::proof {

bool InvertSmall(const IntervalMatrix& a, IntervalMatrix& inv) {
  const std::size_t p = a.size();
  IntervalMatrix w = a;
  inv.assign(p, std::vector<Interval>(p));
  for (std::size_t i = 0; i < p; ++i) inv[i][i] = 1.0;
  for (std::size_t k = 0; k < p; ++k) {
    const Interval piv = w[k][k];
    if (!(piv.Positive() || piv.Negative())) return false;
    for (std::size_t j = 0; j < p; ++j) {
      w[k][j] /= piv;
      inv[k][j] /= piv;
    }
    for (std::size_t i = 0; i < p; ++i) {
      if (i == k) continue;
      const Interval f = w[i][k];
      for (std::size_t j = 0; j < p; ++j) {
        w[i][j] -= f * w[k][j];
        inv[i][j] -= f * inv[k][j];
      }
    }
  }
  return true;
}

bool MakeSetFlow(const IntervalModel& m, const std::vector<int>& held, SetFlow& out, std::string& why) {
  const auto n = static_cast<std::size_t>(m.n), N = 2 * n + 2, p = held.size();
  out.held = held;
  out.h.n = m.n;
  // a(Z) row by row: a_i = −ω_i² X_i − 2σ_i Ẋ_i + T_A,i f sin ωt.
  IntervalMatrix a(n, std::vector<Interval>(N));
  for (std::size_t i = 0; i < n; ++i) {
    a[i][i] = -Sqr(m.omega[i]);
    if (m.damped()) a[i][n + i] = -(Interval(2.0) * m.sigma[i]);
    a[i][2 * n] = m.forcing[i] * m.amplitude;
  }
  IntervalMatrix W(p, std::vector<Interval>(p)), Winv;
  for (std::size_t r = 0; r < p; ++r)
    for (std::size_t k = 0; k < p; ++k) {
      const auto& cr = m.contacts[static_cast<std::size_t>(held[r])];
      const auto& ck = m.contacts[static_cast<std::size_t>(held[k])];
      for (std::size_t i = 0; i < n; ++i) W[r][k] += cr.shape[i] * ck.contact[i];
    }
  if (!InvertSmall(W, Winv)) {
    why = fmt::format("the contact matrix W of the held set {} is not proven invertible (dependent contacts)", held);
    return false;
  }
  // C_H a: row per held contact; λ = −W⁻¹ C_H a.
  IntervalMatrix Ca(p, std::vector<Interval>(N));
  for (std::size_t r = 0; r < p; ++r)
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = 0; k < N; ++k) Ca[r][k] += m.contacts[static_cast<std::size_t>(held[r])].shape[i] * a[i][k];
  out.force.assign(p, std::vector<Interval>(N));
  for (std::size_t r = 0; r < p; ++r)
    for (std::size_t q = 0; q < p; ++q)
      for (std::size_t k = 0; k < N; ++k) out.force[r][k] -= Winv[r][q] * Ca[q][k];
  auto& A = out.h.A;
  A.assign(N, std::vector<Interval>(N));
  for (std::size_t i = 0; i < n; ++i) {
    A[i][n + i] = 1.0;
    for (std::size_t k = 0; k < N; ++k) {
      Interval v = a[i][k];
      for (std::size_t r = 0; r < p; ++r) v += m.contacts[static_cast<std::size_t>(held[r])].contact[i] * out.force[r][k];
      A[n + i][k] = v;
    }
  }
  A[2 * n][2 * n + 1] = m.frequency;
  A[2 * n + 1][2 * n] = -m.frequency;
  out.rate.assign(p, std::vector<Interval>(N));
  for (std::size_t r = 0; r < p; ++r)
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t i = 0; i < N; ++i) out.rate[r][k] += out.force[r][i] * A[i][k];
  return true;
}

namespace {

struct Layout {
  int n, m;  // modes, segments
  std::size_t size() const { return static_cast<std::size_t>(m * (2 * n + 1)); }
  std::size_t t(int b) const { return static_cast<std::size_t>(b * (2 * n + 1)); }
  std::size_t x(int b, int i) const { return t(b) + 1 + static_cast<std::size_t>(i); }
  std::size_t v(int b, int i) const { return t(b) + 1 + static_cast<std::size_t>(n + i); }
};

template <class T>
std::vector<T> Part(const std::vector<T>& u, std::size_t from, int count) {
  return std::vector<T>(u.begin() + static_cast<std::ptrdiff_t>(from), u.begin() + static_cast<std::ptrdiff_t>(from) + count);
}

// γ_jᵀA^k for the gap of contact j (γ_j = (c_j, 0, 0, 0)), k = 0..3.
std::vector<Interval> GapRow(const IntervalModel& m, int j, const IntervalMatrix& A, int power) {
  const auto n = static_cast<std::size_t>(m.n), N = 2 * n + 2;
  std::vector<Interval> row(N);
  for (std::size_t i = 0; i < n; ++i) row[i] = m.contacts[static_cast<std::size_t>(j)].shape[i];
  for (int k = 0; k < power; ++k) {
    std::vector<Interval> next(N);
    for (std::size_t c = 0; c < N; ++c)
      for (std::size_t i = 0; i < N; ++i) next[c] += row[i] * A[i][c];
    row = std::move(next);
  }
  return row;
}

// P_Z = I − T_Z W_ZZ⁻¹ C_Z (n × n).
bool Projection(const IntervalModel& m, const std::vector<int>& Z, IntervalMatrix& P) {
  const auto n = static_cast<std::size_t>(m.n), p = Z.size();
  IntervalMatrix W(p, std::vector<Interval>(p)), Winv;
  for (std::size_t r = 0; r < p; ++r)
    for (std::size_t k = 0; k < p; ++k)
      for (std::size_t i = 0; i < n; ++i)
        W[r][k] += m.contacts[static_cast<std::size_t>(Z[r])].shape[i] * m.contacts[static_cast<std::size_t>(Z[k])].contact[i];
  if (!InvertSmall(W, Winv)) return false;
  P.assign(n, std::vector<Interval>(n));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t l = 0; l < n; ++l) {
      Interval s(i == l ? 1.0 : 0.0);
      for (std::size_t r = 0; r < p; ++r)
        for (std::size_t k = 0; k < p; ++k)
          s -= m.contacts[static_cast<std::size_t>(Z[r])].contact[i] * Winv[r][k] * m.contacts[static_cast<std::size_t>(Z[k])].shape[l];
      P[i][l] = s;
    }
  return true;
}

// The determinant of a small interval matrix (cofactor expansion).
Interval Det(const IntervalMatrix& a) {
  const std::size_t p = a.size();
  if (p == 0) return Interval(1.0);
  if (p == 1) return a[0][0];
  Interval d(0.0);
  for (std::size_t c = 0; c < p; ++c) {
    IntervalMatrix minor;
    for (std::size_t r = 1; r < p; ++r) {
      std::vector<Interval> row;
      for (std::size_t k = 0; k < p; ++k)
        if (k != c) row.push_back(a[r][k]);
      minor.push_back(row);
    }
    const Interval term = a[0][c] * Det(minor);
    d = c % 2 == 0 ? d + term : d - term;
  }
  return d;
}

// e^{As}z0 along a segment for the positivity tests, whose pieces come in order: from the start p of
// the current piece, e^{A(c − p)}(e^{Ap}z0), with e^{Ap}z0 enclosed directly (not stepped from piece to
// piece, which would widen it at every step) and the exponentials of the recurring differences (the
// pieces of one cut have equal widths) enclosed once. Each difference is an interval (c − p in Arb),
// so every enclosure holds for the exact time.
class Stepper {
 public:
  Stepper(const HeldFlow& h, std::vector<Interval> z0) : h_(h), z0_(std::move(z0)) {}
  Interval Value(const std::vector<Interval>& row, double c) {
    const double p = has_ && at_ <= c ? at_ : c;
    return Dot(row, MatVec(Exp(Interval(c) - Interval(p)), At(p)));
  }
  Interval Slope(const std::vector<Interval>& row, const Interval& I) {
    const double p = I.lo();
    return Dot(row, MatVec(Exp(I - Interval(p)), At(p)));
  }

 private:
  const IntervalMatrix& Exp(const Interval& s) {
    const auto key = std::make_pair(s.lo(), s.hi());
    auto it = cache_.find(key);
    if (it == cache_.end()) {
      if (cache_.size() > 4096) cache_.clear();
      it = cache_.emplace(key, HeldExp(h_, s)).first;
    }
    return it->second;
  }
  const std::vector<Interval>& At(double p) {
    if (!has_ || p != at_) {
      z_ = MatVec(HeldExp(h_, Interval(p)), z0_);
      at_ = p;
      has_ = true;
    }
    return z_;
  }
  const HeldFlow& h_;
  std::vector<Interval> z0_, z_;
  double at_ = 0;
  bool has_ = false;
  std::map<std::pair<double, double>, IntervalMatrix> cache_;
};

std::string SetText(const std::vector<int>& s) { return fmt::format("{{{}}}", fmt::join(s, ", ")); }

const char* const kSetNote =
    "sticking on the contacts held at the section collapses their displacements and velocities: the multipliers "
    "listed are those of the monodromy on the held subspace, its other multipliers are 0";

}  // namespace

Outcome ProveHeldSet(const IntervalModel& mdl, const HeldSetGuess& g, const ProofRequest& request, const Budget& budget) {
  Outcome out;
  Ledger ledger;
  const auto finish = [&](std::string reason) {
    out.reason = reason.empty() ? ledger.failed() : std::move(reason);
    out.certificate["inequalities"] = ledger.list();
    return out;
  };
  const int m = static_cast<int>(g.ends.size());
  const Layout L{mdl.n, m};
  const int q = g.period;
  const auto n = static_cast<std::size_t>(mdl.n);
  if (m < 2 || g.held.size() != g.ends.size() || g.times.size() != g.ends.size())
    return finish("the sticking orbit found is not a sequence of landings and releases the prover can follow");
  if (L.size() > kMaxUnknowns)
    return finish(fmt::format("{} events in {} period(s) and {} mode(s): {} unknowns, more than the {} the prover takes "
                              "(docs/prove.md \"Bounds\")", m, q, L.n, L.size(), kMaxUnknowns));
  // The sets: H_{k+1} from H_k and the event ending k; segment 0 starts at a release; every contact
  // held somewhere is landed somewhere (so the held constraints are equations of the zero).
  const auto next_set = [&](int k) {
    std::set<int> s(g.held[static_cast<std::size_t>(k)].begin(), g.held[static_cast<std::size_t>(k)].end());
    const auto& e = g.ends[static_cast<std::size_t>(k)];
    if (e.landing && e.sticks) s.insert(e.contact);
    if (!e.landing) s.erase(e.contact);
    return std::vector<int>(s.begin(), s.end());
  };
  std::set<int> landed, ever;
  for (int k = 0; k < m; ++k) {
    const auto& e = g.ends[static_cast<std::size_t>(k)];
    const auto& H = g.held[static_cast<std::size_t>(k)];
    const bool in = std::find(H.begin(), H.end(), e.contact) != H.end();
    if (next_set(k) != g.held[static_cast<std::size_t>((k + 1) % m)] || (e.landing == in))
      return finish("the sticking orbit found is not a consistent sequence of held sets (not proven by this version)");
    if (e.landing) landed.insert(e.contact);
    ever.insert(H.begin(), H.end());
    if (mdl.contacts[static_cast<std::size_t>(e.contact)].restitution.hi() > 0 && e.landing)
      return finish("a landing with r > 0 in a sticking orbit of several contacts (chattering) is not proven by this "
                    "version");
  }
  if (g.ends.back().landing) return finish("the sticking orbit found does not start at a release");
  for (int c : ever)
    if (!landed.count(c))
      return finish(fmt::format("contact {} is held through the whole period: a sticking orbit held on a contact that "
                                "never lands is not proven by this version", c));
  std::vector<SetFlow> flows(static_cast<std::size_t>(m));
  for (int k = 0; k < m; ++k) {
    std::string why;
    if (!MakeSetFlow(mdl, g.held[static_cast<std::size_t>(k)], flows[static_cast<std::size_t>(k)], why)) return finish(why);
  }
  std::vector<IntervalMatrix> proj(static_cast<std::size_t>(m));
  for (int k = 0; k < m; ++k) {
    const auto& e = g.ends[static_cast<std::size_t>(k)];
    if (!e.landing) continue;
    auto Z = g.held[static_cast<std::size_t>(k)];
    Z.push_back(e.contact);
    std::sort(Z.begin(), Z.end());
    if (!Projection(mdl, Z, proj[static_cast<std::size_t>(k)]))
      return finish(fmt::format("the contact matrix W of the contacts {} at landing {} is not proven invertible", SetText(Z), k));
  }
  const auto force_index = [&](int k, int c) {
    const auto& H = g.held[static_cast<std::size_t>(k)];
    return static_cast<std::size_t>(std::find(H.begin(), H.end(), c) - H.begin());
  };
  const Interval qT = Interval(q) * mdl.period;

  const auto residual = [&](const auto& u) {
    using T = std::decay_t<decltype(u[0])>;
    std::vector<T> res;
    for (int k = 0; k < m; ++k) {
      const auto ks = static_cast<std::size_t>(k);
      const int k1 = (k + 1) % m;
      const T& t = u[L.t(k)];
      const T tn = k + 1 < m ? u[L.t(k + 1)] : u[L.t(0)] + T(qT);
      const auto z0 = HeldState(mdl, t, Part(u, L.x(k, 0), L.n), Part(u, L.v(k, 0), L.n));
      const auto z = HeldAdvance(flows[ks].h, z0, tn - t);
      const auto& e = g.ends[ks];
      std::vector<T> Ve(z.begin() + static_cast<std::ptrdiff_t>(n), z.begin() + static_cast<std::ptrdiff_t>(2 * n));
      if (e.landing) {
        res.push_back(ContactSum(mdl, std::vector<T>(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(n)), e.contact) -
                      T(mdl.contacts[static_cast<std::size_t>(e.contact)].stop));
        std::vector<T> Vp(n, T(0.0));
        for (std::size_t i = 0; i < n; ++i)
          for (std::size_t l = 0; l < n; ++l) Vp[i] = Vp[i] + T(proj[ks][i][l]) * Ve[l];
        Ve = Vp;
      } else {
        res.push_back(Dot(flows[ks].force[force_index(k, e.contact)], z));
      }
      for (int i = 0; i < L.n; ++i) res.push_back(z[static_cast<std::size_t>(i)] - u[L.x(k1, i)]);
      for (int i = 0; i < L.n; ++i) res.push_back(Ve[static_cast<std::size_t>(i)] - u[L.v(k1, i)]);
    }
    return res;
  };

  std::vector<std::string> names;
  std::vector<double> u0;
  for (int b = 0; b < m; ++b) {
    const auto bs = static_cast<std::size_t>(b);
    names.push_back(fmt::format("t_{}", b));
    u0.push_back(g.times[bs]);
    for (int i = 0; i < L.n; ++i) {
      names.push_back(fmt::format("X_{}[{}]", b, i));
      u0.push_back(g.X[bs](i));
    }
    for (int i = 0; i < L.n; ++i) {
      names.push_back(fmt::format("V_{}[{}]", b, i));
      u0.push_back(g.V[bs](i));
    }
  }
  const auto u = NewtonRefine(residual, u0);

  // 1. Existence and uniqueness in the box.
  KrawczykBox kb;
  double radius = request.box_radius;
  for (int attempt = 0; attempt < 4; ++attempt, radius *= 4) {
    kb = KrawczykTest(residual, u, radius);
    if (kb.inside || budget.passed()) break;
  }
  Json krawczyk = Json::array(), box = Json::array(), C = Json::array();
  for (std::size_t p = 0; p < u.size(); ++p) {
    krawczyk.push_back(Pair(kb.K[p]));
    ledger.Check(kb.K[p].InsideOpen(kb.lo[p], kb.hi[p]), "krawczyk", names[p], kb.K[p], "inside the box");
    box.push_back({kb.lo[p], kb.hi[p]});
    Json row = Json::array();
    for (std::size_t l = 0; l < u.size(); ++l) row.push_back(kb.C(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(l)));
    C.push_back(row);
  }
  out.certificate["unknowns"] = names;
  out.certificate["midpoint"] = u;
  out.certificate["box"] = box;
  out.certificate["preconditioner"] = C;
  out.certificate["krawczyk"] = krawczyk;
  if (!kb.inside)
    return finish(fmt::format("Krawczyk's test fails: K(U) is not inside the box U for {} (box half-width {:.1e} "
                              "relative): no unique sticking orbit with this sequence of held sets is proven near the "
                              "orbit found", names[kb.worst], radius / 4));
  std::vector<Interval> U;
  for (std::size_t p = 0; p < u.size(); ++p) U.push_back(Interval::Hull(kb.lo[p], kb.hi[p]));

  // The coupling: W_ZZ a P-matrix at every landing, the held contacts' impulses ≥ 0.
  Json coupling = {{"source", g.coupling_source}};
  {
    Json Wj = Json::array();
    for (const auto& row : g.coupling) {
      Json r = Json::array();
      for (const auto& x : row) r.push_back(Pair(x));
      Wj.push_back(r);
    }
    coupling["W"] = Wj;
  }
  out.certificate["coupling"] = coupling;

  double top = mdl.frequency.hi();
  for (const auto& w : mdl.omega) top = std::max(top, w.hi());
  const double step = 0.25 / top;
  IntervalMatrix Mono(2 * n, std::vector<Interval>(2 * n));
  for (std::size_t i = 0; i < 2 * n; ++i) Mono[i][i] = 1.0;
  Json segments = Json::array(), events = Json::array(), sequence = Json::array();
  const int first = g.ends.back().contact;
  const Interval t0 = U[L.t(0)];
  events.push_back({{"kind", "release"}, {"contact", first}, {"time", Pair(t0)}, {"phase", Pair(Phase(mdl, t0))}, {"velocity_before", {0.0, 0.0}}});
  sequence.push_back("release");

  for (int k = 0; k < m; ++k) {
    const auto ks = static_cast<std::size_t>(k);
    const auto& F = flows[ks];
    const auto& e = g.ends[ks];
    const auto& prev = g.ends[static_cast<std::size_t>((k + m - 1) % m)];
    const std::string seg = fmt::format("segment {}", k);
    const Interval t = U[L.t(k)];
    const Interval tn = k + 1 < m ? U[L.t(k + 1)] : U[L.t(0)] + qT;
    const Interval S = tn - t;
    const auto z0 = HeldState(mdl, t, Part(U, L.x(k, 0), L.n), Part(U, L.v(k, 0), L.n));
    Json sj = {{"held", g.held[ks]}, {"end", e.landing ? "landing" : "release"}, {"contact", e.contact}, {"duration", Pair(S)}};
    if (e.landing) sj["sticks"] = e.sticks;
    if (!ledger.Check(S.Positive(), "duration", seg, S, "> 0")) return finish("");
    const auto zS = HeldAdvance(F.h, z0, S);
    const auto at = [&](const std::vector<Interval>& row, const Interval& s) { return Dot(row, HeldAdvance(F.h, z0, s)); };
    // An end window [S_lo − w, S_hi] over which `rate` has the sign `negative`.
    const auto end_window = [&](const std::vector<Interval>& rate_row, double& w, Interval& r) {
      w = std::min(0.1 / top, 0.25 * S.lo());
      for (int it = 0; it < 16; ++it, w /= 2) {
        r = at(rate_row, Interval::Hull(S.lo() - w, S.hi()));
        if (r.Negative()) return true;
      }
      return false;
    };
    // The forces of the held contacts.
    Json forces = Json::array();
    for (std::size_t r = 0; r < F.held.size(); ++r) {
      const int h = F.held[r];
      const std::string where = fmt::format("{}, force of contact {}", seg, h);
      Json fj = {{"contact", h}};
      double hi_s = S.hi();
      if (!e.landing && e.contact == h) {
        double w = 0;
        Interval rate;
        const bool ok = end_window(F.rate[r], w, rate);
        if (!ledger.Check(ok, "force rate over the end window", where, rate, "< 0"))
          return finish(ledger.failed() + " (the force is not proven to fall through 0 at the release)");
        fj["end_window"] = w;
        hi_s = S.hi() - 0.9 * w;
      } else {
        fj["end_window"] = 0.0;
      }
      Json pieces = Json::array();
      if (0 < hi_s) {
        Stepper st(F.h, z0);
        const auto pos = ProvePositive(0.0, hi_s, step, request.max_depth, budget,
                                       [&](double s) { return st.Value(F.force[r], s); },
                                       [&](const Interval& s) { return st.Slope(F.rate[r], s); });
        if (!pos.proven) {
          ledger.Check(false, "force", fmt::format("{} at s = {:.17g}", where, pos.failed_at), pos.failed_value, "> 0");
          return finish(fmt::format("the force of held contact {} is not proven positive on {}: {}", h, seg, pos.reason));
        }
        for (const auto& [lo, hi] : pos.pieces) pieces.push_back({lo, hi});
      }
      fj["pieces"] = pieces;
      forces.push_back(fj);
    }
    sj["forces"] = forces;
    // Every other gap.
    Json gaps = Json::array();
    for (int j = 0; j < mdl.contact_count(); ++j) {
      if (std::find(F.held.begin(), F.held.end(), j) != F.held.end()) continue;
      const std::string where = fmt::format("{}, gap of contact {}", seg, j);
      const Interval ej = mdl.contacts[static_cast<std::size_t>(j)].stop;
      const auto g0 = GapRow(mdl, j, F.h.A, 0), g1 = GapRow(mdl, j, F.h.A, 1);
      Json gj = {{"contact", j}};
      double lo_s = 0, hi_s = S.hi();
      std::string start = "open";
      if (prev.contact == j && (!prev.landing || !prev.sticks)) {
        // From a release (g = g' = g'' = 0: g''' > 0) or a departure (g = g' = 0: g'' > 0).
        start = prev.landing ? "departure" : "release";
        const int order = prev.landing ? 2 : 3;
        const auto gk = GapRow(mdl, j, F.h.A, order);
        double w = std::min(0.1 / top, 0.25 * S.lo());
        Interval d;
        bool ok = false;
        for (int it = 0; it < 16 && !ok; ++it) {
          d = at(gk, Interval::Hull(0.0, w));
          ok = d.Positive();
          if (!ok) w /= 2;
        }
        if (!ledger.Check(ok, order == 3 ? "third derivative of the gap over the start window"
                                          : "second derivative of the gap over the start window",
                          where, d, "> 0"))
          return finish(ledger.failed() + (order == 3 ? " (the released contact is not proven to leave its stop)"
                                                      : " (the departing contact is not proven to leave its stop)"));
        gj["start_window"] = w;
        lo_s = w;
      } else {
        gj["start_window"] = 0.0;
      }
      gj["start"] = start;
      if (e.landing && e.contact == j) {
        double w = 0;
        Interval rate;
        const bool ok = end_window(g1, w, rate);
        if (!ledger.Check(ok, "gap velocity over the end window", where, rate, "< 0"))
          return finish(ledger.failed() + " (the landing is not proven transversal)");
        gj["end_window"] = w;
        hi_s = S.hi() - 0.9 * w;
      } else {
        gj["end_window"] = 0.0;
      }
      Json pieces = Json::array();
      if (lo_s < hi_s) {
        Stepper st(F.h, z0);
        const auto pos = ProvePositive(lo_s, hi_s, step, request.max_depth, budget,
                                       [&](double s) { return st.Value(g0, s) - ej; },
                                       [&](const Interval& s) { return st.Slope(g1, s); });
        if (!pos.proven) {
          ledger.Check(false, "gap", fmt::format("{} at s = {:.17g}", where, pos.failed_at), pos.failed_value, "> 0");
          return finish(fmt::format("the gap of contact {} is not proven positive on {}: {} (a grazing or a missed "
                                    "contact?)", j, seg, pos.reason));
        }
        for (const auto& [lo, hi] : pos.pieces) pieces.push_back({lo, hi});
      }
      gj["pieces"] = pieces;
      gaps.push_back(gj);
    }
    sj["gaps"] = gaps;

    // The event at the end, and the monodromy through the segment.
    const IntervalMatrix E = HeldExp(F.h, S);
    IntervalMatrix Eb(2 * n, std::vector<Interval>(2 * n));
    for (std::size_t i = 0; i < 2 * n; ++i)
      for (std::size_t l = 0; l < 2 * n; ++l) Eb[i][l] = E[i][l];
    Mono = MatMul(Eb, Mono);
    if (k == m - 1) {
      segments.push_back(sj);
      break;  // the release at t_0 + qT: the section
    }
    if (e.landing) {
      const std::string land = fmt::format("landing at the end of segment {}", k);
      const std::vector<Interval> Xe(zS.begin(), zS.begin() + static_cast<std::ptrdiff_t>(n)),
          Ve(zS.begin() + static_cast<std::ptrdiff_t>(n), zS.begin() + static_cast<std::ptrdiff_t>(2 * n));
      const Interval vminus = ContactSum(mdl, Ve, e.contact);
      if (!ledger.Check(vminus.Negative(), "contact velocity before impact", land, vminus, "< 0")) return finish("");
      sj["velocity_before"] = Pair(vminus);
      // The coupling matrix of Z = H ∪ {j}: every principal minor > 0; the held contacts' impulses.
      auto Z = g.held[ks];
      Z.push_back(e.contact);
      std::sort(Z.begin(), Z.end());
      const std::size_t p = Z.size();
      for (unsigned mask = 1; mask < (1u << p); ++mask) {
        std::vector<int> sub;
        for (std::size_t r = 0; r < p; ++r)
          if (mask & (1u << r)) sub.push_back(Z[r]);
        if (sub.size() < 2) continue;
        IntervalMatrix Ws;
        for (int a : sub) {
          std::vector<Interval> row;
          for (int b : sub) row.push_back(g.coupling[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)]);
          Ws.push_back(row);
        }
        const Interval d = Det(Ws);
        if (!ledger.Check(d.Positive(), "principal minor of W", fmt::format("{}, contacts {}", land, SetText(sub)), d, "> 0"))
          return finish(ledger.failed() + " (the contact laws at the landing may have several solutions)");
      }
      Json impulses = Json::array();
      if (p > 1) {
        IntervalMatrix Wz(p, std::vector<Interval>(p)), Wi;
        for (std::size_t r = 0; r < p; ++r)
          for (std::size_t c = 0; c < p; ++c) Wz[r][c] = g.coupling[static_cast<std::size_t>(Z[r])][static_cast<std::size_t>(Z[c])];
        if (!InvertSmall(Wz, Wi)) return finish(fmt::format("the coupling of the contacts {} is not proven invertible", SetText(Z)));
        const auto jz = static_cast<std::size_t>(std::find(Z.begin(), Z.end(), e.contact) - Z.begin());
        for (std::size_t r = 0; r < p; ++r) {
          if (r == jz) continue;
          // P_h = −(W⁻¹)_{hj} ġ_j⁻ ≥ 0 with ġ_j⁻ < 0: (W⁻¹)_{hj} ≥ 0.
          const Interval x = Wi[r][jz];
          if (!ledger.Check(x.lo() >= 0, "impulse per unit speed", fmt::format("{}, contact {}", land, Z[r]), x, ">= 0"))
            return finish(ledger.failed() + " (a held contact may be pushed off its stop by the landing: not proven by "
                                            "this version)");
          impulses.push_back({{"contact", Z[r]}, {"value", Pair(x)}});
        }
      }
      sj["impulses"] = impulses;
      // Saltation: S = Dg + (f⁺ − Dg f⁻)∇hᵀ/(∇h·f⁻), Dg = diag(I, P_Z), ∇h = (c_j, 0).
      const auto& Pz = proj[ks];
      const auto& Fn = flows[static_cast<std::size_t>(k + 1)];
      std::vector<Interval> zp = zS;
      for (std::size_t i = 0; i < n; ++i) {
        Interval s(0.0);
        for (std::size_t l = 0; l < n; ++l) s += Pz[i][l] * Ve[l];
        zp[n + i] = s;
      }
      const auto fm = MatVec(F.h.A, zS), fp = MatVec(Fn.h.A, zp);
      std::vector<Interval> jump(2 * n);
      for (std::size_t i = 0; i < n; ++i) {
        jump[i] = fp[i] - fm[i];
        Interval s(0.0);
        for (std::size_t l = 0; l < n; ++l) s += Pz[i][l] * fm[n + l];
        jump[n + i] = fp[n + i] - s;
      }
      IntervalMatrix Sal(2 * n, std::vector<Interval>(2 * n));
      for (std::size_t i = 0; i < n; ++i) {
        Sal[i][i] = 1.0;
        for (std::size_t l = 0; l < n; ++l) Sal[n + i][n + l] = Pz[i][l];
      }
      const auto& cj = mdl.contacts[static_cast<std::size_t>(e.contact)].shape;
      for (std::size_t i = 0; i < 2 * n; ++i)
        for (std::size_t l = 0; l < n; ++l) Sal[i][l] += jump[i] * cj[l] / vminus;
      Mono = MatMul(Sal, Mono);
      events.push_back({{"kind", "impact"}, {"contact", e.contact}, {"time", Pair(tn)}, {"phase", Pair(Phase(mdl, tn))}, {"velocity_before", Pair(vminus)}});
      sequence.push_back("impact");
      if (e.sticks) {
        events.push_back({{"kind", "stick"}, {"contact", e.contact}, {"time", Pair(tn)}, {"phase", Pair(Phase(mdl, tn))}, {"velocity_before", Pair(vminus)}});
        sequence.push_back("stick");
      } else {
        events.push_back({{"kind", "departure"}, {"contact", e.contact}, {"time", Pair(tn)}, {"phase", Pair(Phase(mdl, tn))}, {"velocity_before", {0.0, 0.0}}});
        sequence.push_back("departure");
      }
    } else {
      events.push_back({{"kind", "release"}, {"contact", e.contact}, {"time", Pair(tn)}, {"phase", Pair(Phase(mdl, tn))}, {"velocity_before", {0.0, 0.0}}});
      sequence.push_back("release");
    }
    segments.push_back(sj);
  }
  out.certificate["segments"] = segments;
  if (request.period > 0 && request.period % q != 0)
    return finish(fmt::format("the sticking orbit through the release has period {}, which does not divide {}", q,
                              request.period));

  // The least period: for every prime ℓ dividing q, the segments shifted by m/ℓ differ.
  for (int ell = 2, rest = q; ell <= rest; ++ell) {
    if (rest % ell) continue;
    while (rest % ell == 0) rest /= ell;
    if (m % ell) continue;
    const int h = m / ell;
    bool apart = false;
    for (int k = 0; k < m && !apart; ++k) {
      const int k2 = (k + h) % m;
      const auto &a = g.ends[static_cast<std::size_t>(k)], &b = g.ends[static_cast<std::size_t>(k2)];
      if (a.landing != b.landing || a.contact != b.contact || a.sticks != b.sticks ||
          g.held[static_cast<std::size_t>(k)] != g.held[static_cast<std::size_t>(k2)]) {
        apart = true;
        break;
      }
      const Interval dt = U[L.t(k2)] + (k + h >= m ? qT : Interval(0.0)) - U[L.t(k)] - Interval(q / ell) * mdl.period;
      apart = dt.Positive() || dt.Negative();
      for (int i = 0; i < L.n && !apart; ++i) {
        const Interval dx = U[L.x(k2, i)] - U[L.x(k, i)], dv = U[L.v(k2, i)] - U[L.v(k, i)];
        apart = dx.Positive() || dx.Negative() || dv.Positive() || dv.Negative();
      }
    }
    if (!apart) return finish(fmt::format("the orbit found repeats after {} period(s): not proven at period {}", q / ell, q));
  }

  // The multipliers: the monodromy maps into the subspace held at the section (the set held before
  // the release at t_0), {C_P δX = 0, C_P δẊ = 0}; its restriction there, in the coordinates of the
  // modes other than |P| pivots.
  auto P = g.held.back();
  const std::size_t pp = P.size();
  std::vector<std::size_t> piv;
  {
    Eigen::MatrixXd Cm(static_cast<Eigen::Index>(pp), static_cast<Eigen::Index>(n));
    for (std::size_t r = 0; r < pp; ++r)
      for (std::size_t i = 0; i < n; ++i)
        Cm(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(i)) = mdl.contacts[static_cast<std::size_t>(P[r])].shape[i].mid();
    for (std::size_t r = 0; r < pp; ++r) {  // greedy pivots by elimination on the midpoints
      Eigen::Index best = -1;
      double big = 0;
      for (Eigen::Index i = 0; i < Cm.cols(); ++i) {
        if (std::find(piv.begin(), piv.end(), static_cast<std::size_t>(i)) != piv.end()) continue;
        if (std::abs(Cm(static_cast<Eigen::Index>(r), i)) > big) {
          big = std::abs(Cm(static_cast<Eigen::Index>(r), i));
          best = i;
        }
      }
      if (best < 0) return finish("the held contacts at the section are dependent");
      piv.push_back(static_cast<std::size_t>(best));
      for (std::size_t r2 = r + 1; r2 < pp; ++r2)
        Cm.row(static_cast<Eigen::Index>(r2)) -= Cm(static_cast<Eigen::Index>(r2), best) / Cm(static_cast<Eigen::Index>(r), best) * Cm.row(static_cast<Eigen::Index>(r));
    }
  }
  IntervalMatrix Cp(pp, std::vector<Interval>(pp)), Cpi;
  for (std::size_t r = 0; r < pp; ++r)
    for (std::size_t c = 0; c < pp; ++c) Cp[r][c] = mdl.contacts[static_cast<std::size_t>(P[r])].shape[piv[c]];
  if (!InvertSmall(Cp, Cpi)) return finish("the held contacts at the section are not proven independent");
  std::vector<std::size_t> free_modes;
  for (std::size_t i = 0; i < n; ++i)
    if (std::find(piv.begin(), piv.end(), i) == piv.end()) free_modes.push_back(i);
  std::vector<std::size_t> keep;
  for (std::size_t blk = 0; blk < 2; ++blk)
    for (std::size_t i : free_modes) keep.push_back(blk * n + i);
  IntervalMatrix B(2 * n, std::vector<Interval>(keep.size()));
  for (std::size_t col = 0; col < keep.size(); ++col) {
    const std::size_t pcol = keep[col], blk = pcol / n, i = pcol % n;
    B[pcol][col] = 1.0;
    // The pivot components y solve C_P[:, piv] y = −C_P[:, i].
    for (std::size_t a = 0; a < pp; ++a) {
      Interval y(0.0);
      for (std::size_t r = 0; r < pp; ++r) y -= Cpi[a][r] * mdl.contacts[static_cast<std::size_t>(P[r])].shape[i];
      B[blk * n + piv[a]][col] = y;
    }
  }
  const auto MB = MatMul(Mono, B);
  IntervalMatrix Mr(keep.size(), std::vector<Interval>(keep.size()));
  for (std::size_t r = 0; r < keep.size(); ++r)
    for (std::size_t col = 0; col < keep.size(); ++col) Mr[r][col] = MB[keep[r]][col];
  Spectrum spectrum;
  if (keep.empty()) {
    spectrum.enclosed = true;
    spectrum.stability = "stable";
  } else {
    spectrum = Multipliers(Mr);
  }
  Json monodromy = Json::array();
  for (const auto& row : Mono) {
    Json r = Json::array();
    for (const auto& x : row) r.push_back(Pair(x));
    monodromy.push_back(r);
  }
  out.certificate["monodromy"] = monodromy;
  out.certificate["inequalities"] = ledger.list();

  Json Xs = Json::array(), Vs = Json::array();
  for (int i = 0; i < L.n; ++i) {
    Xs.push_back(Pair(U[L.x(0, i)]));
    Vs.push_back(Pair(U[L.v(0, i)]));
  }
  double width = 0;
  for (std::size_t p = 0; p < u.size(); ++p) width = std::max(width, kb.hi[p] - kb.lo[p]);
  int landings = 0, releases = 0;
  for (const auto& e : g.ends) (e.landing ? landings : releases) += 1;
  out.summary["period"] = q;
  out.summary["sequence"] = sequence;
  out.summary["events"] = events;
  out.summary["section"] = {{"time", Pair(t0)}, {"X", Xs}, {"V", Vs}, {"at", "the release"}};
  out.summary["multipliers"] = spectrum.multipliers;
  out.summary["stability"] = spectrum.stability;
  out.summary["stability_note"] = spectrum.note.empty() ? std::string(kSetNote) : spectrum.note;
  out.summary["box_width"] = width;
  out.proven = true;
  out.reason = fmt::format("exactly one period-{} sticking orbit of {} modes held on sets of contacts through the "
                           "release of contact {} in a box of width {:.1e} (Krawczyk): {} segments, {} plastic "
                           "landing(s) and {} release(s), every held force > 0 and every other gap > 0 between them",
                           q, L.n, first, width, m, landings, releases);
  if (request.period > q) StateLeastPeriod(out, request.period);
  return out;
}

}  // namespace vibro::proof
