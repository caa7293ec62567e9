// Proof of an impacting periodic orbit (no sticking): Krawczyk's test on the multiple-shooting map,
// exclusion of any other contact on every flight, the enclosed monodromy (prove.hpp, docs/prove.md).
//
// Unknowns, per impact j = 0..m−1 of one period: u_j = (t_j, X_j, V_j), the time and the modal state
// just after the impact. Equations (m(2n+1) in as many unknowns), with t_m = t_0 + qT:
//   cᵀX_j − x0 = 0                                  (on the stop at the impact)
//   X(t_{j+1}⁻; u_j) − X_{j+1} = 0                   (the closed-form flight, eqs (13)-(14))
//   Impact(Ẋ(t_{j+1}⁻; u_j)) − V_{j+1} = 0           (the restitution law, eqs (10)-(12))
// Krawczyk: K(U) = ũ − C F(ũ) + (I − C J(U))(U − ũ) ⊂ int U  ⇒  exactly one zero of F in U.
#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "proof/jet.hpp"
#include "proof/orbit_family.hpp"
#include "proof/proof_common.hpp"

namespace vibro::proof {
namespace {

struct Layout {
  int n, m;
  std::vector<int> contacts;  // the contact of each impact (all 0 for one contact)
  int contact(int j) const { return contacts.empty() ? 0 : contacts[static_cast<std::size_t>(j)]; }
  std::size_t size() const { return static_cast<std::size_t>(m * (2 * n + 1)); }
  std::size_t t(int j) const { return static_cast<std::size_t>(j * (2 * n + 1)); }
  std::size_t x(int j, int i) const { return t(j) + 1 + static_cast<std::size_t>(i); }
  std::size_t v(int j, int i) const { return t(j) + 1 + static_cast<std::size_t>(n + i); }
};

template <class T>
std::vector<T> Slice(const std::vector<T>& u, std::size_t from, int count) {
  return std::vector<T>(u.begin() + static_cast<std::ptrdiff_t>(from),
                        u.begin() + static_cast<std::ptrdiff_t>(from) + count);
}

template <class T>
std::vector<T> Residual(const IntervalModel& mdl, const Layout& L, int q, const std::vector<T>& u) {
  std::vector<T> res;
  const T qT(Interval(q) * mdl.period);
  for (int j = 0; j < L.m; ++j) {
    const int k = (j + 1) % L.m;
    const T& t = u[L.t(j)];
    const auto X = Slice(u, L.x(j, 0), L.n), V = Slice(u, L.v(j, 0), L.n);
    const T tn = j == L.m - 1 ? u[L.t(k)] + qT : u[L.t(k)];
    const auto e = Flight(mdl, t, X, V, tn - t);
    const int cj = L.contact(j), ck = L.contact(k);
    const auto Vp = Impact(mdl, e.V, ck);
    res.push_back(ContactSum(mdl, X, cj) - T(mdl.contacts[static_cast<std::size_t>(cj)].stop));
    for (int i = 0; i < L.n; ++i) res.push_back(e.X[static_cast<std::size_t>(i)] - u[L.x(k, i)]);
    for (int i = 0; i < L.n; ++i) res.push_back(Vp[static_cast<std::size_t>(i)] - u[L.v(k, i)]);
  }
  return res;
}

// The Jacobian of the residual at (or over) u, enclosed.
std::vector<std::vector<Interval>> Jacobian(const IntervalModel& mdl, const Layout& L, int q,
                                            const std::vector<Interval>& u) {
  const std::size_t N = L.size();
  std::vector<Dual> ud;
  for (std::size_t k = 0; k < N; ++k) ud.push_back(Dual::Variable(u[k], k, N));
  const auto r = Residual(mdl, L, q, ud);
  std::vector<std::vector<Interval>> J(N, std::vector<Interval>(N));
  for (std::size_t p = 0; p < N; ++p)
    for (std::size_t l = 0; l < N && l < r[p].d.size(); ++l) J[p][l] = r[p].d[l];
  return J;
}

Eigen::MatrixXd Mid(const std::vector<std::vector<Interval>>& a) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(a.size()), static_cast<Eigen::Index>(a.size()));
  for (std::size_t p = 0; p < a.size(); ++p)
    for (std::size_t l = 0; l < a.size(); ++l) m(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(l)) = a[p][l].mid();
  return m;
}

std::vector<Interval> Points(const std::vector<double>& u) { return {u.begin(), u.end()}; }

// Newton in double on the midpoints: the guess of the Poincaré solver to full accuracy.
std::vector<double> Refine(const IntervalModel& mdl, const Layout& L, int q, std::vector<double> u) {
  for (int it = 0; it < 6; ++it) {
    const auto r = Residual(mdl, L, q, Points(u));
    Eigen::VectorXd F(static_cast<Eigen::Index>(u.size()));
    for (std::size_t p = 0; p < u.size(); ++p) F(static_cast<Eigen::Index>(p)) = r[p].mid();
    const Eigen::VectorXd du = Mid(Jacobian(mdl, L, q, Points(u))).fullPivLu().solve(F);
    if (!du.allFinite()) break;
    for (std::size_t p = 0; p < u.size(); ++p) u[p] -= du(static_cast<Eigen::Index>(p));
  }
  return u;
}

using Matrix = std::vector<std::vector<Interval>>;
Matrix Product(const Matrix& a, const Matrix& b) {
  const std::size_t N = a.size();
  Matrix c(N, std::vector<Interval>(N));
  for (std::size_t i = 0; i < N; ++i)
    for (std::size_t k = 0; k < N; ++k)
      for (std::size_t j = 0; j < N; ++j) c[i][j] += a[i][k] * b[k][j];
  return c;
}

// The monodromy over the box U: per flight the flight's state transition and the saltation matrix of
// the impact at its end (docs/model.md §5.6), multiplied in order. At the orbit in U it is the orbit's
// monodromy; over U (and the model's parameter intervals) it encloses the monodromy of every orbit
// there.
Matrix MonodromyOver(const IntervalModel& mdl, const Layout& L, int q, const std::vector<Interval>& U) {
  const Interval qT = Interval(q) * mdl.period;
  Matrix M(static_cast<std::size_t>(2 * L.n), std::vector<Interval>(static_cast<std::size_t>(2 * L.n)));
  for (int i = 0; i < 2 * L.n; ++i) M[static_cast<std::size_t>(i)][static_cast<std::size_t>(i)] = 1.0;
  for (int j = 0; j < L.m; ++j) {
    const int kk = (j + 1) % L.m;
    const Interval& t = U[L.t(j)];
    const auto X = Slice(U, L.x(j, 0), L.n), V = Slice(U, L.v(j, 0), L.n);
    const Interval tn = j == L.m - 1 ? U[L.t(kk)] + qT : U[L.t(kk)];
    const Interval S = tn - t;
    const auto e = Flight(mdl, t, X, V, S);
    const int ck = L.contact(kk);
    const Interval vminus = ContactSum(mdl, e.V, ck);
    // Monodromy: the flight (per mode [[cos, sin/ω_i], [−ω_i sin, cos]]) and the saltation matrix of
    // the impact at its end (docs/model.md §5.6).
    const auto n = static_cast<std::size_t>(L.n);
    Matrix Phi(2 * n, std::vector<Interval>(2 * n)), Sal(2 * n, std::vector<Interval>(2 * n));
    const auto& hit = mdl.contacts[static_cast<std::size_t>(ck)];
    const Interval one_r = Interval(1.0) + hit.restitution;
    if (mdl.damped()) {
      // Per mode [[h1, h2], [−ω_i² h2, h3]] (enclosure.hpp); the saltation matrix of the impact,
      // S = Dg + (f⁺ − Dg f⁻) ∇hᵀ/(∇h·f⁻) with Dg = diag(I, Π), ∇h = (c, 0): its lower-left block is
      // (Ẍ⁺ − Π Ẍ⁻) cᵀ/ẋ_B⁻, the damping force changing with the velocity at the impact.
      for (std::size_t i = 0; i < n; ++i) {
        const Interval decay = Exp(-(mdl.sigma[i] * S)), sd = Sin(mdl.omega_d[i] * S), cd = Cos(mdl.omega_d[i] * S);
        const Interval h2 = decay * sd / mdl.omega_d[i], ratio = mdl.sigma[i] / mdl.omega_d[i] * sd;
        Phi[i][i] = decay * (cd + ratio);
        Phi[i][n + i] = h2;
        Phi[n + i][i] = -(Sqr(mdl.omega[i]) * h2);
        Phi[n + i][n + i] = decay * (cd - ratio);
      }
      const auto before = Acceleration(mdl, tn, e.X, e.V), after = Acceleration(mdl, tn, e.X, Impact(mdl, e.V, ck));
      for (std::size_t i = 0; i < n; ++i) {
        Interval jump = after[i];
        for (std::size_t l = 0; l < n; ++l) {
          const Interval pr = Interval(i == l ? 1.0 : 0.0) - one_r * hit.contact[i] * hit.shape[l] / hit.W;
          Sal[i][l] = pr;
          Sal[n + i][n + l] = pr;
          jump -= pr * before[l];
        }
        for (std::size_t l = 0; l < n; ++l) Sal[n + i][l] = jump * hit.shape[l] / vminus;
      }
    } else {
      for (std::size_t i = 0; i < n; ++i) {
        const Interval c = Cos(mdl.omega[i] * S), s = Sin(mdl.omega[i] * S);
        Phi[i][i] = c;
        Phi[i][n + i] = s / mdl.omega[i];
        Phi[n + i][i] = -(mdl.omega[i] * s);
        Phi[n + i][n + i] = c;
      }
      const Interval aB = ContactAcceleration(mdl, tn, e.X, ck);
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t l = 0; l < n; ++l) {
          const Interval pr = Interval(i == l ? 1.0 : 0.0) - one_r * hit.contact[i] * hit.shape[l] / hit.W;
          Sal[i][l] = pr;
          Sal[n + i][n + l] = pr;
          Sal[n + i][l] = one_r * aB * hit.contact[i] * hit.shape[l] / (hit.W * vminus);
        }
    }
    M = Product(Sal, Product(Phi, M));
  }
  return M;
}

struct Krawczyk {
  bool inside = false;
  std::vector<double> lo, hi;
  std::vector<Interval> K;
  Eigen::MatrixXd C;
  std::size_t worst = 0;  // the component farthest from inside
  // A frequency segment (TangentTest): the orbits u(ω) = ũ + a(ω − ω̃) + w, w in the box W.
  double centre = 0;
  std::vector<double> u, tangent;
  std::vector<Interval> W, KW;
};

// ũ − C F(ũ) over the parameter interval, component p: with the model at the two ends (a residual
// affine in the parameter), the hull of the values at the ends, which is its exact range (the
// centred form ũ − C F(ũ, p̃) − (C ∂F/∂p)(P − p̃) with ∂F/∂p constant); otherwise F(ũ) evaluated for
// the whole interval at once.
Interval Constant(const Eigen::MatrixXd& C, const std::vector<double>& u, std::size_t p,
                  const std::vector<Interval>& F) {
  Interval v(u[p]);
  for (std::size_t l = 0; l < u.size(); ++l) v -= Interval(C(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(l))) * F[l];
  return v;
}

// Over an interval P of the forcing frequency (docs/prove.md "Along a branch", "Segments in the
// frequency") the residual is not affine in ω, and the orbits' times move with the period
// (dt_j/dω ≈ −t_j/ω): an axis-parallel box around the whole family is far wider in the times than in
// the velocities, and the second-order term of Krawczyk's operator, |C| |∂J| r_max², exceeds the
// smallest radius (the tube, 0.9 to 0.9002: 7 times). So the family is enclosed in a tube along its
// tangent: with a ≈ du/dω at (ũ, ω̃) (a = −J_u⁻¹ F_ω, any vector will do), u(p) = ũ + a(p − ω̃) + w, and
// for every p ∈ P Krawczyk's test on G_p(w) = F(ũ + a(p − ω̃) + w, p) in the box W around 0:
//   K(W) = −C G_p(0) + (I − C J_u(ũ + a(P − ω̃) + W, P)) W ⊂ int W
// proves for each p exactly one zero of F in ũ + a(p − ω̃) + W. G_p(0) = g(p) is a function of p alone,
// enclosed by Taylor's theorem with the Lagrange remainder, component by component:
//   g(p) ∈ g(ω̃) + g'(ω̃)(p − ω̃) + g''(P)(p − ω̃)²/2,
// the first two terms at the point ω̃ (g'(ω̃) = J_u a + F_ω ≈ 0 by the choice of a), g'' over P, by
// second-order forward differentiation (jet.hpp) of the residual with the frequency a variable
// (orbit_family.hpp). The box of the certificate is the hull of the tube, ũ + a(P − ω̃) + W.
family::Setup FrequencySetup(const IntervalModel& mdl, const Layout& L, int q) {
  family::Setup g;
  g.m = &mdl;
  g.n = L.n;
  g.count = L.m;
  g.q = q;
  g.frequency = true;
  for (int j = 0; j < L.m; ++j) g.hits.push_back(L.contact(j));
  return g;
}

// g(p) = F(ũ + a(p − ω̃), p) as a jet in δ = p − ω̃ over `delta`.
std::vector<Jet2> AlongTangent(const family::Setup& g, const std::vector<double>& u, const std::vector<double>& a,
                               double centre, const Interval& delta) {
  const Jet2 d = Jet2::Variable(delta);
  std::vector<Jet2> uj;
  for (std::size_t p = 0; p < u.size(); ++p) uj.push_back(Jet2(Interval(u[p])) + Jet2(Interval(a[p])) * d);
  return family::Residual(g, uj, Jet2(0.0), Jet2(Interval(centre)) + d, false);
}

Krawczyk TangentTest(const IntervalModel& mdl, const Layout& L, int q, std::vector<double> u, double radius,
                     double inflate) {
  Krawczyk k;
  const std::size_t N = u.size();
  const auto g = FrequencySetup(mdl, L, q);
  k.centre = mdl.frequency.mid();
  // ũ: Newton at ω̃ (the guess is the orbit interpolated between the ends); J_u and F_ω there.
  Eigen::MatrixXd Ju(static_cast<Eigen::Index>(N), static_cast<Eigen::Index>(N));
  Eigen::VectorXd Fw(static_cast<Eigen::Index>(N));
  for (int it = 0; it < 4; ++it) {
    std::vector<Interval> x(u.begin(), u.end());
    x.push_back(Interval(k.centre));
    const auto lin = family::Linearize(g, x, x, false);
    Eigen::VectorXd F(static_cast<Eigen::Index>(N));
    for (std::size_t a = 0; a < N; ++a) {
      F(static_cast<Eigen::Index>(a)) = lin.F[a].mid();
      Fw(static_cast<Eigen::Index>(a)) = lin.J[a][N].mid();
      for (std::size_t b = 0; b < N; ++b) Ju(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = lin.J[a][b].mid();
    }
    if (it == 3) break;
    const Eigen::VectorXd du = Ju.fullPivLu().solve(F);
    if (!du.allFinite()) break;
    for (std::size_t a = 0; a < N; ++a) u[a] -= du(static_cast<Eigen::Index>(a));
  }
  k.u = u;
  const Eigen::VectorXd av = -Ju.fullPivLu().solve(Fw);
  k.tangent.assign(av.data(), av.data() + N);
  if (!av.allFinite()) return k;
  const Interval delta = Union(mdl.frequency - Interval(k.centre), Interval(0.0));
  const auto at = AlongTangent(g, u, k.tangent, k.centre, Interval(0.0));
  const auto over = AlongTangent(g, u, k.tangent, k.centre, delta);
  k.C = Ju.inverse();
  if (!k.C.allFinite()) return k;
  // −C g(p) for every p ∈ P, then W: its radius the constant's magnitude, inflated, plus `radius`.
  std::vector<Interval> cst;
  for (std::size_t p = 0; p < N; ++p) {
    Interval v(0.0);
    for (std::size_t l = 0; l < N; ++l) {
      const Interval c(k.C(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(l)));
      v -= c * (at[l].v + at[l].d1 * delta + over[l].d2 * Sqr(delta) / Interval(2.0));
    }
    cst.push_back(v);
    const double r = inflate * std::max(std::abs(v.lo()), std::abs(v.hi())) + radius * (1 + std::abs(u[p]));
    if (!std::isfinite(r)) return k;  // the constant term not enclosed (the Taylor form wraps): no test
    k.W.push_back(Interval::Hull(-r, r));
  }
  std::vector<Interval> U;
  for (std::size_t p = 0; p < N; ++p) {
    const Interval x = Interval(u[p]) + Interval(k.tangent[p]) * delta + k.W[p];
    k.lo.push_back(x.lo());
    k.hi.push_back(x.hi());
    U.push_back(x);
  }
  const auto J = Jacobian(mdl, L, q, U);
  k.inside = true;
  double worst = -1;
  for (std::size_t p = 0; p < N; ++p) {
    Interval v = cst[p];
    for (std::size_t l = 0; l < N; ++l) {
      Interval row(p == l ? 1.0 : 0.0);
      for (std::size_t j = 0; j < N; ++j) row -= Interval(k.C(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(j))) * J[j][l];
      v += row * k.W[l];
    }
    // Inside 0.8 W, not only W: the checker's K(W), from its own jets at 192 bits, comes out up to
    // some 15 % wider (near the tube's pitchfork, a piece inside W by less failed its check).
    const bool in = v.InsideOpen(0.8 * k.W[p].lo(), 0.8 * k.W[p].hi());
    const double excess = v.finite() ? std::max(v.hi() - k.W[p].hi(), k.W[p].lo() - v.lo()) / (k.W[p].hi() - k.W[p].lo()) : 1e300;
    if (excess > worst) {
      worst = excess;
      k.worst = p;
    }
    k.inside = k.inside && in;
    k.KW.push_back(v);
    // Reported in u: ũ + a(P − ω̃) + K', K' three quarters of the way from K(W) to W (a wider claim,
    // still inside W, so that it holds the checker's enclosure of the orbits, whose K(W) comes out
    // a little wider: 13 % in the tube's).
    const Interval wider =
        in ? Interval::Hull((v.lo() + 3 * k.W[p].lo()) / 4, (v.hi() + 3 * k.W[p].hi()) / 4) : v;
    k.K.push_back(Interval(u[p]) + Interval(k.tangent[p]) * delta + wider);
  }
  k.lo.clear();
  k.hi.clear();
  for (std::size_t p = 0; p < N; ++p) {
    k.lo.push_back(U[p].lo());
    k.hi.push_back(U[p].hi());
  }
  return k;
}

Krawczyk Test(const IntervalModel& mdl, const Layout& L, int q, const std::vector<double>& u, double radius,
               const std::vector<double>& spread, double spread_scale, const AffineEnds* ends) {
  Krawczyk k;
  const std::size_t N = u.size();
  std::vector<Interval> U;
  for (std::size_t p = 0; p < N; ++p) {
    const double d = radius * (1 + std::abs(u[p])) + (spread.empty() ? 0.0 : spread[p] * spread_scale);
    k.lo.push_back(u[p] - d);
    k.hi.push_back(u[p] + d);
    U.push_back(Interval::Hull(k.lo.back(), k.hi.back()));
  }
  const auto F = Residual(mdl, L, q, Points(u));
  std::vector<Interval> F_lo, F_hi;
  if (ends) {
    F_lo = Residual(ends->lo, L, q, Points(u));
    F_hi = Residual(ends->hi, L, q, Points(u));
  }
  const auto J = Jacobian(mdl, L, q, U);
  k.C = Mid(J).inverse();
  k.inside = k.C.allFinite();
  double worst = -1;
  for (std::size_t p = 0; p < N; ++p) {
    Interval v = ends ? Union(Constant(k.C, u, p, F_lo), Constant(k.C, u, p, F_hi)) : Constant(k.C, u, p, F);
    for (std::size_t l = 0; l < N; ++l) {
      Interval row(p == l ? 1.0 : 0.0);
      for (std::size_t j = 0; j < N; ++j) row -= Interval(k.C(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(j))) * J[j][l];
      v += row * (U[l] - Interval(u[l]));
    }
    const bool in = v.InsideOpen(k.lo[p], k.hi[p]);
    const double excess = v.finite() ? std::max(v.hi() - k.hi[p], k.lo[p] - v.lo()) / (k.hi[p] - k.lo[p]) : 1e300;
    if (excess > worst) {
      worst = excess;
      k.worst = p;
    }
    k.inside = k.inside && in;
    k.K.push_back(std::move(v));
  }
  return k;
}

}  // namespace

Outcome ProveImpactOrbit(const IntervalModel& mdl, const ImpactGuess& guess, const ProofRequest& request,
                         const Budget& budget, const AffineEnds* ends, bool frequency_interval) {
  Outcome out;
  const Layout L{mdl.n, static_cast<int>(guess.times.size()), guess.contacts};
  const bool several = mdl.contact_count() > 1;
  const int q = guess.period;
  if (L.size() > kMaxUnknowns) {  // memory and time grow as the square and the cube of the unknowns
    out.reason = fmt::format("{} impacts in {} period(s) and {} mode(s): {} unknowns, more than the {} the prover "
                             "takes (docs/prove.md \"Bounds\")", L.m, q, L.n, L.size(), kMaxUnknowns);
    return out;
  }
  std::vector<std::string> names;
  std::vector<double> u0;
  for (int j = 0; j < L.m; ++j) {
    names.push_back(fmt::format("t_{}", j));
    u0.push_back(guess.times[static_cast<std::size_t>(j)]);
    for (int i = 0; i < L.n; ++i) {
      names.push_back(fmt::format("X_{}[{}]", j, i));
      u0.push_back(guess.X[static_cast<std::size_t>(j)](i));
    }
    for (int i = 0; i < L.n; ++i) {
      names.push_back(fmt::format("V_{}[{}]", j, i));
      u0.push_back(guess.V[static_cast<std::size_t>(j)](i));
    }
  }
  // Over a parameter interval (guess.spread), the orbit of the middle parameter, from the midpoint
  // of the orbits at the two ends.
  const auto u = Refine(mdl, L, q, u0);
  std::vector<double> spread;
  if (!guess.spread.empty()) {
    spread = guess.spread;
    for (std::size_t p = 0; p < spread.size(); ++p) spread[p] = 0.75 * spread[p] + std::abs(u[p] - u0[p]);
  }
  Ledger ledger;

  // 1. Existence and uniqueness in the box: Krawczyk, widening the box a few times.
  Krawczyk k;
  double radius = request.box_radius;
  for (int attempt = 0; attempt < 4; ++attempt, radius *= 4) {
    k = frequency_interval ? TangentTest(mdl, L, q, u, radius, 1.5 * radius / request.box_radius)
                           : Test(mdl, L, q, u, radius, spread, radius / request.box_radius, ends);
    if (k.inside || budget.passed()) break;
  }
  if (k.K.size() != u.size()) {  // the tangent of a frequency segment not computed (a singular J_u)
    out.reason = "Krawczyk's test fails: the shooting map's Jacobian at the middle of the frequency interval is "
                 "singular, or the Taylor form of its constant term is not finite: no unique orbit with this impact "
                 "sequence is proven near the orbit found";
    return out;
  }
  Json krawczyk = Json::array();
  for (std::size_t p = 0; p < u.size(); ++p) {
    const bool in = k.K[p].InsideOpen(k.lo[p], k.hi[p]);
    krawczyk.push_back(Pair(k.K[p]));
    ledger.Check(in, "krawczyk", names[p], k.K[p],
                 "inside the box");
  }
  Json box = Json::array(), C = Json::array();
  for (std::size_t p = 0; p < u.size(); ++p) {
    box.push_back({k.lo[p], k.hi[p]});
    Json row = Json::array();
    for (std::size_t l = 0; l < u.size(); ++l) row.push_back(k.C(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(l)));
    C.push_back(row);
  }
  out.certificate["unknowns"] = names;
  out.certificate["midpoint"] = frequency_interval ? k.u : u;
  if (frequency_interval) {  // the tube along the family's tangent (TangentTest)
    Json W = Json::array();
    for (const auto& w : k.W) W.push_back(Pair(w));
    out.certificate["tangent"] = {{"centre", k.centre}, {"direction", k.tangent}, {"box", W}};
  }
  out.certificate["box"] = box;
  out.certificate["preconditioner"] = C;
  out.certificate["krawczyk"] = krawczyk;
  if (!k.inside) {
    out.reason = fmt::format("Krawczyk's test fails: K(U) is not inside the box U for {} (box half-width {:.1e} relative): "
                             "no unique orbit with this impact sequence is proven near the orbit found",
                             names[k.worst], radius / 4);
    out.certificate["inequalities"] = ledger.list();
    return out;
  }
  std::vector<Interval> U;
  for (std::size_t p = 0; p < u.size(); ++p) U.push_back(Interval::Hull(k.lo[p], k.hi[p]));

  // 2. The event sequence: every flight is free of contact between its impacts.
  double top = mdl.frequency.hi();
  for (const auto& w : mdl.omega) top = std::max(top, w.hi());
  const double step = 0.25 / top;
  const Interval qT = Interval(q) * mdl.period;
  Json flights = Json::array(), events = Json::array();
  std::vector<Interval> v_before(static_cast<std::size_t>(L.m));
  bool ok = true;
  for (int j = 0; j < L.m && ok; ++j) {
    const int kk = (j + 1) % L.m;
    const Interval& t = U[L.t(j)];
    const auto X = Slice(U, L.x(j, 0), L.n), V = Slice(U, L.v(j, 0), L.n);
    const Interval tn = j == L.m - 1 ? U[L.t(kk)] + qT : U[L.t(kk)];
    const Interval S = tn - t;
    const auto e = Flight(mdl, t, X, V, S);
    const int cj = L.contact(j), ck = L.contact(kk);
    const Interval a = ContactSum(mdl, V, cj), vminus = ContactSum(mdl, e.V, ck);
    const std::string where = fmt::format("flight {} (impact {} to impact {})", j, j, kk);
    // The second-derivative bound of every gap (one contact: the stop's only).
    std::vector<Interval> M2;
    for (int l = 0; l < mdl.contact_count(); ++l) M2.push_back(DerivativeBound(mdl, t, X, V, 2, l));
    const auto gap_where = [&](int l) { return several ? fmt::format("{}, gap of contact {}", where, l) : where; };
    ok = ledger.Check(S.Positive(), "duration", where, S, "> 0") &&
         ledger.Check(a.Positive(), "contact velocity after impact", where, a, "> 0") &&
         ledger.Check(vminus.Negative(), "contact velocity before impact", where, vminus, "< 0");
    for (int l = 0; l < mdl.contact_count() && ok; ++l)
      ok = ledger.Check(M2[static_cast<std::size_t>(l)].finite(), "second-derivative bound", gap_where(l),
                        M2[static_cast<std::size_t>(l)], "finite");
    if (!ok) break;
    v_before[static_cast<std::size_t>(kk)] = vminus;
    // Windows: g(s) ≥ s(a − M2 s/2) > 0 on (0, ws] for the gap of the contact just hit;
    // g(S−σ) ≥ σ(b − M2 σ/2) > 0 on (0, we] for the gap of the contact hit next.
    // The bounds a ≤ ẋ_B⁺ and b ≤ −ẋ_B⁻ are taken a little below the enclosures, so that a checker
    // whose enclosures are a little wider still finds them valid.
    const Interval& M2s = M2[static_cast<std::size_t>(cj)];
    const Interval& M2e = M2[static_cast<std::size_t>(ck)];
    const double a_low = a.lo() * (1 - 1e-9), b_low = -vminus.hi() * (1 - 1e-9);
    const double ws = a_low / M2s.hi(), we = b_low / M2e.hi();
    const Interval start_margin = Interval(a_low) - M2s * Interval(ws) / Interval(2.0);
    const Interval end_margin = Interval(b_low) - M2e * Interval(we) / Interval(2.0);
    ok = ledger.Check(start_margin.Positive(), "start window a - M2 ws/2", where, start_margin, "> 0") &&
         ledger.Check(end_margin.Positive(), "end window b - M2 we/2", where, end_margin, "> 0");
    if (!ok) break;
    // Every gap positive between the windows. The end window covers s ≥ S* − we ≥ S.hi − we; the
    // pieces overlap it by 0.1 we, so that a checker whose enclosure of S is a little wider still
    // finds them covering. The gap of a contact not hit at either end is proven positive on all of
    // [0, S] (and a little beyond S.hi, for the same reason).
    Json gaps = Json::array(), pieces = Json::array();
    for (int l = 0; l < mdl.contact_count() && ok; ++l) {
      const double lo_s = l == cj ? ws : 0.0;
      const double hi_s = l == ck ? S.hi() - 0.9 * we : S.hi() + 1e-9 * (1 + S.hi());
      Json these = Json::array();
      if (lo_s < hi_s) {
        const auto& stop = mdl.contacts[static_cast<std::size_t>(l)].stop;
        const auto gap = [&](double s) { return ContactSum(mdl, Flight(mdl, t, X, V, Interval(s)).X, l) - stop; };
        const auto slope = [&](const Interval& s) { return ContactSum(mdl, Flight(mdl, t, X, V, s).V, l); };
        const auto pos = ProvePositive(lo_s, hi_s, step, request.max_depth, budget, gap, slope);
        if (!pos.proven) {
          ledger.Check(false, "gap", fmt::format("{} at s = {:.17g}", gap_where(l), pos.failed_at), pos.failed_value, "> 0");
          out.reason = fmt::format("the gap{} is not proven positive on {}: {} (a grazing or a missed contact?)",
                                   several ? fmt::format(" of contact {}", l) : "", where, pos.reason);
          ok = false;
          break;
        }
        for (const auto& [lo, hi] : pos.pieces) these.push_back({lo, hi});
      }
      if (several)
        gaps.push_back({{"contact", l}, {"second_derivative_bound", M2[static_cast<std::size_t>(l)].hi()}, {"pieces", these}});
      else
        pieces = these;
    }
    if (!ok) break;
    Json flight = {{"from", j}, {"duration", Pair(S)}, {"velocity_after", Pair(a)},
                   {"velocity_before_next", Pair(vminus)}, {"velocity_after_lower", a_low},
                   {"speed_before_lower", b_low}, {"start_window", ws}, {"end_window", we}};
    if (several) {
      flight["gaps"] = gaps;
    } else {
      flight["second_derivative_bound"] = M2s.hi();
      flight["pieces"] = pieces;
    }
    flights.push_back(flight);
  }
  out.certificate["flights"] = flights;
  if (several) out.certificate["impact_contacts"] = L.contacts;
  if (!ok) {
    if (out.reason.empty()) out.reason = ledger.failed();
    out.certificate["inequalities"] = ledger.list();
    return out;
  }
  for (int j = 0; j < L.m; ++j) {
    const Interval& t = U[L.t(j)];
    events.push_back({{"kind", "impact"}, {"contact", L.contact(j)}, {"time", Pair(t)}, {"phase", Pair(Phase(mdl, t))},
                      {"velocity_before", Pair(v_before[static_cast<std::size_t>(j)])}});
  }
  // The least period is q: for every prime ℓ | q, shifting by q/ℓ periods does not map the impacts
  // onto themselves (a time or a state difference excludes 0), as the checker verifies.
  for (int ell = 2, rest = q; ell <= rest; ++ell) {
    if (rest % ell) continue;
    while (rest % ell == 0) rest /= ell;
    if (L.m % ell) continue;
    const int p = q / ell, h = L.m / ell;
    bool apart = false;
    for (int j = 0; j < L.m && !apart; ++j) {
      const int kk = (j + h) % L.m;
      const Interval dt = U[L.t(kk)] + (j + h >= L.m ? qT : Interval(0.0)) - U[L.t(j)] - Interval(p) * mdl.period;
      apart = L.contact(kk) != L.contact(j) || dt.Positive() || dt.Negative();
      for (int i = 0; i < L.n && !apart; ++i) {
        const Interval dx = U[L.x(kk, i)] - U[L.x(j, i)], dv = U[L.v(kk, i)] - U[L.v(j, i)];
        apart = dx.Positive() || dx.Negative() || dv.Positive() || dv.Negative();
      }
    }
    if (!apart) {
      out.reason = fmt::format("the orbit proven in the box repeats after {} forcing period(s) (or cannot be told "
                               "apart from one that does): its least period is not proven to be {}", p, q);
      out.certificate["inequalities"] = ledger.list();
      return out;
    }
  }
  const Matrix M = MonodromyOver(mdl, L, q, U);
  const auto spectrum = Multipliers(M);
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
  out.summary["period"] = q;
  out.summary["sequence"] = Json(std::vector<std::string>(static_cast<std::size_t>(L.m), "impact"));
  out.summary["events"] = events;
  out.summary["section"] = {{"time", Pair(U[L.t(0)])}, {"X", Xs}, {"V", Vs}, {"at", "just after impact 0"}};
  out.summary["multipliers"] = spectrum.multipliers;
  out.summary["stability"] = spectrum.stability;
  if (!spectrum.note.empty()) out.summary["stability_note"] = spectrum.note;
  double width = 0;
  for (std::size_t p = 0; p < u.size(); ++p) width = std::max(width, k.hi[p] - k.lo[p]);
  out.summary["box_width"] = width;
  out.proven = true;
  // A frequency segment proves uniqueness in the tube along the tangent, not in the whole box.
  out.reason = frequency_interval
                   ? fmt::format("exactly one period-{} orbit with {} impact(s) per period in the tube along the "
                                 "family's tangent (the certificate's tangent: ũ + a(ω − ω̃) + W) and no other contact "
                                 "in its box of width {:.1e} (Krawczyk)", q, L.m, width)
                   : fmt::format("exactly one period-{} orbit with {} impact(s) per period and no other contact in a "
                                 "box of width {:.1e} around the orbit found (Krawczyk)", q, L.m, width);
  return out;
}

std::vector<std::vector<Interval>> ImpactMonodromy(const IntervalModel& model, const std::vector<int>& contacts,
                                                   int impacts, int q, const std::vector<Interval>& U) {
  return MonodromyOver(model, Layout{model.n, impacts, contacts}, q, U);
}

SubTube TangentOrbits(const IntervalModel& model, const std::vector<int>& contacts, int impacts, int q,
                      const std::vector<double>& guess, double radius) {
  const Layout L{model.n, impacts, contacts};
  Krawczyk k;
  for (int attempt = 0; attempt < 4; ++attempt) {
    k = TangentTest(model, L, q, guess, radius * (1 << (2 * attempt)), 1.5 * (1 << (2 * attempt)));
    if (k.inside) break;
  }
  SubTube out;
  out.proven = k.inside && k.K.size() == guess.size();
  out.centre = k.centre;
  out.u = k.u;
  out.tangent = k.tangent;
  out.W = k.W;
  out.K = k.K;
  return out;
}

Interval Phase(const IntervalModel& model, const Interval& t) {
  const Interval wt = model.frequency * t, two_pi = Interval(2.0) * Interval::Pi();
  const double turns = std::floor(wt.mid() / two_pi.mid());
  return wt - Interval(turns) * two_pi;
}

}  // namespace vibro::proof
