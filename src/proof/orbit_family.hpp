// An impacting orbit as a family in one parameter (the amplitude or the forcing frequency), for the
// bifurcation proofs of grazing_proof.cpp and orbit_pitchfork_proof.cpp: its multiple-shooting
// residual with the parameter a variable (damped or not, several contacts, a symmetric orbit as its
// half), the gaps along a flight, and Krawczyk's test in its parametric and extended forms.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "proof/proof_common.hpp"

namespace vibro::proof::family {

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
inline Linear Linearize(const Setup& g, const std::vector<Interval>& x, const std::vector<Interval>& X, bool extended) {
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

inline Eigen::MatrixXd Mid(const Matrix& a) {
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
inline KrawczykTest Krawczyk(const Setup& g, const std::vector<double>& x, const std::vector<Interval>& X, bool extended) {
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

inline std::string Dec(double x) { return fmt::format("{}", x); }

// γ at s over the box (u ∈ U, p ∈ P), its velocity, and its acceleration c_lᵀẌ.
struct Gap {
  Interval value, rate, acceleration;
};
inline Gap GapAt(const Setup& g, const std::vector<Interval>& U, const Interval& P, int j, int l, const Interval& s) {
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
inline std::optional<std::vector<double>> Newton(const Setup& g, std::vector<double> x) {
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


// The orbit is an orbit for every p ∈ P and u ∈ U: every flight has a positive duration, leaves its
// contact with a positive gap velocity and reaches the next with a negative one, and every gap is
// positive between the impacts (windows at the impacts where the gap velocity has its sign), except
// contact g.contact's on flight g.flight over [wlo, whi] (wlo > whi: no exception). "" when proven.
inline std::string OrbitGaps(const Setup& g, const std::vector<Interval>& Uu, const Interval& P, const Budget& budget,
                             double step, double wlo, double whi) {
  const IntervalModel& model = *g.m;
  const bool window = wlo < whi;
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
    if (window && j == g.flight && !(e0 < wlo && whi < S.lo() - e1)) {
      fail = "the tangency's window meets the windows at the impacts";
      break;
    }
    for (int l = 0; l < model.contact_count() && fail.empty(); ++l) {
      const double a = l == cj ? e0 : 0.0, b = l == ck ? S.lo() - e1 : S.hi();
      std::vector<std::pair<double, double>> ranges{{a, b}};
      if (window && j == g.flight && l == g.contact) ranges = {{a, wlo}, {whi, b}};
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
  return fail;
}

}  // namespace vibro::proof::family
