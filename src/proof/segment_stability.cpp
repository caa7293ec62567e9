// Stability along a segment in the forcing frequency (docs/prove.md "Stability along a segment").
//
// A segment's box spans the orbits of its whole interval P, and the monodromy enclosed over it is too
// wide for its eigenvalues to be enclosed one by one. Stability needs less: the spectral radius below
// 1 for every ω ∈ P. The orbits of a sub-piece P_k ⊂ P lie in the sub-tube T_k = ũ + a(P_k − ω̃) + W
// (impact_proof.cpp TangentTest: for every p ∈ P the orbit is ũ + a(p − ω̃) + w, w ∈ W), and in
// E_k = T_k ∩ K_k(T_k), K_k Krawczyk's operator over P_k (iterated), so the monodromy over (E_k, P_k),
// an interval matrix 𝐌_k, holds the monodromy of every orbit of P_k. For any
// invertible S, ρ(M) = ρ(S⁻¹MS) ≤ ‖S⁻¹MS‖ in any induced norm. With S the real eigenvector basis of the
// midpoint of 𝐌_k (a real eigenvalue: its eigenvector; a complex pair: the real and imaginary parts of
// one eigenvector, on which M acts as [[α, β], [−β, α]], of 2-norm |μ|), the norm ‖x‖ = max_b ‖x_b‖₂
// over those blocks, whose induced norm is at most max_b Σ_c ‖A_bc‖₂, and R ≈ S⁻¹ in floating point,
// E = I − RS enclosed: S⁻¹ = (I − E)⁻¹R, so with ‖E‖ ≤ δ < 1
//   ρ(M) ≤ ‖R M S‖/(1 − δ)   for every M ∈ 𝐌_k.
// At the midpoint the bound is max|μ|; it grows with the width of 𝐌_k, so a sub-piece where it is
// not below 1 is halved (at a decimal), up to kMaxDepth times.
#include <algorithm>
#include <cmath>
#include <complex>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "proof/proof_common.hpp"

namespace vibro::proof {
namespace {

using Matrix = std::vector<std::vector<Interval>>;
constexpr int kMaxDepth = 16;  // pieces down to 2^-16 of the segment's

std::string DecimalOf(double x) { return fmt::format("{}", x); }

// An upper bound of the 2-norm of the block rows [r0, r0 + rb) × columns [c0, c0 + cb) of A.
double BlockNorm(const Matrix& A, std::size_t r0, std::size_t rb, std::size_t c0, std::size_t cb) {
  if (rb == 1 && cb == 1) return Abs(A[r0][c0]).hi();
  Interval frob(0.0);
  for (std::size_t i = r0; i < r0 + rb; ++i)
    for (std::size_t j = c0; j < c0 + cb; ++j) frob += Sqr(A[i][j]);
  if (rb == 2 && cb == 2) {
    // σ_max² = (F + √(F² − 4D²))/2, F = ‖A‖_F², D = det A: increasing in F, decreasing in D².
    const Interval det = A[r0][c0] * A[r0 + 1][c0 + 1] - A[r0][c0 + 1] * A[r0 + 1][c0];
    const Interval F(frob.hi()), D2(Sqr(det).lo());
    const Interval s2 = (F + Sqrt(Sqr(F) - Interval(4.0) * D2)) * Interval(0.5);
    return Sqrt(s2).hi();
  }
  return Sqrt(frob).hi();  // the Frobenius norm bounds the 2-norm
}

// max_b Σ_c ‖A_bc‖₂, rounded up: the induced norm of A for ‖x‖ = max_b ‖x_b‖₂ is at most this.
double InducedNorm(const Matrix& A, const std::vector<int>& blocks) {
  double worst = 0;
  std::size_t r0 = 0;
  for (const int rb : blocks) {
    Interval sum(0.0);
    std::size_t c0 = 0;
    for (const int cb : blocks) {
      sum += Interval(BlockNorm(A, r0, static_cast<std::size_t>(rb), c0, static_cast<std::size_t>(cb)));
      c0 += static_cast<std::size_t>(cb);
    }
    worst = std::max(worst, sum.hi());
    r0 += static_cast<std::size_t>(rb);
  }
  return worst;
}

struct Bound {
  bool ok = false;
  double radius = 0;  // ρ(M) ≤ radius for every M of the interval matrix
  double mid = 0;     // the midpoint's spectral radius (floating point: to choose the pieces and the claim)
  Eigen::MatrixXd S;
  std::vector<int> blocks;
};

// The similarity S from the midpoint's eigenvectors, and the bound ‖R M S‖/(1 − ‖I − RS‖).
Bound RadiusBound(const Matrix& M) {
  Bound b;
  const auto n = static_cast<Eigen::Index>(M.size());
  Eigen::MatrixXd mid(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) {
      if (!M[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)].finite()) return b;
      mid(i, j) = M[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)].mid();
    }
  const Eigen::EigenSolver<Eigen::MatrixXd> es(mid);
  if (es.info() != Eigen::Success) return b;
  b.S = Eigen::MatrixXd::Zero(n, n);
  Eigen::Index col = 0;
  for (Eigen::Index e = 0; e < n; ++e) b.mid = std::max(b.mid, std::abs(es.eigenvalues()(e)));
  for (Eigen::Index e = 0; e < n && col < n; ++e) {
    const std::complex<double> lambda = es.eigenvalues()(e);
    Eigen::VectorXcd v = es.eigenvectors().col(e);
    v /= v.norm();
    if (lambda.imag() == 0) {
      b.S.col(col++) = v.real();
      b.blocks.push_back(1);
    } else if (lambda.imag() > 0 && col + 1 < n) {
      b.S.col(col++) = v.real();
      b.S.col(col++) = v.imag();
      b.blocks.push_back(2);
    }
  }
  if (col != n) return b;
  const Eigen::MatrixXd R = b.S.inverse();
  if (!R.allFinite()) return b;
  const auto N = M.size();
  const auto at = [](const Eigen::MatrixXd& A, std::size_t i, std::size_t j) {
    return Interval(A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)));
  };
  Matrix MS(N, std::vector<Interval>(N)), B(N, std::vector<Interval>(N)), E(N, std::vector<Interval>(N));
  for (std::size_t i = 0; i < N; ++i)
    for (std::size_t j = 0; j < N; ++j)
      for (std::size_t k = 0; k < N; ++k) MS[i][j] += M[i][k] * at(b.S, k, j);
  for (std::size_t i = 0; i < N; ++i)
    for (std::size_t j = 0; j < N; ++j) {
      E[i][j] = Interval(i == j ? 1.0 : 0.0);
      for (std::size_t k = 0; k < N; ++k) {
        B[i][j] += at(R, i, k) * MS[k][j];
        E[i][j] -= at(R, i, k) * at(b.S, k, j);
      }
    }
  const double delta = InducedNorm(E, b.blocks);
  if (!(delta < 1)) return b;
  b.radius = (Interval(InducedNorm(B, b.blocks)) / (Interval(1.0) - Interval(delta))).hi();
  b.ok = std::isfinite(b.radius) && b.radius < 1;
  return b;
}

}  // namespace

SegmentStability ProveSegmentStability(const std::function<IntervalModel(const std::string&)>& model_at,
                                       const std::string& lo, const std::string& hi, const Json& cert, int q,
                                       const Budget& budget) {
  SegmentStability out;
  out.certificate = Json::array();
  const auto& u = cert.at("midpoint");
  const auto& tangent = cert.at("tangent");
  const double centre = tangent.at("centre").get<double>();
  const auto& a = tangent.at("direction");
  const auto& W = tangent.at("box");
  const std::size_t N = u.size();
  const IntervalModel first = model_at("[" + lo + ", " + hi + "]");
  const int per = 2 * first.n + 1;
  const int impacts = static_cast<int>(N) / per;
  std::vector<int> contacts(static_cast<std::size_t>(impacts), 0);
  if (cert.contains("impact_contacts")) contacts = cert.at("impact_contacts").get<std::vector<int>>();
  std::function<bool(const std::string&, const std::string&, int)> sub = [&](const std::string& x0,
                                                                             const std::string& x1, int depth) {
    if (budget.passed()) {
      out.reason = "the time limit was reached";
      return false;
    }
    const std::string text = "[" + x0 + ", " + x1 + "]";
    const IntervalModel mk = model_at(text);
    // The orbits of P_k: a tube of their own (TangentTest over P_k, W_k ~ |P_k|² of the curvature),
    // inside the segment's tube for every ω ∈ P_k, so that its orbit is the segment's.
    std::vector<double> guess;
    const double pm = mk.frequency.mid();
    for (std::size_t p = 0; p < N; ++p) guess.push_back(u[p].get<double>() + a[p].get<double>() * (pm - centre));
    const auto tube = TangentOrbits(mk, contacts, impacts, q, guess, 1e-13);
    bool within = tube.proven;
    for (std::size_t p = 0; p < N && within; ++p) {
      const Interval d = Interval(tube.u[p]) - Interval(u[p].get<double>()) +
                         Interval(a[p].get<double>()) * (Interval(centre) - Interval(tube.centre)) +
                         (Interval(tube.tangent[p]) - Interval(a[p].get<double>())) * (mk.frequency - Interval(tube.centre)) +
                         tube.W[p];
      within = Interval::Hull(W[p][0].get<double>(), W[p][1].get<double>()).Contains(d);
    }
    bool finite = within;
    for (std::size_t p = 0; p < N && finite; ++p) finite = tube.K[p].finite();
    const std::vector<Interval>& T = tube.K;
    const auto Mk = finite ? ImpactMonodromy(mk, contacts, impacts, q, T) : Matrix{};
    const auto bound = finite ? RadiusBound(Mk) : Bound{};
    // A sub-piece is taken when the bound spends at most half the margin 1 − ρ_mid; the claim is
    // 1 − (1 − ρ_mid)/8 (< 1), so that the checker's enclosure of the same norm, wider than the
    // prover's (its monodromy over its own enclosure of the orbits: up to 1.5 times in the excess
    // over ρ_mid on the tube), stays below it.
    const bool tight = bound.ok && bound.mid < 1 && bound.radius <= 1 - (1 - bound.mid) / 2;
    if (within && tight) {
      const double claim = 1 - (1 - bound.mid) / 8;
      Json S = Json::array(), Wk = Json::array();
      for (Eigen::Index i = 0; i < bound.S.rows(); ++i) {
        Json row = Json::array();
        for (Eigen::Index j = 0; j < bound.S.cols(); ++j) row.push_back(bound.S(i, j));
        S.push_back(row);
      }
      for (const auto& w : tube.W) Wk.push_back(Pair(w));
      out.certificate.push_back({{"interval", text}, {"midpoint", tube.u},
                                 {"tangent", {{"centre", tube.centre}, {"direction", tube.tangent}, {"box", Wk}}},
                                 {"similarity", S}, {"blocks", bound.blocks}, {"bound", claim}});
      out.bound = std::max(out.bound, claim);
      return true;
    }
    const double v0 = Interval::Decimal(x0).mid(), v1 = Interval::Decimal(x1).mid(), vm = v0 + (v1 - v0) / 2;
    if (depth >= kMaxDepth || !(v0 < vm && vm < v1)) {
      out.reason = fmt::format("the spectral radius of the monodromy is not proven below 1 over frequency in {} "
                               "(bound {:.6g})", text, bound.radius);
      return false;
    }
    const std::string xm = DecimalOf(vm);
    return sub(x0, xm, depth + 1) && sub(xm, x1, depth + 1);
  };
  out.proven = sub(lo, hi, 0);
  out.pieces = static_cast<int>(out.certificate.size());
  return out;
}

}  // namespace vibro::proof
