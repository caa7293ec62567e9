// Proof of a sticking orbit of several modes held on contact 0 with plastic landings, r = 0
// (proof_common.hpp, docs/prove.md "Sticking orbits of several modes").
//
// Unknowns: block 0 = (t_r, X_r, V_r), the release and the modal state there; block j = 1..m =
// (t_j, X_j, V_j), landing j and the state just after its plastic impact. Equations
// ((m + 1)(2n + 1) in as many unknowns), with the closed-form flight (eqs (13)-(14)), the plastic
// impact (eqs (10)-(12) with r = 0) and the held flow Z(t0 + s) = e^{As}Z(t0) (held_flow.hpp):
//   cᵀX(t_{j+1}⁻; block j) − x0 = 0,  X(t_{j+1}⁻) − X_{j+1} = 0,  Impact(Ẋ(t_{j+1}⁻)) − V_{j+1} = 0
//   (X, V)(t_r + qT; held from block m) − (X_r, V_r) = 0,   R(t_r, X_r, V_r) = 0.
// At a zero, cᵀX = x0 and cᵀẊ = 0 at every landing and at the release (the held flow keeps both), so
// the gap of the flight from the release starts with g = g' = g'' = 0 (R = 0), g''' > 0, and the
// flight from a departure (R < 0 at its landing) with g = g' = 0, g'' = −s_B R > 0. Krawczyk's test
// proves one zero in the box; then, over the box: every gap positive between its start and its
// landing (windows at both ends, subdivision between), every landing transversal, R < 0 at each
// landing but the last (departure), R > 0 at the last and over the whole held phase up to a window
// before the release where Ṙ < 0 (so R > 0 until it vanishes there). The monodromy is the product
// of the flights, the saltation matrices of the landings and the held flow; sticking collapses
// (x_B, ẋ_B), so it has rank 2n − 2 and its other multipliers are those of its restriction to the
// held subspace {cᵀδX = 0, cᵀδẊ = 0}.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "proof/held_flow.hpp"
#include "proof/krawczyk.hpp"
#include "proof/proof_common.hpp"

namespace vibro::proof {
namespace {

struct Layout {
  int n, m;  // modes, landings
  std::size_t size() const { return static_cast<std::size_t>((m + 1) * (2 * n + 1)); }
  std::size_t t(int b) const { return static_cast<std::size_t>(b * (2 * n + 1)); }
  std::size_t x(int b, int i) const { return t(b) + 1 + static_cast<std::size_t>(i); }
  std::size_t v(int b, int i) const { return t(b) + 1 + static_cast<std::size_t>(n + i); }
};

template <class T>
std::vector<T> Part(const std::vector<T>& u, std::size_t from, int count) {
  return std::vector<T>(u.begin() + static_cast<std::ptrdiff_t>(from), u.begin() + static_cast<std::ptrdiff_t>(from) + count);
}

template <class T>
std::vector<T> Residual(const IntervalModel& mdl, const HeldFlow& h, const Layout& L, int q, const std::vector<T>& u) {
  std::vector<T> res;
  const T stop(mdl.stop);
  for (int j = 0; j < L.m; ++j) {
    const T& t = u[L.t(j)];
    const auto e = Flight(mdl, t, Part(u, L.x(j, 0), L.n), Part(u, L.v(j, 0), L.n), u[L.t(j + 1)] - t);
    const auto Vp = Impact(mdl, e.V, 0);
    res.push_back(ContactSum(mdl, e.X) - stop);
    for (int i = 0; i < L.n; ++i) res.push_back(e.X[static_cast<std::size_t>(i)] - u[L.x(j + 1, i)]);
    for (int i = 0; i < L.n; ++i) res.push_back(Vp[static_cast<std::size_t>(i)] - u[L.v(j + 1, i)]);
  }
  const T qT(Interval(q) * mdl.period);
  const auto z0 = HeldState(mdl, u[L.t(L.m)], Part(u, L.x(L.m, 0), L.n), Part(u, L.v(L.m, 0), L.n));
  const auto z = HeldAdvance(h, z0, u[L.t(0)] + qT - u[L.t(L.m)]);
  for (int i = 0; i < L.n; ++i) res.push_back(z[static_cast<std::size_t>(i)] - u[L.x(0, i)]);
  for (int i = 0; i < L.n; ++i) res.push_back(z[static_cast<std::size_t>(L.n + i)] - u[L.v(0, i)]);
  res.push_back(Dot(h.reaction, HeldState(mdl, u[L.t(0)], Part(u, L.x(0, 0), L.n), Part(u, L.v(0, 0), L.n))));
  return res;
}

// d/dt of the free acceleration: −Ω²Ẋ − DẌ + T_A f ω cos ωt.
std::vector<Interval> Jerk(const IntervalModel& mdl, const Interval& t, const std::vector<Interval>& X,
                           const std::vector<Interval>& V) {
  const auto acc = Acceleration(mdl, t, X, V);
  const Interval drive = mdl.amplitude * mdl.frequency * Cos(mdl.frequency * t);
  std::vector<Interval> out;
  for (std::size_t i = 0; i < X.size(); ++i) {
    Interval ji = mdl.forcing[i] * drive - Sqr(mdl.omega[i]) * V[i];
    if (mdl.damped()) ji -= Interval(2.0) * mdl.sigma[i] * acc[i];
    out.push_back(ji);
  }
  return out;
}

// ∂(X, V)(t + S)/∂(X, V)(t) of a free flight (forward differentiation of the closed form).
IntervalMatrix FlightMatrix(const IntervalModel& mdl, const Interval& t, const std::vector<Interval>& X,
                            const std::vector<Interval>& V, const Interval& S) {
  const auto n = static_cast<std::size_t>(mdl.n);
  std::vector<Dual> Xd, Vd;
  for (std::size_t i = 0; i < n; ++i) {
    Xd.push_back(Dual::Variable(X[i], i, 2 * n));
    Vd.push_back(Dual::Variable(V[i], n + i, 2 * n));
  }
  const auto e = Flight(mdl, Dual(t), Xd, Vd, Dual(S));
  IntervalMatrix Phi(2 * n, std::vector<Interval>(2 * n));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t l = 0; l < 2 * n; ++l) {
      if (l < e.X[i].d.size()) Phi[i][l] = e.X[i].d[l];
      if (l < e.V[i].d.size()) Phi[n + i][l] = e.V[i].d[l];
    }
  return Phi;
}

// The saltation matrix of a plastic landing, S = Dg + (f⁺ − Dg f⁻)∇hᵀ/(∇h·f⁻), Dg = diag(I, Π),
// ∇h = (c, 0), f⁻ = (Ẋ⁻, a(Ẋ⁻)); f⁺ = (ΠẊ⁻, Π a(ΠẊ⁻)) into sticking, (ΠẊ⁻, a(ΠẊ⁻)) departing.
IntervalMatrix PlasticSaltation(const IntervalModel& mdl, const Interval& t, const std::vector<Interval>& X,
                                const std::vector<Interval>& Vm, const Interval& vminus, bool sticks) {
  const auto n = static_cast<std::size_t>(mdl.n);
  const auto& hit = mdl.contacts[0];
  IntervalMatrix Pi(n, std::vector<Interval>(n)), S(2 * n, std::vector<Interval>(2 * n));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t l = 0; l < n; ++l) Pi[i][l] = Interval(i == l ? 1.0 : 0.0) - hit.contact[i] * hit.shape[l] / hit.W;
  const auto Vp = MatVec(Pi, Vm);
  const auto am = Acceleration(mdl, t, X, Vm);
  auto ap = Acceleration(mdl, t, X, Vp);
  if (sticks) ap = MatVec(Pi, ap);
  const auto Piam = MatVec(Pi, am);
  std::vector<Interval> jump(2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    jump[i] = Vp[i] - Vm[i];
    jump[n + i] = ap[i] - Piam[i];
  }
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t l = 0; l < n; ++l) {
      S[i][l] = Interval(i == l ? 1.0 : 0.0);
      S[n + i][n + l] = Pi[i][l];
    }
  for (std::size_t i = 0; i < 2 * n; ++i)
    for (std::size_t l = 0; l < n; ++l) S[i][l] += jump[i] * hit.shape[l] / vminus;
  return S;
}

const char* const kHeldNote =
    "sticking collapses the contact's displacement and velocity: the monodromy has rank 2n - 2, its two other "
    "multipliers are 0";

}  // namespace

Outcome ProveStickingModes(const IntervalModel& mdl, const StickingGuess& guess, const ProofRequest& request,
                           const Budget& budget) {
  Outcome out;
  Ledger ledger;
  const auto finish = [&](std::string reason) {
    out.reason = reason.empty() ? ledger.failed() : std::move(reason);
    out.certificate["inequalities"] = ledger.list();
    return out;
  };
  const Layout L{mdl.n, static_cast<int>(guess.landing_times.size())};
  const int q = guess.period;
  if (L.size() > kMaxUnknowns)
    return finish(fmt::format("{} landings in {} period(s) and {} mode(s): {} unknowns, more than the {} the prover "
                              "takes (docs/prove.md \"Bounds\")", L.m, q, L.n, L.size(), kMaxUnknowns));
  const HeldFlow h = MakeHeldFlow(mdl);
  std::vector<std::string> names;
  std::vector<double> u0;
  for (int b = 0; b <= L.m; ++b) {
    const double t = b == 0 ? guess.release_time : guess.landing_times[static_cast<std::size_t>(b - 1)];
    const Eigen::VectorXd& X = b == 0 ? guess.X_release : guess.X[static_cast<std::size_t>(b - 1)];
    const Eigen::VectorXd& V = b == 0 ? guess.V_release : guess.V[static_cast<std::size_t>(b - 1)];
    names.push_back(fmt::format("t_{}", b));
    u0.push_back(t);
    for (int i = 0; i < L.n; ++i) {
      names.push_back(fmt::format("X_{}[{}]", b, i));
      u0.push_back(X(i));
    }
    for (int i = 0; i < L.n; ++i) {
      names.push_back(fmt::format("V_{}[{}]", b, i));
      u0.push_back(V(i));
    }
  }
  const auto residual = [&](const auto& u) { return Residual(mdl, h, L, q, u); };
  const auto u = NewtonRefine(residual, u0);

  // 1. Existence and uniqueness in the box.
  KrawczykBox k;
  double radius = request.box_radius;
  for (int attempt = 0; attempt < 4; ++attempt, radius *= 4) {
    k = KrawczykTest(residual, u, radius);
    if (k.inside || budget.passed()) break;
  }
  Json krawczyk = Json::array(), box = Json::array(), C = Json::array();
  for (std::size_t p = 0; p < u.size(); ++p) {
    krawczyk.push_back(Pair(k.K[p]));
    ledger.Check(k.K[p].InsideOpen(k.lo[p], k.hi[p]), "krawczyk", names[p], k.K[p], "inside the box");
    box.push_back({k.lo[p], k.hi[p]});
    Json row = Json::array();
    for (std::size_t l = 0; l < u.size(); ++l) row.push_back(k.C(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(l)));
    C.push_back(row);
  }
  out.certificate["unknowns"] = names;
  out.certificate["midpoint"] = u;
  out.certificate["box"] = box;
  out.certificate["preconditioner"] = C;
  out.certificate["krawczyk"] = krawczyk;
  if (!k.inside)
    return finish(fmt::format("Krawczyk's test fails: K(U) is not inside the box U for {} (box half-width {:.1e} "
                              "relative): no unique sticking orbit with this sequence is proven near the orbit found",
                              names[k.worst], radius / 4));
  std::vector<Interval> U;
  for (std::size_t p = 0; p < u.size(); ++p) U.push_back(Interval::Hull(k.lo[p], k.hi[p]));
  const auto X_of = [&](int b) { return Part(U, L.x(b, 0), L.n); };
  const auto V_of = [&](int b) { return Part(U, L.v(b, 0), L.n); };

  double top = mdl.frequency.hi();
  for (const auto& w : mdl.omega) top = std::max(top, w.hi());
  const double step = 0.25 / top;
  const Interval qT = Interval(q) * mdl.period;
  const auto n = static_cast<std::size_t>(L.n);

  // 2. The release: R falls through 0.
  const Interval& tr = U[L.t(0)];
  const Interval rate = Dot(h.reaction_rate, HeldState(mdl, tr, X_of(0), V_of(0)));
  if (!ledger.Check(rate.Negative(), "reaction rate", "release", rate, "< 0")) return finish("");
  out.certificate["release"] = {{"reaction_rate", Pair(rate)}};

  // 3. The flights, each from the release or a departure to a plastic landing.
  Json flights = Json::array(), events = Json::array(), sequence = Json::array({"release"});
  events.push_back({{"kind", "release"}, {"contact", 0}, {"time", Pair(tr)}, {"phase", Pair(Phase(mdl, tr))}, {"velocity_before", {0.0, 0.0}}});
  IntervalMatrix M(2 * n, std::vector<Interval>(2 * n));
  for (std::size_t i = 0; i < 2 * n; ++i) M[i][i] = 1.0;
  for (int j = 0; j < L.m; ++j) {
    const std::string fl = fmt::format("flight {}", j), land = fmt::format("landing {}", j + 1);
    const Interval& t = U[L.t(j)];
    const auto X = X_of(j), V = V_of(j);
    const Interval tn = U[L.t(j + 1)], S = tn - t;
    const auto e = Flight(mdl, t, X, V, S);
    const Interval vminus = ContactSum(mdl, e.V);
    Json flight = {{"start", j == 0 ? "release" : "departure"}, {"duration", Pair(S)}};
    if (!ledger.Check(S.Positive(), "duration", fl, S, "> 0") ||
        !ledger.Check(vminus.Negative(), "contact velocity before impact", fl, vminus, "< 0"))
      return finish("");
    double ws = 0;
    if (j == 0) {
      // g = g' = g'' = 0 at the true orbit: g(s) ≥ s³(g'''/6 − M4 s/24).
      const Interval g3 = ContactSum(mdl, Jerk(mdl, t, X, V));
      const Interval M4 = DerivativeBound(mdl, t, X, V, 4);
      if (!ledger.Check(g3.Positive(), "third derivative of the gap", fl, g3, "> 0") ||
          !ledger.Check(M4.finite(), "fourth-derivative bound", fl, M4, "finite"))
        return finish("");
      const double g3_low = g3.lo() * (1 - 1e-9);
      ws = 2 * g3_low / M4.hi();
      const Interval margin = Interval(g3_low) / Interval(6.0) - M4 * Interval(ws) / Interval(24.0);
      if (!ledger.Check(margin.Positive(), "start window g'''/6 - M4 ws/24", fl, margin, "> 0")) return finish("");
      flight["third_derivative"] = Pair(g3);
      flight["third_derivative_lower"] = g3_low;
      flight["fourth_derivative_bound"] = M4.hi();
    } else {
      // A departure: g = g' = 0, g'' = cᵀẌ = −s_B R > 0: g(s) ≥ s²(g''/2 − M3 s/6).
      const Interval g2 = ContactSum(mdl, Acceleration(mdl, t, X, V));
      const Interval M3 = DerivativeBound(mdl, t, X, V, 3);
      if (!ledger.Check(g2.Positive(), "second derivative of the gap", fl, g2, "> 0") ||
          !ledger.Check(M3.finite(), "third-derivative bound", fl, M3, "finite"))
        return finish("");
      const double g2_low = g2.lo() * (1 - 1e-9);
      ws = 1.5 * g2_low / M3.hi();
      const Interval margin = Interval(g2_low) / Interval(2.0) - M3 * Interval(ws) / Interval(6.0);
      if (!ledger.Check(margin.Positive(), "start window g''/2 - M3 ws/6", fl, margin, "> 0")) return finish("");
      flight["second_derivative"] = Pair(g2);
      flight["second_derivative_lower"] = g2_low;
      flight["third_derivative_bound"] = M3.hi();
    }
    // The landing: g(S − σ) ≥ σ(b − M2 σ/2) on (0, we], b ≤ −ẋ_B⁻.
    const Interval M2 = DerivativeBound(mdl, t, X, V, 2);
    if (!ledger.Check(M2.finite(), "second-derivative bound", fl, M2, "finite")) return finish("");
    const double b_low = -vminus.hi() * (1 - 1e-9), we = b_low / M2.hi();
    const Interval end_margin = Interval(b_low) - M2 * Interval(we) / Interval(2.0);
    if (!ledger.Check(end_margin.Positive(), "end window b - M2 we/2", fl, end_margin, "> 0")) return finish("");
    const double hi_s = S.hi() - 0.9 * we;
    Json pieces = Json::array();
    if (ws < hi_s) {
      const auto gap = [&](double s) { return ContactSum(mdl, Flight(mdl, t, X, V, Interval(s)).X) - mdl.stop; };
      const auto slope = [&](const Interval& s) { return ContactSum(mdl, Flight(mdl, t, X, V, s).V); };
      const auto pos = ProvePositive(ws, hi_s, step, request.max_depth, budget, gap, slope);
      if (!pos.proven) {
        ledger.Check(false, "gap", fmt::format("{} at s = {:.17g}", fl, pos.failed_at), pos.failed_value, "> 0");
        return finish(fmt::format("the gap is not proven positive on {}: {} (a grazing or a missed contact?)", fl, pos.reason));
      }
      for (const auto& [lo, hi] : pos.pieces) pieces.push_back({lo, hi});
    }
    const bool sticks = j == L.m - 1;
    const Interval R_land = Dot(h.reaction, HeldState(mdl, tn, X_of(j + 1), V_of(j + 1)));
    if (!ledger.Check(sticks ? R_land.Positive() : R_land.Negative(), "reaction at the landing", land, R_land,
                      sticks ? "> 0" : "< 0"))
      return finish(ledger.failed() + (sticks ? " (the last landing must stick)" : " (a landing before the last must depart)"));
    flight["start_window"] = ws;
    flight["second_derivative_bound"] = M2.hi();
    flight["velocity_before_next"] = Pair(vminus);
    flight["speed_before_lower"] = b_low;
    flight["end_window"] = we;
    flight["pieces"] = pieces;
    flight["reaction_at_landing"] = Pair(R_land);
    flights.push_back(flight);
    events.push_back({{"kind", "impact"}, {"contact", 0}, {"time", Pair(tn)}, {"phase", Pair(Phase(mdl, tn))}, {"velocity_before", Pair(vminus)}});
    sequence.push_back("impact");
    if (sticks) {
      events.push_back({{"kind", "stick"}, {"contact", 0}, {"time", Pair(tn)}, {"phase", Pair(Phase(mdl, tn))}, {"velocity_before", Pair(vminus)}});
      sequence.push_back("stick");
    } else {
      events.push_back({{"kind", "departure"}, {"contact", 0}, {"time", Pair(tn)}, {"phase", Pair(Phase(mdl, tn))}, {"velocity_before", {0.0, 0.0}}});
      sequence.push_back("departure");
    }
    M = MatMul(PlasticSaltation(mdl, tn, e.X, e.V, vminus, sticks), MatMul(FlightMatrix(mdl, t, X, V, S), M));
  }
  out.certificate["flights"] = flights;

  // 4. The held phase: R > 0 from the last landing to the release; near the release Ṙ < 0.
  const std::string st = "sticking phase";
  const Interval tm = U[L.t(L.m)];
  const auto zm = HeldState(mdl, tm, X_of(L.m), V_of(L.m));
  const Interval tau = tr + qT - tm;
  if (!ledger.Check(tau.Positive(), "duration", st, tau, "> 0")) return finish("");
  double we = std::min(0.1 / top, 0.25 * tau.lo());
  Interval tail_rate;
  for (int it = 0; it < 12; ++it, we /= 2) {
    tail_rate = Dot(h.reaction_rate, HeldAdvance(h, zm, Interval::Hull(tau.lo() - we, tau.hi())));
    if (tail_rate.Negative()) break;
  }
  if (!ledger.Check(tail_rate.Negative(), "reaction rate over the end window", st, tail_rate, "< 0"))
    return finish(ledger.failed() + " (the reaction is not proven to fall through 0 at the release)");
  Json stick_pieces = Json::array();
  const double to = tau.hi() - 0.9 * we;
  if (0 < to) {
    const auto rpos = ProvePositive(0.0, to, step, request.max_depth, budget,
                                    [&](double s) { return Dot(h.reaction, HeldAdvance(h, zm, Interval(s))); },
                                    [&](const Interval& s) { return Dot(h.reaction_rate, HeldAdvance(h, zm, s)); });
    if (!rpos.proven) {
      ledger.Check(false, "reaction", fmt::format("{} at t - t_{} = {:.17g}", st, L.m, rpos.failed_at), rpos.failed_value, "> 0");
      return finish(fmt::format("the reaction is not proven positive over the {}: {}", st, rpos.reason));
    }
    for (const auto& [lo, hi] : rpos.pieces) stick_pieces.push_back({lo, hi});
  }
  out.certificate["sticking"] = {{"duration", Pair(tau)}, {"end_window", we}, {"pieces", stick_pieces}};
  if (request.period > 0 && request.period % q != 0)
    return finish(fmt::format("the sticking orbit through the release has period {}, which does not divide {}", q,
                              request.period));

  // 5. The monodromy and its restriction to the held subspace (coordinates i ≠ k, k the largest |c_k|).
  const IntervalMatrix E = HeldExp(h, tau);
  IntervalMatrix Eh(2 * n, std::vector<Interval>(2 * n));
  for (std::size_t i = 0; i < 2 * n; ++i)
    for (std::size_t l = 0; l < 2 * n; ++l) Eh[i][l] = E[i][l];
  M = MatMul(Eh, M);
  const auto& c = mdl.contacts[0].shape;
  std::size_t kk = 0;
  for (std::size_t i = 1; i < n; ++i)
    if (std::abs(c[i].mid()) > std::abs(c[kk].mid())) kk = i;
  std::vector<std::size_t> keep;
  for (std::size_t blk = 0; blk < 2; ++blk)
    for (std::size_t i = 0; i < n; ++i)
      if (i != kk) keep.push_back(blk * n + i);
  IntervalMatrix B(2 * n, std::vector<Interval>(keep.size()));
  for (std::size_t col = 0; col < keep.size(); ++col) {
    const std::size_t p = keep[col], blk = p / n, i = p % n;
    B[p][col] = 1.0;
    B[blk * n + kk][col] = -(c[i] / c[kk]);
  }
  const auto MB = MatMul(M, B);
  IntervalMatrix Mr(keep.size(), std::vector<Interval>(keep.size()));
  for (std::size_t r = 0; r < keep.size(); ++r)
    for (std::size_t col = 0; col < keep.size(); ++col) Mr[r][col] = MB[keep[r]][col];
  const auto spectrum = Multipliers(Mr);
  Json monodromy = Json::array();
  for (const auto& row : M) {
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
  for (std::size_t p = 0; p < u.size(); ++p) width = std::max(width, k.hi[p] - k.lo[p]);
  out.summary["period"] = q;
  out.summary["sequence"] = sequence;
  out.summary["events"] = events;
  out.summary["section"] = {{"time", Pair(tr)}, {"X", Xs}, {"V", Vs}, {"at", "the release"}};
  out.summary["multipliers"] = spectrum.multipliers;
  out.summary["stability"] = spectrum.stability;
  out.summary["stability_note"] = spectrum.note.empty() ? std::string(kHeldNote) : spectrum.note;
  out.summary["box_width"] = width;
  out.proven = true;
  out.reason = fmt::format("exactly one period-{} sticking orbit of {} modes through the release in a box of width "
                           "{:.1e} (Krawczyk): release, {} flight(s) with plastic landings, sticking with R > 0 until "
                           "the next release", q, L.n, width, L.m);
  if (request.period > q) StateLeastPeriod(out, request.period);
  return out;
}

}  // namespace vibro::proof
