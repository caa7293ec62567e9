// The held flow, enclosed (held_flow.hpp, docs/prove.md "Sticking orbits of several modes").
#include "proof/held_flow.hpp"

#include <algorithm>
#include <cmath>

namespace vibro::proof {
namespace {

constexpr int kTaylorTerms = 24;

double NormInfHi(const IntervalMatrix& a) {
  double norm = 0;
  for (const auto& row : a) {
    double sum = 0;
    for (const auto& x : row) sum += std::max(std::abs(x.lo()), std::abs(x.hi()));
    norm = std::max(norm, sum);
  }
  return norm * (1 + 1e-12);  // rounded up: the sum of the row's bounds, each already outward
}

IntervalMatrix Identity(std::size_t N) {
  IntervalMatrix I(N, std::vector<Interval>(N));
  for (std::size_t i = 0; i < N; ++i) I[i][i] = 1.0;
  return I;
}

// e^B for every B in the interval matrix b, when ‖b‖∞ ≤ β ≤ 1/2: the series to kTaylorTerms terms
// plus every entry's remainder, |Σ_{j>N} B^j/j!| ≤ β^{N+1}/(N+1)! · 1/(1 − β/(N+2)) (in ‖·‖∞).
IntervalMatrix ExpSmall(const IntervalMatrix& b, double beta) {
  const std::size_t N = b.size();
  IntervalMatrix sum = Identity(N), term = Identity(N);
  for (int j = 1; j <= kTaylorTerms; ++j) {
    term = MatMul(term, b);
    const Interval inv = Interval(1.0) / Interval(static_cast<double>(j));
    for (auto& row : term)
      for (auto& x : row) x *= inv;
    for (std::size_t i = 0; i < N; ++i)
      for (std::size_t k = 0; k < N; ++k) sum[i][k] += term[i][k];
  }
  Interval rest = Interval(1.0);
  for (int j = 1; j <= kTaylorTerms + 1; ++j) rest = rest * Interval(beta) / Interval(static_cast<double>(j));
  rest = rest / (Interval(1.0) - Interval(beta) / Interval(static_cast<double>(kTaylorTerms + 2)));
  const Interval pad = Interval::Hull(-rest.hi(), rest.hi());
  for (auto& row : sum)
    for (auto& x : row) x += pad;
  return sum;
}

// e^{A s} for every s in s (a point or a narrow interval): scaling by 2^−k, the series, k squarings.
IntervalMatrix ExpScaled(const IntervalMatrix& A, const Interval& s) {
  const std::size_t N = A.size();
  IntervalMatrix b(N, std::vector<Interval>(N));
  for (std::size_t i = 0; i < N; ++i)
    for (std::size_t k = 0; k < N; ++k) b[i][k] = A[i][k] * s;
  const double norm = NormInfHi(b);
  int k = 0;
  while (std::ldexp(norm, -k) > 0.5 && k < 60) ++k;
  const Interval scale(std::ldexp(1.0, -k));
  for (auto& row : b)
    for (auto& x : row) x *= scale;
  IntervalMatrix e = ExpSmall(b, std::ldexp(norm, -k));
  for (int j = 0; j < k; ++j) e = MatMul(e, e);
  return e;
}

}  // namespace

IntervalMatrix MatMul(const IntervalMatrix& a, const IntervalMatrix& b) {
  const std::size_t N = a.size(), K = b.size(), P = b.empty() ? 0 : b[0].size();
  IntervalMatrix c(N, std::vector<Interval>(P));
  for (std::size_t i = 0; i < N; ++i)
    for (std::size_t k = 0; k < K; ++k)
      for (std::size_t j = 0; j < P; ++j) c[i][j] += a[i][k] * b[k][j];
  return c;
}

std::vector<Interval> MatVec(const IntervalMatrix& a, const std::vector<Interval>& z) {
  std::vector<Interval> out(a.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t k = 0; k < z.size(); ++k) out[i] += a[i][k] * z[k];
  return out;
}

HeldFlow MakeHeldFlow(const IntervalModel& m) {
  HeldFlow h;
  h.n = m.n;
  const auto n = static_cast<std::size_t>(m.n), N = 2 * n + 2;
  const auto& hit = m.contacts[0];
  h.A.assign(N, std::vector<Interval>(N));
  std::vector<Interval> w2(n), D(n);
  for (std::size_t i = 0; i < n; ++i) {
    w2[i] = Sqr(m.omega[i]);
    D[i] = m.damped() ? Interval(2.0) * m.sigma[i] : Interval(0.0);
  }
  Interval sA(0.0);
  for (std::size_t i = 0; i < n; ++i) sA += hit.shape[i] * m.forcing[i];
  for (std::size_t i = 0; i < n; ++i) {
    h.A[i][n + i] = 1.0;
    Interval force(0.0);
    for (std::size_t l = 0; l < n; ++l) {
      const Interval pr = Interval(i == l ? 1.0 : 0.0) - hit.contact[i] * hit.shape[l] / hit.W;  // Π_il
      h.A[n + i][l] = -(pr * w2[l]);
      h.A[n + i][n + l] = -(pr * D[l]);
      force += pr * m.forcing[l];
    }
    h.A[n + i][2 * n] = force * m.amplitude;
  }
  h.A[2 * n][2 * n + 1] = m.frequency;
  h.A[2 * n + 1][2 * n] = -m.frequency;
  h.reaction.assign(N, Interval(0.0));
  for (std::size_t i = 0; i < n; ++i) {
    h.reaction[i] = hit.shape[i] * w2[i] / hit.W;
    h.reaction[n + i] = hit.shape[i] * D[i] / hit.W;
  }
  h.reaction[2 * n] = -(sA * m.amplitude / hit.W);
  h.reaction_rate.assign(N, Interval(0.0));
  for (std::size_t k = 0; k < N; ++k)
    for (std::size_t i = 0; i < N; ++i) h.reaction_rate[k] += h.reaction[i] * h.A[i][k];
  return h;
}

IntervalMatrix HeldExp(const HeldFlow& h, const Interval& s) {
  // e^{A s} = e^{A s_lo} e^{A [0, s_hi − s_lo]}: the wide part without squaring its width.
  const double lo = s.lo(), width = s.hi() - s.lo();
  if (width == 0) return ExpScaled(h.A, Interval(lo));
  return MatMul(ExpScaled(h.A, Interval(lo)), ExpScaled(h.A, Interval::Hull(0.0, width)));
}

std::vector<Interval> HeldAdvance(const HeldFlow& h, const std::vector<Interval>& z, const Interval& s) {
  return MatVec(HeldExp(h, s), z);
}

std::vector<Dual> HeldAdvance(const HeldFlow& h, const std::vector<Dual>& z, const Dual& s) {
  const IntervalMatrix E = HeldExp(h, s.v);
  const std::size_t N = z.size();
  std::vector<Interval> zv(N);
  for (std::size_t k = 0; k < N; ++k) zv[k] = z[k].v;
  const auto Ez = MatVec(E, zv), AEz = MatVec(h.A, Ez);
  std::vector<Dual> out(N);
  for (std::size_t i = 0; i < N; ++i) {
    Dual y(Ez[i]);
    for (std::size_t k = 0; k < N; ++k) y.d = detail::Combine(1.0, y.d, E[i][k], z[k].d);
    y.d = detail::Combine(1.0, y.d, AEz[i], s.d);
    out[i] = std::move(y);
  }
  return out;
}

}  // namespace vibro::proof
