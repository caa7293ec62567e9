// Floquet multipliers of an enclosed monodromy matrix (proof_common.hpp). Stability is claimed
// only when every enclosure lies inside the unit disc (stable) or one lies outside it (unstable).
#include <complex>

#include <Eigen/Eigenvalues>

#include "proof/proof_common.hpp"

namespace vibro::proof {
namespace {

Json Multiplier(const Interval& re, const Interval& im) { return {{"re", Pair(re)}, {"im", Pair(im)}}; }

}  // namespace

Spectrum Multipliers(const std::vector<std::vector<Interval>>& M) {
  Spectrum out;
  std::vector<Interval> modulus2;
  if (M.size() == 2) {
    // λ² − tr λ + det = 0: λ = (tr ± √(tr² − 4 det))/2.
    const Interval tr = M[0][0] + M[1][1], det = M[0][0] * M[1][1] - M[0][1] * M[1][0];
    const Interval disc = Sqr(tr) - Interval(4.0) * det, half = Interval(0.5);
    if (disc.Positive()) {
      const Interval root = Sqrt(disc);
      for (const Interval& l : {half * (tr + root), half * (tr - root)}) {
        out.multipliers.push_back(Multiplier(l, 0.0));
        modulus2.push_back(Sqr(l));
      }
    } else if (disc.Negative()) {
      const Interval re = half * tr, im = half * Sqrt(-disc);
      out.multipliers.push_back(Multiplier(re, im));
      out.multipliers.push_back(Multiplier(re, -im));
      modulus2 = {det, det};  // |λ|² = det for a complex pair
    } else {
      // Real or complex: both lie in tr/2 ± (√disc⁺ ∪ i√(−disc)⁺)/2.
      const Interval re = half * tr + Interval::Hull(-1, 1) * half * Sqrt(disc);
      const Interval im = Interval::Hull(-1, 1) * half * Sqrt(-disc);
      out.multipliers.push_back(Multiplier(re, im));
      out.multipliers.push_back(Multiplier(re, im));
      modulus2 = {Sqr(re) + Sqr(im), Sqr(re) + Sqr(im)};
      out.note = "the discriminant of the 2 x 2 monodromy is not separated from 0";
    }
    out.enclosed = true;
  } else {
    Eigen::MatrixXd mid(static_cast<Eigen::Index>(M.size()), static_cast<Eigen::Index>(M.size()));
    for (std::size_t i = 0; i < M.size(); ++i)
      for (std::size_t j = 0; j < M.size(); ++j) mid(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = M[i][j].mid();
    Eigen::EigenSolver<Eigen::MatrixXd> es(mid);
    std::vector<std::complex<double>> approx;
    std::vector<std::vector<std::complex<double>>> vectors(M.size());
    for (Eigen::Index i = 0; i < mid.rows(); ++i) {
      approx.push_back(es.eigenvalues()(i));
      for (Eigen::Index j = 0; j < mid.rows(); ++j) vectors[static_cast<std::size_t>(i)].push_back(es.eigenvectors()(i, j));
    }
    const auto e = Eigenvalues(M, approx, vectors);
    if (!e) {
      out.note = "the eigenvalues of the enclosed monodromy could not be separated (Rump's test)";
      return out;
    }
    for (const auto& z : *e) {
      out.multipliers.push_back(Multiplier(z.re, z.im));
      modulus2.push_back(Sqr(z.re) + Sqr(z.im));
    }
    out.enclosed = true;
  }
  bool inside = true, outside = false;
  for (const auto& m2 : modulus2) {
    inside = inside && m2.hi() < 1;
    outside = outside || m2.lo() > 1;
  }
  out.stability = outside ? "unstable" : inside ? "stable" : "undecided";
  if (!outside && !inside && out.note.empty()) out.note = "a multiplier enclosure meets the unit circle";
  return out;
}

}  // namespace vibro::proof
