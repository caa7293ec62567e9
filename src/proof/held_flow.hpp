// The flow of the structure held at a contact (docs/model.md §4.2, docs/prove.md "Sticking orbits
// of several modes"), enclosed. While contact 0 is held (cᵀX = x0, cᵀẊ = 0, R ≥ 0) the modes obey
//   Ẍ = Π(−Ω²X − DẊ + T_A f sin ωt),   Π = I − T_B cᵀ/s_B,   D = diag(2ζ_iω_i),
// and the reaction is R = (cᵀΩ²X + cᵀDẊ − s_A f sin ωt)/s_B (the paper's eq. (5), with damping).
// With Z = (X, Ẋ, sin ωt, cos ωt) this is the linear system Ż = A Z, so Z(t0 + s) = e^{As} Z(t0) and
// R = ℓᵀZ. e^{As} is enclosed by its Taylor series with a bound on the remainder (scaling and
// squaring), for every s of an interval: no eigen-decomposition, damped or not.
#pragma once

#include <vector>

#include "proof/enclosure.hpp"

namespace vibro::proof {

using IntervalMatrix = std::vector<std::vector<Interval>>;

struct HeldFlow {
  int n = 0;            // modes; Z has 2n + 2 components
  IntervalMatrix A;     // (2n + 2) × (2n + 2)
  std::vector<Interval> reaction;  // ℓ: R = ℓᵀZ
  std::vector<Interval> reaction_rate;  // ℓᵀA: Ṙ = (ℓᵀA) Z
};

// The held flow of contact 0 of the model.
HeldFlow MakeHeldFlow(const IntervalModel& m);

// e^{A s} for every s in `s` (s ≥ 0 or not), enclosed.
IntervalMatrix HeldExp(const HeldFlow& h, const Interval& s);

IntervalMatrix MatMul(const IntervalMatrix& a, const IntervalMatrix& b);
std::vector<Interval> MatVec(const IntervalMatrix& a, const std::vector<Interval>& z);

// Z = (X, V, sin ωt, cos ωt).
template <class T>
std::vector<T> HeldState(const IntervalModel& m, const T& t, const std::vector<T>& X, const std::vector<T>& V) {
  std::vector<T> z(X);
  z.insert(z.end(), V.begin(), V.end());
  const T wt = T(m.frequency) * t;
  z.push_back(Sin(wt));
  z.push_back(Cos(wt));
  return z;
}

template <class T>
T Dot(const std::vector<Interval>& l, const std::vector<T>& z) {
  T sum(0.0);
  for (std::size_t k = 0; k < l.size(); ++k) sum = sum + T(l[k]) * z[k];
  return sum;
}

// Z(t0 + s) = e^{As} Z(t0), s and Z(t0) enclosed (Interval) or with their gradients (Dual: the
// gradient of e^{As}Z is e^{As}∇Z + A e^{As} Z ∇s, with e^{As} over the enclosure of s).
std::vector<Interval> HeldAdvance(const HeldFlow& h, const std::vector<Interval>& z, const Interval& s);
std::vector<Dual> HeldAdvance(const HeldFlow& h, const std::vector<Dual>& z, const Dual& s);

}  // namespace vibro::proof
