// Krawczyk's test on a square system F(u) = 0 given as a residual template (docs/prove.md,
// "Impacting orbits" 1.): K(U) = ũ − C F(ũ) + (I − C J(U))(U − ũ) ⊂ int U ⇒ exactly one zero in U,
// with J(U) the Jacobian enclosed over the box by forward differentiation (Dual) and C ≈ J(ũ)⁻¹.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <Eigen/Dense>

#include "proof/enclosure.hpp"

namespace vibro::proof {

struct KrawczykBox {
  bool inside = false;
  std::vector<double> lo, hi;
  std::vector<Interval> K;
  Eigen::MatrixXd C;
  std::size_t worst = 0;  // the component farthest from inside
};

template <class Residual>
std::vector<std::vector<Interval>> JacobianOver(const Residual& residual, const std::vector<Interval>& u) {
  const std::size_t N = u.size();
  std::vector<Dual> ud;
  for (std::size_t k = 0; k < N; ++k) ud.push_back(Dual::Variable(u[k], k, N));
  const std::vector<Dual> r = residual(ud);
  std::vector<std::vector<Interval>> J(N, std::vector<Interval>(N));
  for (std::size_t p = 0; p < N; ++p)
    for (std::size_t l = 0; l < N && l < r[p].d.size(); ++l) J[p][l] = r[p].d[l];
  return J;
}

inline Eigen::MatrixXd MidMatrix(const std::vector<std::vector<Interval>>& a) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(a.size()), static_cast<Eigen::Index>(a.size()));
  for (std::size_t p = 0; p < a.size(); ++p)
    for (std::size_t l = 0; l < a.size(); ++l) m(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(l)) = a[p][l].mid();
  return m;
}

// Newton in double on the midpoints.
template <class Residual>
std::vector<double> NewtonRefine(const Residual& residual, std::vector<double> u, int rounds = 8) {
  for (int it = 0; it < rounds; ++it) {
    const std::vector<Interval> pu(u.begin(), u.end());
    const std::vector<Interval> r = residual(pu);
    Eigen::VectorXd F(static_cast<Eigen::Index>(u.size()));
    for (std::size_t p = 0; p < u.size(); ++p) F(static_cast<Eigen::Index>(p)) = r[p].mid();
    const Eigen::VectorXd du = MidMatrix(JacobianOver(residual, pu)).fullPivLu().solve(F);
    if (!du.allFinite()) break;
    for (std::size_t p = 0; p < u.size(); ++p) u[p] -= du(static_cast<Eigen::Index>(p));
  }
  return u;
}

// The test on the box of half-width radius (1 + |u_p|) around u.
template <class Residual>
KrawczykBox KrawczykTest(const Residual& residual, const std::vector<double>& u, double radius) {
  KrawczykBox k;
  const std::size_t N = u.size();
  std::vector<Interval> U;
  for (std::size_t p = 0; p < N; ++p) {
    const double d = radius * (1 + std::abs(u[p]));
    k.lo.push_back(u[p] - d);
    k.hi.push_back(u[p] + d);
    U.push_back(Interval::Hull(k.lo.back(), k.hi.back()));
  }
  const std::vector<Interval> F = residual(std::vector<Interval>(u.begin(), u.end()));
  const auto J = JacobianOver(residual, U);
  k.C = MidMatrix(J).inverse();
  k.inside = k.C.allFinite();
  double worst = -1;
  for (std::size_t p = 0; p < N; ++p) {
    Interval v(u[p]);
    for (std::size_t l = 0; l < N; ++l) {
      v -= Interval(k.C(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(l))) * F[l];
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

}  // namespace vibro::proof
