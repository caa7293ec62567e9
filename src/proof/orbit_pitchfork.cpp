// The symmetry-breaking pitchfork of a symmetric impacting orbit, proven (docs/prove.md
// "Bifurcation points"): any number of modes, damped or not, a mirrored model.
//
// The symmetric orbit a = (t_0, X_0, V_0) (impact on contact a, then on the other contact b half a
// period later in the state −(X_0, V_0)) solves R_sym(a, p) = rows0(a, σ(a)) = 0, where rows0(u_0, u_1)
// are the equations of flight 0 of the whole orbit (on contact a at t_0; the flight to t_1 ends in
// X_1; the impact on b gives V_1) and σ(u) = (t + T/2, −X, −V). With A, B the Jacobians of rows0 in
// u_0 and u_1 and σ' = diag(1, −I, −I), the whole orbit's Jacobian splits into the symmetric block
// A + Bσ' (that of R_sym) and the antisymmetric block M = A − Bσ': the pitchfork (the period map's
// multiplier +1 with an antisymmetric eigenvector) is where M is singular. M is written here in
// closed form (the flight's state-transition h1, h2, h3 per mode, the vector field at both ends, the
// impact's projection Π = I − (1 + r_b) T_b c_bᵀ/W_b), so that forward differentiation gives its
// derivatives. Proven, over a box A × B × P with P ≤ 1e-10 wide:
//  (1) the parametric Krawczyk test on (R_sym, M b + μ e_k, ℓᵀb − 1) = 0 in (a, b, μ), p ∈ P: for
//      every p exactly one (a(p), b(p), μ(p)) in the box (μ(p) = 0 exactly where M is singular);
//  (2) Krawczyk's test on E(a, b, p) = (R_sym, M b, ℓᵀb − 1) = 0 with p an unknown: exactly one
//      pitchfork in the box;
//  (3) ‖I − CJ‖∞ ≤ δ < 1 over the box for E's Jacobian: along the family E = (0, −μ e_k, 0), so
//      dp/dμ = −(J⁻¹)_{p,k'} (k' the row of M b's component k) ∈ −C_{p,k'} ± δ/(1 − δ)‖C e_k'‖∞;
//      excluding 0, μ is strictly monotonic on P: the pitchfork is the only one, crossed
//      transversally;
//  (4) the symmetric orbit is an orbit over the box (durations, impact velocities, gaps).
#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/SVD>
#include <fmt/format.h>

#include "proof/orbit_family.hpp"
#include "proof/orbit_pitchfork.hpp"

namespace vibro::proof {
using namespace family;
namespace {

// M(a, p) b, the antisymmetric block applied to b, in closed form.
template <class T>
std::vector<T> AntiTimes(const Setup& g, const std::vector<T>& a, const std::vector<T>& b, const T& p) {
  const IntervalModel& m = *g.m;
  const int n = g.n, ca = g.hits[0], cb = 1 - ca;
  const T f = Amplitude(g, p), w = Frequency(g, p);
  const T t0 = a[0], s = T(Interval::Pi()) / w, t1 = t0 + s;
  const std::vector<T> X0(a.begin() + 1, a.begin() + 1 + n), V0(a.begin() + 1 + n, a.end());
  const auto e = FlightP(g, f, w, t0, X0, V0, s);
  std::vector<T> h1, h2, h3, acc0, acc1;
  const T l0 = f * Sin(w * t0), l1 = f * Sin(w * t1);
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const T sg(m.damped() ? m.sigma[k] : Interval(0.0));
    const T wd(m.damped() ? m.omega_d[k] : m.omega[k]);
    const T w2(Sqr(m.omega[k]));
    const T ex = m.damped() ? Exp(-(sg * s)) : T(1.0);
    const T sd = Sin(wd * s), cd = Cos(wd * s);
    h1.push_back(ex * (cd + sg / wd * sd));
    h2.push_back(ex * sd / wd);
    h3.push_back(ex * (cd - sg / wd * sd));
    acc0.push_back(T(m.forcing[k]) * l0 - w2 * X0[k] - T(2.0) * sg * V0[k]);
    acc1.push_back(T(m.forcing[k]) * l1 - w2 * e.X[k] - T(2.0) * sg * e.V[k]);
  }
  const auto& kb = m.contacts[static_cast<std::size_t>(cb)];
  const auto& ka = m.contacts[static_cast<std::size_t>(ca)];
  const T bt = b[0];
  // Row 0: c_a·δX_0.
  std::vector<T> out;
  T r0(0.0);
  for (int i = 0; i < n; ++i) r0 = r0 + T(ka.shape[static_cast<std::size_t>(i)]) * b[static_cast<std::size_t>(1 + i)];
  out.push_back(r0);
  // Rows X: (A_t − B_t) b_t + (A_X + B_X) b_X + (A_V + B_V) b_V, per mode.
  std::vector<T> dv;  // the pre-impact velocity's part, before Π
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const T w2(Sqr(m.omega[k]));
    const T bx = b[1 + k], bv = b[1 + static_cast<std::size_t>(n) + k];
    const T At = -(h1[k] * V0[k] + h2[k] * acc0[k]), Bt = e.V[k];
    out.push_back((At - Bt) * bt + (h1[k] - T(1.0)) * bx + h2[k] * bv);
    const T Dt0 = -(h3[k] * acc0[k] - w2 * h2[k] * V0[k]), Dt1 = acc1[k];
    dv.push_back((Dt0 - Dt1) * bt - w2 * h2[k] * bx + h3[k] * bv);
  }
  // Rows V: Π dv + (A_V-part of B: −I on V_1, with the sign of σ' flipped) b_V.
  T cdv(0.0);
  for (int i = 0; i < n; ++i) cdv = cdv + T(kb.shape[static_cast<std::size_t>(i)]) * dv[static_cast<std::size_t>(i)];
  const T factor = T(-(Interval(1.0) + kb.restitution) / kb.W) * cdv;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    out.push_back(dv[k] + factor * T(kb.contact[k]) - b[1 + static_cast<std::size_t>(n) + k]);
  }
  return out;
}

// (R_sym, M b + μ e_k, ℓᵀb − 1) at (a, b, μ, p).
template <class T>
std::vector<T> PitchResidual(const Setup& g, const std::vector<T>& x, std::size_t k, const std::vector<double>& ell) {
  const std::size_t h = g.N();
  const std::vector<T> a(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(h));
  const std::vector<T> b(x.begin() + static_cast<std::ptrdiff_t>(h), x.begin() + static_cast<std::ptrdiff_t>(2 * h));
  const T& mu = x[2 * h];
  const T& p = x[2 * h + 1];
  auto out = Residual(g, a, T(0.0), p, false);
  auto mb = AntiTimes(g, a, b, p);
  mb[k] = mb[k] + mu;
  out.insert(out.end(), mb.begin(), mb.end());
  T l(-1.0);
  for (std::size_t i = 0; i < h; ++i) l = l + T(ell[i]) * b[i];
  out.push_back(l);
  return out;
}

// Krawczyk's test on the square system of the columns `unknowns` of J (rows = F), the columns
// `params` held in their boxes (parametric form). x, X: every variable's point and box.
struct Test {
  bool inside = false;
  Eigen::MatrixXd C;
  double delta = std::numeric_limits<double>::infinity();
  std::size_t worst = 0;
};
Test Krawczyk2(const Setup& g, std::size_t k, const std::vector<double>& ell, const std::vector<double>& x,
               const std::vector<Interval>& X, const std::vector<std::size_t>& unknowns,
               const std::vector<std::size_t>& params) {
  Test t;
  const std::vector<Interval> xi(x.begin(), x.end());
  const auto F = PitchResidual(g, xi, k, ell);
  std::vector<Dual> d;
  for (std::size_t c = 0; c < X.size(); ++c) d.push_back(Dual::Variable(X[c], c, X.size()));
  const auto R = PitchResidual(g, d, k, ell);
  const std::size_t V = unknowns.size();
  const auto J = [&](std::size_t r, std::size_t c) { return c < R[r].d.size() ? R[r].d[c] : Interval(0.0); };
  Eigen::MatrixXd mid(static_cast<Eigen::Index>(V), static_cast<Eigen::Index>(V));
  for (std::size_t r = 0; r < V; ++r)
    for (std::size_t c = 0; c < V; ++c) mid(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = J(r, unknowns[c]).mid();
  t.C = mid.inverse();
  t.inside = t.C.allFinite() && F.size() == V;
  if (!t.inside) return t;
  double worst = -1, delta = 0;
  for (std::size_t r = 0; r < V; ++r) {
    const std::size_t u = unknowns[r];
    Interval v(x[u]), rowsum(0.0);
    std::vector<Interval> cp(params.size());
    for (std::size_t l = 0; l < V; ++l) {
      const Interval c(t.C(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(l)));
      v -= c * F[l];
      for (std::size_t q = 0; q < params.size(); ++q) cp[q] += c * J(l, params[q]);
      Interval row(r == l ? 1.0 : 0.0);
      for (std::size_t j = 0; j < V; ++j) row -= Interval(t.C(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(j))) * J(j, unknowns[l]);
      v += row * (X[unknowns[l]] - Interval(x[unknowns[l]]));
      rowsum += Abs(row);
    }
    for (std::size_t q = 0; q < params.size(); ++q) v -= cp[q] * (X[params[q]] - Interval(x[params[q]]));
    delta = std::max(delta, rowsum.hi());
    const bool in = v.InsideOpen(X[u].lo(), X[u].hi());
    const double excess = v.finite() ? std::max(v.hi() - X[u].hi(), X[u].lo() - v.lo()) / (X[u].hi() - X[u].lo()) : 1e300;
    if (excess > worst) {
      worst = excess;
      t.worst = u;
    }
    t.inside = t.inside && in;
  }
  t.delta = std::isfinite(delta) ? delta : std::numeric_limits<double>::infinity();
  return t;
}

}  // namespace

Outcome ProveOrbitPitchfork(const IntervalModel& model, bool mirrored, const ImpactGuess& guess, bool frequency,
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
  if (model.contact_count() != 2) {
    out.reason = fmt::format("the model has {} contact(s): a symmetry-breaking pitchfork needs two mirrored ones",
                             model.contact_count());
    return out;
  }
  if (model.contacts[0].restitution_text != model.contacts[1].restitution_text) {
    out.reason = "the two restitutions differ: the model is not symmetric, no symmetry-breaking pitchfork to prove";
    return out;
  }
  if (model.contacts[0].stop_text != model.contacts[1].stop_text) {
    out.reason = "the two stops are not symmetric (e_1 ≠ e_0): no symmetry-breaking pitchfork to prove";
    return out;
  }
  if (g.count == 0 || !MakeSymmetric(g, guess, mirrored, 2 * M_PI / (frequency ? located : model.frequency.mid()))) {
    out.reason = "the orbit found is not the symmetric orbit of a mirrored model (one impact on each contact, half a "
                 "period apart, the second state the first mirrored): no symmetry-breaking pitchfork to prove";
    return out;
  }
  const std::size_t h = g.N(), V = 2 * h + 2;  // (a, b, μ, p)
  std::vector<double> x(V, 0.0);
  x[0] = guess.times[0];
  for (int i = 0; i < g.n; ++i) {
    x[1 + static_cast<std::size_t>(i)] = guess.X[0](i);
    x[1 + static_cast<std::size_t>(g.n + i)] = guess.V[0](i);
  }
  x[V - 1] = located;
  // b and ℓ: the near-null vector of M at the guess (SVD), k: the row the left one weighs most.
  const auto antiMid = [&](const std::vector<double>& xx) {
    Eigen::MatrixXd M(static_cast<Eigen::Index>(h), static_cast<Eigen::Index>(h));
    std::vector<Interval> a(xx.begin(), xx.begin() + static_cast<std::ptrdiff_t>(h));
    for (std::size_t c = 0; c < h; ++c) {
      std::vector<Interval> e(h, Interval(0.0));
      e[c] = Interval(1.0);
      const auto col = AntiTimes(g, a, e, Interval(xx[V - 1]));
      for (std::size_t r = 0; r < h; ++r) M(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = col[r].mid();
    }
    return M;
  };
  // Newton on R_sym at the located value first (the orbit from the search is within its tolerance).
  for (int it = 0; it < 8; ++it) {
    std::vector<Interval> ai(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(h));
    std::vector<Dual> ad;
    for (std::size_t c = 0; c < h; ++c) ad.push_back(Dual::Variable(ai[c], c, h));
    const auto R = Residual(g, ad, Dual(0.0), Dual(Interval(located)), false);
    Eigen::MatrixXd J(static_cast<Eigen::Index>(h), static_cast<Eigen::Index>(h));
    Eigen::VectorXd F(static_cast<Eigen::Index>(h));
    for (std::size_t r = 0; r < h; ++r) {
      F(static_cast<Eigen::Index>(r)) = R[r].v.mid();
      for (std::size_t c = 0; c < h; ++c) J(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = c < R[r].d.size() ? R[r].d[c].mid() : 0.0;
    }
    const Eigen::VectorXd dx = J.fullPivLu().solve(F);
    if (!dx.allFinite()) break;
    for (std::size_t c = 0; c < h; ++c) x[c] -= dx(static_cast<Eigen::Index>(c));
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(antiMid(x), Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::VectorXd right = svd.matrixV().col(static_cast<Eigen::Index>(h) - 1);
  const Eigen::VectorXd left = svd.matrixU().col(static_cast<Eigen::Index>(h) - 1);
  std::size_t k = 0;
  for (std::size_t r = 1; r < h; ++r)
    if (std::abs(left(static_cast<Eigen::Index>(r))) > std::abs(left(static_cast<Eigen::Index>(k)))) k = r;
  std::vector<double> ell(h);
  for (std::size_t c = 0; c < h; ++c) {
    ell[c] = right(static_cast<Eigen::Index>(c));
    x[h + c] = right(static_cast<Eigen::Index>(c));
  }
  // Newton on E (μ = 0, p free).
  std::vector<std::size_t> ext, fam;
  for (std::size_t c = 0; c < 2 * h; ++c) {
    ext.push_back(c);
    fam.push_back(c);
  }
  ext.push_back(V - 1);
  fam.push_back(2 * h);
  bool converged = false;
  for (int it = 0; it < 40 && !converged; ++it) {
    std::vector<Dual> xd;
    for (std::size_t c = 0; c < V; ++c) xd.push_back(Dual::Variable(Interval(x[c]), c, V));
    const auto R = PitchResidual(g, xd, k, ell);
    Eigen::MatrixXd J(static_cast<Eigen::Index>(ext.size()), static_cast<Eigen::Index>(ext.size()));
    Eigen::VectorXd F(static_cast<Eigen::Index>(ext.size()));
    for (std::size_t r = 0; r < ext.size(); ++r) {
      F(static_cast<Eigen::Index>(r)) = R[r].v.mid();
      for (std::size_t c = 0; c < ext.size(); ++c)
        J(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = ext[c] < R[r].d.size() ? R[r].d[ext[c]].mid() : 0.0;
    }
    const Eigen::VectorXd dx = J.fullPivLu().solve(F);
    if (!dx.allFinite()) break;
    double big = 0;
    for (std::size_t c = 0; c < ext.size(); ++c) {
      x[ext[c]] -= dx(static_cast<Eigen::Index>(c));
      big = std::max(big, std::abs(dx(static_cast<Eigen::Index>(c))) / (1 + std::abs(x[ext[c]])));
    }
    converged = big < 1e-15 && it > 2;
  }
  if (!converged) {
    out.reason = "Newton on the symmetric orbit with a singular antisymmetric block does not converge from the located "
                 "point: no pitchfork found to prove";
    return out;
  }
  const double pstar = x[V - 1];
  const double center = bracket > 0 && std::abs(pstar - located) <= bracket + 1e-10 * (1 + std::abs(located)) ? pstar : located;
  // The family's tangent d(a, b, μ)/dp for the box's radii.
  std::vector<double> dxdp(V, 0.0);
  {
    std::vector<Dual> xd;
    for (std::size_t c = 0; c < V; ++c) xd.push_back(Dual::Variable(Interval(x[c]), c, V));
    const auto R = PitchResidual(g, xd, k, ell);
    Eigen::MatrixXd J(static_cast<Eigen::Index>(fam.size()), static_cast<Eigen::Index>(fam.size()));
    Eigen::VectorXd b(static_cast<Eigen::Index>(fam.size()));
    for (std::size_t r = 0; r < fam.size(); ++r) {
      b(static_cast<Eigen::Index>(r)) = -(V - 1 < R[r].d.size() ? R[r].d[V - 1].mid() : 0.0);
      for (std::size_t c = 0; c < fam.size(); ++c)
        J(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = fam[c] < R[r].d.size() ? R[r].d[fam[c]].mid() : 0.0;
    }
    const Eigen::VectorXd d = J.fullPivLu().solve(b);
    for (std::size_t c = 0; c < fam.size() && d.allFinite(); ++c) dxdp[fam[c]] = d(static_cast<Eigen::Index>(c));
  }
  double top = model.frequency.hi() + (frequency ? 1.0 : 0.0);
  for (const auto& w : model.omega) top = std::max(top, w.hi());
  std::string last;
  for (double half = 1e-12 * (1 + std::abs(center)); 2 * half <= 1e-10 && !budget.passed(); half *= 4) {
    const std::string lo = Dec(center - half), hi = Dec(center + half);
    const Interval P = Union(Interval::Decimal(lo), Interval::Decimal(hi));
    if (!(P.lo() < pstar && pstar < P.hi())) {
      last = fmt::format("the antisymmetric block is singular at {} = {} (Newton), outside [{}, {}]: no pitchfork is "
                         "proven there", name, Dec(pstar), lo, hi);
      continue;
    }
    const double reach = std::max(P.hi() - pstar, pstar - P.lo());
    std::vector<Interval> X;
    Test f, e;
    bool boxed = false;
    for (double r0 = 1e-13; r0 <= 1e-9 && !boxed; r0 *= 10) {
      X.clear();
      for (std::size_t c = 0; c + 1 < V; ++c) {
        const double rad = r0 * (1 + std::abs(x[c])) + 2 * std::abs(dxdp[c]) * reach;
        X.push_back(Interval::Hull(x[c] - rad, x[c] + rad));
      }
      X.push_back(P);
      f = Krawczyk2(g, k, ell, x, X, fam, {V - 1});
      if (!f.inside) {
        last = fmt::format("the parametric Krawczyk test on the symmetric orbit and its antisymmetric block over [{}, "
                           "{}] fails (unknown {})", lo, hi, f.worst);
        continue;
      }
      std::vector<Interval> Xe = X;
      Xe[2 * h] = Interval(0.0);  // μ = 0
      std::vector<double> xe = x;
      xe[2 * h] = 0.0;
      e = Krawczyk2(g, k, ell, xe, Xe, ext, {});
      if (!e.inside) {
        last = fmt::format("Krawczyk's test on the symmetric orbit with a singular antisymmetric block fails (unknown "
                           "{}): no unique pitchfork proven in [{}, {}]", e.worst, lo, hi);
        continue;
      }
      boxed = true;
    }
    if (!boxed) continue;
    if (!(e.delta < 1)) {
      last = fmt::format("‖I − CJ‖∞ ≤ {} over the box: not below 1", e.delta);
      continue;
    }
    const auto pr = static_cast<Eigen::Index>(ext.size() - 1), kr = static_cast<Eigen::Index>(h + k);
    double cmax = 0;
    for (Eigen::Index r = 0; r <= pr; ++r) cmax = std::max(cmax, std::abs(e.C(r, kr)));
    const Interval dl(e.delta);
    const double spread = (dl / (Interval(1.0) - dl) * Interval(cmax)).hi();
    const Interval dpdmu = -(Interval(e.C(pr, kr)) + Interval::Hull(-spread, spread));
    if (dpdmu.Contains(0.0)) {
      last = fmt::format("dp/dμ is {} over the box: not proven nonzero", dpdmu.ToString());
      continue;
    }
    const Interval slope = Interval(1.0) / dpdmu;
    const std::vector<Interval> A(X.begin(), X.begin() + static_cast<std::ptrdiff_t>(h));
    if (auto fail = OrbitGaps(g, A, P, budget, 0.25 / top, 1.0, 0.0); !fail.empty()) {
      last = std::move(fail);
      continue;
    }
    const double m = 1e-6 * std::max(std::abs(slope.lo()), std::abs(slope.hi())) + (slope.hi() - slope.lo());
    const Interval claim = Interval::Hull(slope.lo() - m, slope.hi() + m);
    interval_text = "[" + lo + ", " + hi + "]";
    out.proven = true;
    out.reason = fmt::format(
        "exactly one {} in [{}, {}] at which the symmetric orbit's antisymmetric block is singular (its period map has "
        "the multiplier +1 with an antisymmetric eigenvector: the symmetry-breaking pitchfork); the bordering μ "
        "(zero exactly there) has dμ/d{} = {}, nonzero over the whole interval: the crossing is transversal",
        name, lo, hi, name, slope.ToString());
    Json box = Json::array();
    for (std::size_t c = 0; c + 1 < V; ++c) box.push_back(Pair(X[c]));
    Json hits = Json::array({g.hits[0], 1 - g.hits[0]});
    out.summary = {{"bifurcation", "pitchfork"},
                   {"parameter", name},
                   {"located", located},
                   {"center", center},
                   {"interval", Json::array({lo, hi})},
                   {"width", P.hi() - P.lo()},
                   {"box_width", P.hi() - P.lo()},
                   {"slope", Pair(claim)},
                   {"impact_contacts", hits},
                   {"symmetric", true},
                   {"period", 1}};
    out.certificate = {{"bifurcation",
                        {{"type", "orbit-pitchfork"},
                         {"parameter", name},
                         {"interval", Json::array({lo, hi})},
                         {"impact_contacts", hits},
                         {"normal", ell},
                         {"row", k},
                         {"midpoint", std::vector<double>(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(2 * h))},
                         {"box", box},
                         {"slope", Pair(claim)}}}};
    return out;
  }
  out.reason = last.empty() ? "the time limit was reached" : last;
  return out;
}

}  // namespace vibro::proof
