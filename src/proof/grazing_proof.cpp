// A grazing of an impacting orbit, proven (docs/prove.md "Bifurcation points").
//
// The orbit's unknowns u = (t_j, X_j, V_j) per impact j (as in impact_proof.cpp: the time and the
// modal state just after impact j) satisfy F(u, p) = 0 (on the contact at each impact, the flight
// of eqs (13)-(14) and docs/model.md §7 to the next, the restitution law (10)-(12)), p the amplitude
// or the forcing frequency. On flight J (from impact J), the gap of contact l,
// γ(s; u, p) = c_lᵀX(t_J + s) − e_l, has a local minimum m(p) at s(p): the grazing is m(p) = 0.
// The extended system E(u, s, p) = (F, γ̇, γ) = 0 (N + 2 equations in N + 2 unknowns) is proven to
// have exactly one zero in the box U × S × P by Krawczyk's test, P = [p_lo, p_hi] ≤ 1e-10 wide.
// Exactly one grazing parameter in P, crossed transversally:
//  (1) Krawczyk on F(u, P) = 0 alone over U: for every p ∈ P exactly one orbit u(p) ∈ U;
//  (2) γ̈ > 0 over a window W ⊇ S (every p ∈ P, u ∈ U) and γ̇ < 0 at S's lower end, > 0 at its
//      upper end: the minimum s(p) on W is unique and lies in S;
//  (3) every matrix J of the extended Jacobian over the box has ‖I − CJ‖∞ ≤ δ < 1 (C the
//      preconditioner), so J⁻¹ e_last ∈ C e_last ± δ/(1 − δ)‖C e_last‖∞; along the family,
//      E(u(p), s(p), p) = (0, 0, m(p)) gives dp/dm = (J⁻¹)_{last,last}: when that excludes 0,
//      dm/dp = 1/(J⁻¹)_{last,last} is enclosed and nonzero over all of P, so m is strictly monotone
//      on P: the zero that Krawczyk's test proves is the only one and the crossing is transversal;
//  (4) the orbit is an orbit: every flight has a positive duration, leaves its contact with a
//      positive gap velocity and reaches the next with a negative one, and every gap is positive
//      between the impacts (certified positivity) except contact l's on W, where it is convex.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "proof/grazing_proof.hpp"

namespace vibro::proof {
namespace {

using Matrix = std::vector<std::vector<Interval>>;

struct Setup {
  const IntervalModel* m = nullptr;
  int n = 0, count = 0, q = 1;
  std::vector<int> hits;  // the contact of each impact
  int flight = 0, contact = 0;
  bool frequency = false;
  // The symmetric orbit of a mirrored model (contact 1 is contact 0 mirrored: c_1 = −c_0, T_1 = −T_0,
  // e_1 = e_0, r_1 = r_0): one impact on contact hits[0] at t_0, then on the other contact at
  // t_0 + T/2 in the state −(X_0, V_0); the second half is the first mirrored.
  bool symmetric = false;
  std::size_t N() const { return static_cast<std::size_t>(count * (2 * n + 1)); }
  std::size_t t(int j) const { return static_cast<std::size_t>(j * (2 * n + 1)); }
  std::size_t x(int j) const { return t(j) + 1; }
  std::size_t v(int j) const { return t(j) + 1 + static_cast<std::size_t>(n); }
};

template <class T>
std::vector<T> Slice(const std::vector<T>& u, std::size_t from, int count) {
  return {u.begin() + static_cast<std::ptrdiff_t>(from), u.begin() + static_cast<std::ptrdiff_t>(from) + count};
}

// The free flight with the parameter a variable too: per mode the forced response
// U = P sin ωt + Q cos ωt of Ü + 2σU̇ + ω_i²U = T_A f sin ωt plus the free decay
// e^{−σs}(a cos ω_d s + b sin ω_d s) matching (X, V) at t0 (σ = 0, ω_d = ω_i undamped).
template <class T>
FlightEnd<T> FlightP(const Setup& g, const T& f, const T& w, const T& t0, const std::vector<T>& X,
                     const std::vector<T>& V, const T& s) {
  const IntervalModel& m = *g.m;
  FlightEnd<T> e;
  const T t1 = t0 + s;
  const T s0 = Sin(w * t0), c0 = Cos(w * t0), s1 = Sin(w * t1), c1 = Cos(w * t1);
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const T wi(m.omega[k]);
    const T sg(m.damped() ? m.sigma[k] : Interval(0.0));
    const T wd(m.damped() ? m.omega_d[k] : m.omega[k]);
    const T det = wi * wi - w * w, dmp = T(2.0) * sg * w, den = det * det + dmp * dmp;
    const T load = T(m.forcing[k]) * f;
    const T P = load * det / den, Q = -(load * dmp / den);
    const T U0 = P * s0 + Q * c0, Ud0 = w * (P * c0 - Q * s0);
    const T U1 = P * s1 + Q * c1, Ud1 = w * (P * c1 - Q * s1);
    const T a = X[k] - U0, b = (V[k] - Ud0 + sg * a) / wd;
    const T ex = m.damped() ? Exp(-(sg * s)) : T(1.0);
    const T cd = Cos(wd * s), sd = Sin(wd * s);
    e.X.push_back(U1 + ex * (a * cd + b * sd));
    e.V.push_back(Ud1 + ex * ((b * wd - a * sg) * cd - (a * wd + b * sg) * sd));
  }
  return e;
}

template <class T>
T Amplitude(const Setup& g, const T& p) { return g.frequency ? T(g.m->amplitude) : p; }
template <class T>
T Frequency(const Setup& g, const T& p) { return g.frequency ? p : T(g.m->frequency); }

// The flight from impact j over s (the last impact's flight ends at t_0 + qT).
template <class T>
FlightEnd<T> FlightFrom(const Setup& g, const std::vector<T>& u, int j, const T& p, const T& s) {
  return FlightP(g, Amplitude(g, p), Frequency(g, p), u[g.t(j)], Slice(u, g.x(j), g.n), Slice(u, g.v(j), g.n), s);
}

template <class T>
T Duration(const Setup& g, const std::vector<T>& u, int j, const T& p) {
  if (g.symmetric) return T(Interval::Pi()) / Frequency(g, p);
  const int k = (j + 1) % g.count;
  const T end = j == g.count - 1 ? u[g.t(k)] + T(Interval(2.0 * g.q) * Interval::Pi()) / Frequency(g, p) : u[g.t(k)];
  return end - u[g.t(j)];
}

// F(u, p), and with `extended` also γ̇(s), γ(s) of contact l on flight J.
template <class T>
std::vector<T> Residual(const Setup& g, const std::vector<T>& u, const T& s, const T& p, bool extended) {
  const IntervalModel& m = *g.m;
  std::vector<T> res;
  if (g.symmetric) {  // on contact a at t_0; at t_0 + T/2 on contact b in −X_0, leaving with −V_0
    const int a = g.hits[0], b = 1 - a;
    const auto e = FlightFrom(g, u, 0, p, Duration(g, u, 0, p));
    const auto Vp = Impact(m, e.V, b);
    res.push_back(ContactSum(m, Slice(u, g.x(0), g.n), a) - T(m.contacts[static_cast<std::size_t>(a)].stop));
    for (int i = 0; i < g.n; ++i) res.push_back(e.X[static_cast<std::size_t>(i)] + u[g.x(0) + static_cast<std::size_t>(i)]);
    for (int i = 0; i < g.n; ++i) res.push_back(Vp[static_cast<std::size_t>(i)] + u[g.v(0) + static_cast<std::size_t>(i)]);
  }
  for (int j = 0; j < g.count && !g.symmetric; ++j) {
    const int k = (j + 1) % g.count;
    const auto e = FlightFrom(g, u, j, p, Duration(g, u, j, p));
    const int cj = g.hits[static_cast<std::size_t>(j)], ck = g.hits[static_cast<std::size_t>(k)];
    const auto Vp = Impact(m, e.V, ck);
    res.push_back(ContactSum(m, Slice(u, g.x(j), g.n), cj) - T(m.contacts[static_cast<std::size_t>(cj)].stop));
    for (int i = 0; i < g.n; ++i) res.push_back(e.X[static_cast<std::size_t>(i)] - u[g.x(k) + static_cast<std::size_t>(i)]);
    for (int i = 0; i < g.n; ++i) res.push_back(Vp[static_cast<std::size_t>(i)] - u[g.v(k) + static_cast<std::size_t>(i)]);
  }
  if (extended) {
    const auto e = FlightFrom(g, u, g.flight, p, s);
    res.push_back(ContactSum(m, e.V, g.contact));
    res.push_back(ContactSum(m, e.X, g.contact) - T(m.contacts[static_cast<std::size_t>(g.contact)].stop));
  }
  return res;
}

// The residual at the point x (thin) and its Jacobian over the box X: x = (u, s, p) when extended
// (N + 2 equations and unknowns), else x = (u, p) with N equations: the last column of J is then
// ∂F/∂p, for the parametric Krawczyk test (p not an unknown).
struct Linear {
  std::vector<Interval> F;
  Matrix J;
};
Linear Linearize(const Setup& g, const std::vector<Interval>& x, const std::vector<Interval>& X, bool extended) {
  const std::size_t N = g.N(), V = extended ? N + 2 : N + 1;
  Linear l;
  {
    const std::vector<Interval> u(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(N));
    l.F = extended ? Residual(g, u, x[N], x[N + 1], true) : Residual(g, u, Interval(0.0), x[N], false);
  }
  std::vector<Dual> d;
  for (std::size_t k = 0; k < V; ++k) d.push_back(Dual::Variable(X[k], k, V));
  const std::vector<Dual> u(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(N));
  const auto r = extended ? Residual(g, u, d[N], d[N + 1], true) : Residual(g, u, Dual(0.0), d[N], false);
  l.J.assign(r.size(), std::vector<Interval>(V));
  for (std::size_t a = 0; a < r.size(); ++a)
    for (std::size_t b = 0; b < V && b < r[a].d.size(); ++b) l.J[a][b] = r[a].d[b];
  return l;
}

Eigen::MatrixXd Mid(const Matrix& a) {
  const auto n = static_cast<Eigen::Index>(a.size());
  Eigen::MatrixXd m(n, n);
  for (Eigen::Index p = 0; p < n; ++p)
    for (Eigen::Index l = 0; l < n; ++l) m(p, l) = a[static_cast<std::size_t>(p)][static_cast<std::size_t>(l)].mid();
  return m;
}

struct KrawczykTest {
  bool inside = false;
  std::vector<Interval> K;
  Eigen::MatrixXd C;
  double delta = std::numeric_limits<double>::infinity();  // an upper bound of ‖I − C J(X)‖∞
  std::size_t worst = 0;
};

// Krawczyk's test on the box X around x: the extended system (x = (u, s, p)), or the orbit alone
// (x = (u, p̃), X = (U, P)) in its parametric form
// K = ũ − C F(ũ, p̃) − (C ∂F/∂p(U, P))(P − p̃) + (I − C ∂F/∂u(U, P))(U − ũ).
KrawczykTest Krawczyk(const Setup& g, const std::vector<double>& x, const std::vector<Interval>& X, bool extended) {
  KrawczykTest k;
  std::vector<Interval> xi(x.begin(), x.end());
  const auto lin = Linearize(g, xi, X, extended);
  const std::size_t V = lin.F.size();
  Matrix square(V, std::vector<Interval>(V));
  for (std::size_t a = 0; a < V; ++a)
    for (std::size_t b = 0; b < V; ++b) square[a][b] = lin.J[a][b];
  k.C = Mid(square).inverse();
  k.inside = k.C.allFinite();
  if (!k.inside) return k;
  double worst = -1, delta = 0;
  for (std::size_t a = 0; a < V; ++a) {
    Interval v(x[a]);
    Interval rowsum(0.0), dp(0.0);
    for (std::size_t l = 0; l < V; ++l) {
      const Interval c(k.C(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(l)));
      v -= c * lin.F[l];
      if (!extended) dp += c * lin.J[l][V];
      Interval row(a == l ? 1.0 : 0.0);
      for (std::size_t j = 0; j < V; ++j) row -= Interval(k.C(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(j))) * lin.J[j][l];
      v += row * (X[l] - Interval(x[l]));
      rowsum += Abs(row);
    }
    if (!extended) v -= dp * (X[V] - Interval(x[V]));
    delta = std::max(delta, rowsum.hi());
    const bool in = v.InsideOpen(X[a].lo(), X[a].hi());
    const double excess = v.finite() ? std::max(v.hi() - X[a].hi(), X[a].lo() - v.lo()) / (X[a].hi() - X[a].lo()) : 1e300;
    if (excess > worst) {
      worst = excess;
      k.worst = a;
    }
    k.inside = k.inside && in;
    k.K.push_back(v);
  }
  k.delta = std::isfinite(delta) ? delta : std::numeric_limits<double>::infinity();
  return k;
}

std::string Dec(double x) { return fmt::format("{}", x); }

// γ at s over the box (u ∈ U, p ∈ P), its velocity, and its acceleration c_lᵀẌ.
struct Gap {
  Interval value, rate, acceleration;
};
Gap GapAt(const Setup& g, const std::vector<Interval>& U, const Interval& P, int j, int l, const Interval& s) {
  const IntervalModel& m = *g.m;
  const auto e = FlightFrom(g, U, j, P, s);
  const Interval t = U[g.t(j)] + s, f = Amplitude(g, P), w = Frequency(g, P);
  const Interval load = f * Sin(w * t);
  std::vector<Interval> a;
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    Interval ai = m.forcing[k] * load - Sqr(m.omega[k]) * e.X[k];
    if (m.damped()) ai -= Interval(2.0) * m.sigma[k] * e.V[k];
    a.push_back(ai);
  }
  return {ContactSum(m, e.X, l) - m.contacts[static_cast<std::size_t>(l)].stop, ContactSum(m, e.V, l), ContactSum(m, a, l)};
}

// Newton in double (midpoints) on E(x) = 0 from x; nullopt when it does not converge.
std::optional<std::vector<double>> Newton(const Setup& g, std::vector<double> x) {
  for (int it = 0; it < 40; ++it) {
    std::vector<Interval> xi(x.begin(), x.end());
    const auto lin = Linearize(g, xi, xi, true);
    Eigen::VectorXd F(static_cast<Eigen::Index>(x.size()));
    for (std::size_t a = 0; a < x.size(); ++a) F(static_cast<Eigen::Index>(a)) = lin.F[a].mid();
    const Eigen::VectorXd dx = Mid(lin.J).fullPivLu().solve(F);
    if (!dx.allFinite()) return std::nullopt;
    double big = 0;
    for (std::size_t a = 0; a < x.size(); ++a) {
      x[a] -= dx(static_cast<Eigen::Index>(a));
      big = std::max(big, std::abs(dx(static_cast<Eigen::Index>(a))) / (1 + std::abs(x[a])));
    }
    if (big < 1e-15 && it > 2) return x;
  }
  std::vector<Interval> xi(x.begin(), x.end());
  const auto lin = Linearize(g, xi, xi, true);
  for (const auto& r : lin.F)
    if (!(std::abs(r.mid()) < 1e-11)) return std::nullopt;
  return x;
}

}  // namespace

Outcome ProveGrazing(const IntervalModel& model, bool mirrored, const ImpactGuess& guess, bool frequency,
                     double located, double bracket, const Budget& budget, std::string& interval_text) {
  Outcome out;
  const char* name = frequency ? "frequency" : "amplitude";
  Setup g;
  g.m = &model;
  g.n = model.n;
  g.count = static_cast<int>(guess.times.size());
  g.q = guess.period;
  g.frequency = frequency;
  g.hits = guess.contacts.empty() ? std::vector<int>(static_cast<std::size_t>(g.count), 0) : guess.contacts;
  if (g.count == 0) {
    out.reason = "the orbit found has no impact: a grazing is proven for impacting orbits";
    return out;
  }
  if (g.N() + 2 > kMaxUnknowns) {
    out.reason = fmt::format("{} impacts and {} mode(s): {} unknowns, more than the {} the prover takes", g.count, g.n,
                             g.N() + 2, kMaxUnknowns);
    return out;
  }
  // A symmetric orbit of a mirrored model: proven as its half (the two grazings, of contact l on
  // one half and of the other contact on the mirrored half, are then one).
  if (model.contact_count() == 2 && g.count == 2 && g.q == 1 && g.hits[0] != g.hits[1]) {
    const auto& k0 = model.contacts[0];
    const auto& k1 = model.contacts[1];
    bool exact = true;
    for (int i = 0; i < g.n; ++i) {
      const auto z = static_cast<std::size_t>(i);
      const Interval c = k0.shape[z] + k1.shape[z], t = k0.contact[z] + k1.contact[z];
      exact = exact && c.lo() == 0 && c.hi() == 0 && t.lo() == 0 && t.hi() == 0;
    }
    const double T = 2 * M_PI / (frequency ? located : model.frequency.mid());
    bool image = std::abs(guess.times[1] - guess.times[0] - T / 2) < 1e-4 * T;
    for (int i = 0; i < g.n; ++i)
      image = image && std::abs(guess.X[1](i) + guess.X[0](i)) < 1e-4 * (1 + std::abs(guess.X[0](i))) &&
              std::abs(guess.V[1](i) + guess.V[0](i)) < 1e-4 * (1 + std::abs(guess.V[0](i)));
    if ((exact || mirrored) && k0.stop_text == k1.stop_text && k0.restitution_text == k1.restitution_text && image) {
      g.symmetric = true;
      g.count = 1;
      g.hits.resize(1);
    }
  }
  std::vector<double> u0;
  for (int j = 0; j < g.count; ++j) {
    u0.push_back(guess.times[static_cast<std::size_t>(j)]);
    for (int i = 0; i < g.n; ++i) u0.push_back(guess.X[static_cast<std::size_t>(j)](i));
    for (int i = 0; i < g.n; ++i) u0.push_back(guess.V[static_cast<std::size_t>(j)](i));
  }
  // The flight and contact that come nearest to a tangency: the interior local minimum of a gap
  // (sampled) of least value.
  const std::vector<Interval> U0(u0.begin(), u0.end());
  const Interval p0(located);
  double best = std::numeric_limits<double>::infinity(), s0 = 0;
  for (int j = 0; j < g.count; ++j) {
    const double S = Duration(g, U0, j, p0).mid();
    constexpr int kSamples = 400;
    std::vector<double> gap(kSamples + 1);
    for (int l = 0; l < model.contact_count(); ++l) {
      for (int k = 0; k <= kSamples; ++k) gap[static_cast<std::size_t>(k)] = GapAt(g, U0, p0, j, l, Interval(S * k / kSamples)).value.mid();
      for (int k = 1; k < kSamples; ++k) {
        const double y = gap[static_cast<std::size_t>(k)];
        if (y <= gap[static_cast<std::size_t>(k - 1)] && y <= gap[static_cast<std::size_t>(k + 1)] && std::abs(y) < best) {
          best = std::abs(y);
          s0 = S * k / kSamples;
          g.flight = j;
          g.contact = l;
        }
      }
    }
  }
  if (!std::isfinite(best)) {
    out.reason = "no free flight of the orbit has an interior minimum of a gap: no grazing near the located point";
    return out;
  }
  std::vector<double> x0 = u0;
  x0.push_back(s0);
  x0.push_back(located);
  const auto solved = Newton(g, x0);
  if (!solved) {
    out.reason = fmt::format("Newton on the orbit with a tangency of contact {} on flight {} does not converge from the "
                             "located point: no grazing found to prove", g.contact, g.flight);
    return out;
  }
  const std::vector<double> x = *solved;
  const std::size_t N = g.N();
  const double pstar = x[N + 1], sstar = x[N];
  const double slack = bracket + 1e-10 * (1 + std::abs(located));
  const double center = bracket > 0 && std::abs(pstar - located) <= slack ? pstar : located;
  // The family's tangent dx/dp (F = 0, γ̇ = 0 with p given), for the box's radii.
  std::vector<double> dxdp(N + 1, 0.0);
  {
    std::vector<Interval> xi(x.begin(), x.end());
    const auto lin = Linearize(g, xi, xi, true);
    Eigen::MatrixXd A(static_cast<Eigen::Index>(N + 1), static_cast<Eigen::Index>(N + 1));
    Eigen::VectorXd b(static_cast<Eigen::Index>(N + 1));
    for (std::size_t a = 0; a <= N; ++a) {
      for (std::size_t c = 0; c <= N; ++c) A(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(c)) = lin.J[a][c].mid();
      b(static_cast<Eigen::Index>(a)) = -lin.J[a][N + 1].mid();
    }
    const Eigen::VectorXd d = A.fullPivLu().solve(b);
    for (std::size_t a = 0; a <= N && d.allFinite(); ++a) dxdp[a] = d(static_cast<Eigen::Index>(a));
  }
  double top = model.frequency.hi() + (frequency ? 1.0 : 0.0);
  for (const auto& w : model.omega) top = std::max(top, w.hi());
  const double step = 0.25 / top;
  std::string last;
  for (double half = 1e-12 * (1 + std::abs(center)); 2 * half <= 1e-10 && !budget.passed(); half *= 4) {
    const std::string lo = Dec(center - half), hi = Dec(center + half);
    const Interval P = Union(Interval::Decimal(lo), Interval::Decimal(hi));
    if (!(P.lo() < pstar && pstar < P.hi())) {
      last = fmt::format("the tangency of contact {} on flight {} is at {} = {} (Newton), outside [{}, {}]: no grazing "
                         "is proven there", g.contact, g.flight, name, Dec(pstar), lo, hi);
      continue;
    }
    const double reach = std::max(P.hi() - pstar, pstar - P.lo());
    std::vector<Interval> X;
    KrawczykTest fam, ext;
    bool boxed = false;
    for (double r0 = 1e-13; r0 <= 1e-9 && !boxed; r0 *= 10) {
      X.clear();
      for (std::size_t a = 0; a <= N; ++a) {
        const double rad = r0 * (1 + std::abs(x[a])) + 2 * std::abs(dxdp[a]) * reach;
        X.push_back(Interval::Hull(x[a] - rad, x[a] + rad));
      }
      X.push_back(P);
      const std::vector<Interval> Uu(X.begin(), X.begin() + static_cast<std::ptrdiff_t>(N));
      std::vector<double> xu(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(N));
      std::vector<Interval> UP = Uu;
      xu.push_back(pstar);
      UP.push_back(P);
      fam = Krawczyk(g, xu, UP, false);
      if (!fam.inside) {
        last = fmt::format("Krawczyk's test on the orbit over {} in [{}, {}] fails (unknown {}): no unique orbit proven "
                           "over the interval", name, lo, hi, fam.worst);
        continue;
      }
      // The tangency's time box: wide enough that γ̇ has its signs at its ends for every orbit of U
      // (γ̇ at s* over the box is that wide, and γ̈ turns it into time).
      const Gap mid = GapAt(g, Uu, P, g.flight, g.contact, Interval(sstar));
      const double rad_s = X[N].hi() - sstar + 2 * (mid.rate.hi() - mid.rate.lo()) / std::abs(mid.acceleration.mid());
      X[N] = Interval::Hull(sstar - rad_s, sstar + rad_s);
      ext = Krawczyk(g, x, X, true);
      if (!ext.inside) {
        last = fmt::format("Krawczyk's test on the orbit with its tangency fails (unknown {} of {}): no unique grazing "
                           "proven in [{}, {}]", ext.worst, N + 2, lo, hi);
        continue;
      }
      const Gap a = GapAt(g, Uu, P, g.flight, g.contact, Interval(X[N].lo()));
      const Gap b = GapAt(g, Uu, P, g.flight, g.contact, Interval(X[N].hi()));
      if (!a.rate.Negative() || !b.rate.Positive()) {
        last = fmt::format("the gap velocity at the ends of the tangency's time box is {} and {}: not proven of "
                           "opposite signs", a.rate.ToString(), b.rate.ToString());
        continue;
      }
      boxed = true;
    }
    if (!boxed) continue;
    const std::vector<Interval> Uu(X.begin(), X.begin() + static_cast<std::ptrdiff_t>(N));
    // (3) dm/dp over P.
    const auto Nl = static_cast<Eigen::Index>(N + 1);
    double cmax = 0;
    for (Eigen::Index a = 0; a <= Nl; ++a) cmax = std::max(cmax, std::abs(ext.C(a, Nl)));
    if (!(ext.delta < 1)) {
      last = fmt::format("‖I − CJ‖∞ ≤ {} over the box: not below 1", ext.delta);
      continue;
    }
    const Interval dl(ext.delta);
    const double spread = (dl / (Interval(1.0) - dl) * Interval(cmax)).hi();
    const Interval inv = Interval(ext.C(Nl, Nl)) + Interval::Hull(-spread, spread);
    if (inv.Contains(0.0)) {
      last = fmt::format("dp/dm (the inverse of the minimum gap's derivative) is {} over the box: not proven nonzero",
                         inv.ToString());
      continue;
    }
    const Interval slope = Interval(1.0) / inv;
    // (2) The window: γ̈ > 0 on W ⊇ S, for every p and orbit of the box.
    const Interval Sj = Duration(g, Uu, g.flight, P);
    std::optional<double> wlo, whi;
    for (double ww = std::min(0.05 * Sj.lo(), 0.45 * std::min(sstar, Sj.lo() - sstar)); ww > 1e-6 * Sj.lo(); ww /= 2) {
      const double a = std::max(sstar - ww, 0.0), b = std::min(sstar + ww, Sj.lo());
      if (!(a < X[N].lo() && X[N].hi() < b)) break;
      bool convex = true;
      constexpr int kPieces = 32;
      for (int k = 0; k < kPieces && convex; ++k)
        convex = GapAt(g, Uu, P, g.flight, g.contact, Interval::Hull(a + (b - a) * k / kPieces, a + (b - a) * (k + 1) / kPieces))
                     .acceleration.Positive();
      if (convex) {
        wlo = a;
        whi = b;
        break;
      }
    }
    if (!wlo) {
      last = "the gap is not proven convex on a window around the tangency";
      continue;
    }
    // (4) The orbit is an orbit, for every p and u of the box.
    std::string fail;
    for (int j = 0; j < g.count && fail.empty(); ++j) {
      const int k = (j + 1) % g.count;
      const int cj = g.hits[static_cast<std::size_t>(j)];
      const int ck = g.symmetric ? 1 - cj : g.hits[static_cast<std::size_t>(k)];
      const Interval S = Duration(g, Uu, j, P);
      const Interval after = GapAt(g, Uu, P, j, cj, Interval(0.0)).rate;
      const Interval before = GapAt(g, Uu, P, j, ck, S).rate;
      if (!S.Positive() || !after.Positive() || !before.Negative()) {
        fail = fmt::format("flight {}: its duration {}, the velocity after its impact {} or before the next {} has not "
                           "the sign of an impacting orbit", j, S.ToString(), after.ToString(), before.ToString());
        break;
      }
      // Windows at the impacts, where the gap velocity has its sign (the gap is 0 at the impact).
      double e0 = S.lo() / 16, e1 = S.lo() / 16;
      bool w0 = false, w1 = false;
      for (int it = 0; it < 24 && !w0; ++it)
        if (!(w0 = GapAt(g, Uu, P, j, cj, Interval::Hull(0.0, e0)).rate.Positive())) e0 /= 2;
      for (int it = 0; it < 24 && !w1; ++it)
        if (!(w1 = GapAt(g, Uu, P, j, ck, Interval::Hull(S.lo() - e1, S.hi())).rate.Negative())) e1 /= 2;
      if (!w0 || !w1) {
        fail = fmt::format("flight {}: the gap velocity just after or just before its impacts is not proven of its sign", j);
        break;
      }
      if (j == g.flight && !(e0 < *wlo && *whi < S.lo() - e1)) {
        fail = "the tangency's window meets the windows at the impacts";
        break;
      }
      for (int l = 0; l < model.contact_count() && fail.empty(); ++l) {
        const double a = l == cj ? e0 : 0.0, b = l == ck ? S.lo() - e1 : S.hi();
        std::vector<std::pair<double, double>> ranges{{a, b}};
        if (j == g.flight && l == g.contact) ranges = {{a, *wlo}, {*whi, b}};
        for (const auto& [from, to] : ranges) {
          if (!(from < to)) continue;
          const auto pos = ProvePositive(
              from, to, step, 30, budget, [&](double s) { return GapAt(g, Uu, P, j, l, Interval(s)).value; },
              [&](const Interval& s) { return GapAt(g, Uu, P, j, l, s).rate; });
          if (!pos.proven) {
            fail = fmt::format("the gap of contact {} on flight {} is not proven positive: {}", l, j, pos.reason);
            break;
          }
        }
      }
    }
    if (!fail.empty()) {
      last = fail;
      continue;
    }
    const Gap at = GapAt(g, Uu, P, g.flight, g.contact, X[N]);
    // Claims: widened a little beyond the prover's enclosures, so that they contain the checker's
    // own (computed otherwise: docs/prove.md, every claim must contain it).
    const auto widen = [](const Interval& v, double rel) {
      const double m = rel * std::max(std::abs(v.lo()), std::abs(v.hi())) + (v.hi() - v.lo());
      return Interval::Hull(v.lo() - m, v.hi() + m);
    };
    const Interval slope_claim = widen(slope, 1e-6), curvature = widen(at.acceleration, 1e-6);
    const Interval time = widen(Uu[g.t(g.flight)] + X[N], 1e-12);
    Json box = Json::array(), names = Json::array();
    for (std::size_t a = 0; a <= N; ++a) box.push_back(Pair(X[a]));
    for (int j = 0; j < g.count; ++j) {
      names.push_back(fmt::format("t_{}", j));
      for (int i = 0; i < g.n; ++i) names.push_back(fmt::format("X_{}[{}]", j, i));
      for (int i = 0; i < g.n; ++i) names.push_back(fmt::format("V_{}[{}]", j, i));
    }
    names.push_back("s");
    interval_text = "[" + lo + ", " + hi + "]";
    out.proven = true;
    const bool opens = slope.Positive();
    out.reason = fmt::format(
        "exactly one {} in [{}, {}] at which flight {} of the orbit touches contact {} with zero velocity (a grazing): "
        "the minimum gap m on that flight is zero there and its derivative dm/d{}, {}, is nonzero over the whole "
        "interval: the crossing is transversal (below the point the flight {} the contact, above it it {})",
        name, lo, hi, g.flight, g.contact, name, slope.ToString(), opens ? "crosses" : "clears",
        opens ? "clears" : "crosses");
    Json hits = Json::array();
    for (int h : g.hits) hits.push_back(h);
    if (g.symmetric) {
      hits.push_back(1 - g.hits[0]);
      out.reason += fmt::format("; the orbit is symmetric (proven as its half: the second half is the first mirrored), so "
                                "at the same point flight 1 touches contact {} likewise", 1 - g.contact);
    }
    out.summary = {{"bifurcation", "grazing"},
                   {"parameter", name},
                   {"located", located},
                   {"center", center},
                   {"interval", Json::array({lo, hi})},
                   {"width", P.hi() - P.lo()},
                   {"box_width", P.hi() - P.lo()},
                   {"slope", Pair(slope_claim)},
                   {"curvature", Pair(curvature)},
                   {"grazing_contact", g.contact},
                   {"grazing_flight", g.flight},
                   {"grazing_time", Pair(time)},
                   {"impact_contacts", hits},
                   {"symmetric", g.symmetric},
                   {"period", g.q}};
    out.certificate = {{"bifurcation",
                        {{"type", "grazing"},
                         {"parameter", name},
                         {"interval", Json::array({lo, hi})},
                         {"contact", g.contact},
                         {"flight", g.flight},
                         {"impact_contacts", hits},
                         {"symmetric", g.symmetric},
                         {"unknowns", names},
                         {"midpoint", std::vector<double>(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(N + 1))},
                         {"box", box},
                         {"window", Json::array({*wlo, *whi})},
                         {"slope", Pair(slope_claim)},
                         {"curvature", Pair(curvature)},
                         {"grazing_time", Pair(time)}}}};
    return out;
  }
  out.reason = last.empty() ? "the time limit was reached" : last;
  return out;
}

}  // namespace vibro::proof
