// The start of a free flight (docs/model.md §2.1): derivatives of the gap g = x_B − x0 at σ = 0, rigorous
// bounds of its third and fourth derivatives, and the certified window (0, σ_w) free of roots once
// the known zero at σ = 0 is divided out. Shared by both engines (and both scalars).
#pragma once

#include <Eigen/Dense>

#include "dynamics/model_t.hpp"
#include "dynamics/oscillator.hpp"
#include "dynamics/propagator.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

template <class S>
struct FlightJetT {
  S g1, g2, g3;  // g', g'', g''' at σ = 0 (g(0) = 0 on the stop)
  S M3, M4;      // bounds of |g'''|, |g''''| over [0, H]
};
using FlightJet = FlightJetT<double>;

// kWeighted: the gap is Σ c_i X_i with general c_i (a contact other than the scaling's, whose
// c_i are 0 or 1: docs/contacts.md).
template <class S, bool kWeighted>
[[gnu::always_inline]] inline FlightJetT<S> StartJetOf(const ModelT<S>& m, const typename ModelT<S>::Vec& X,
                         const typename ModelT<S>::Vec& V, const S& sp, const S& cp, const S& H,
                         const S* phase = nullptr) {
  FlightJetT<S> j{S(0), S(0), S(0), S(0), S(0)};
  if (!m.harmonics.empty()) {  // a sum of harmonics (docs/harmonics.md): every forcing term summed
    using R = Real<S>;
    const auto& hs = m.harmonics;
    const typename ModelT<S>::Vec f0 = hs.Vector(*phase, 0), f1 = hs.Vector(*phase, 1);
    for (int i = 0; i < m.dof(); ++i) {
      if (m.shape[i] == S(0)) continue;
      const OscillatorT<S> o{m.omega[i], m.zeta[i], S(0)};
      S sf(0), sfw(0), sfw2(0);
      for (const auto& h : hs.h) {
        const S a = R::abs(h.forcing[i]);
        sf += a;
        sfw += a * h.omega;
        sfw2 += a * h.omega * h.omega;
      }
      const S tz = S(2) * o.zeta * o.nu;
      const S acc = -o.nu * o.nu * X[i] - tz * V[i] + f0[i];
      const S jerk = -o.nu * o.nu * V[i] - tz * acc + f1[i];
      const S A = Amplitude<S>(o, X[i], V[i]) + sf * H;
      const S nu = o.nu;
      const S d2 = nu * A + tz * A + sf, d3 = nu * nu * A + tz * d2 + sfw, d4 = nu * nu * d2 + tz * d3 + sfw2;
      const S c = m.shape[i];
      j.g1 += c * V[i];
      j.g2 += c * acc;
      j.g3 += c * jerk;
      j.M3 += R::abs(c) * d3;
      j.M4 += R::abs(c) * d4;
    }
    const S margin = S(1) + S(1e-9);
    j.M3 *= margin;
    j.M4 *= margin;
    return j;
  }
  for (int i = 0; i < m.dof(); ++i) {
    if (m.shape[i] == S(0)) continue;
    const OscillatorT<S> o{m.omega[i], m.zeta[i], m.forcing[i] * m.f};
    const S tz = S(2) * o.zeta * o.nu;
    const S acc = -o.nu * o.nu * X[i] - tz * V[i] + o.F * sp;
    const S jerk = -o.nu * o.nu * V[i] - tz * acc + o.F * m.w * cp;
    const auto b = Bounds<S>(o, m.w, Amplitude<S>(o, X[i], V[i]) + Real<S>::abs(o.F) * H);
    if constexpr (kWeighted) {
      const S c = m.shape[i];
      j.g1 += c * V[i];
      j.g2 += c * acc;
      j.g3 += c * jerk;
      j.M3 += Real<S>::abs(c) * b.d3;
      j.M4 += Real<S>::abs(c) * b.d4;
    } else {
      j.g1 += V[i];
      j.g2 += acc;
      j.g3 += jerk;
      j.M3 += b.d3;
      j.M4 += b.d4;
    }
  }
  const S margin = S(1) + S(1e-9);  // rounding of the evaluated jets
  j.M3 *= margin;
  j.M4 *= margin;
  return j;
}

// With sp, cp = sin φ, cos φ of the flight's phase, already at hand.
// A sum of harmonics needs the phase φ itself (docs/harmonics.md).
template <class S>
[[gnu::always_inline]] inline FlightJetT<S> StartJet(const ModelT<S>& m, const typename ModelT<S>::Vec& X,
                       const typename ModelT<S>::Vec& V, const S& sp, const S& cp, const S& H,
                       const S* phase = nullptr) {
  return m.unit_shape ? StartJetOf<S, false>(m, X, V, sp, cp, H, phase)
                      : StartJetOf<S, true>(m, X, V, sp, cp, H, phase);
}

template <class S>
[[gnu::always_inline]] inline FlightJetT<S> StartJet(const ModelT<S>& m, const typename ModelT<S>::Vec& X,
                       const typename ModelT<S>::Vec& V, const S& phase, const S& H) {
  return StartJet<S>(m, X, V, Real<S>::sin(phase), Real<S>::cos(phase), H, &phase);
}

// σ_w ≤ H with no root of g in (0, σ_w): after an impact g(σ)/σ ≥ g' + g''σ/2 − M3σ²/6; after a
// departure g(σ)/σ² ≥ g''/2 − M3σ/6; after a release g(σ)/σ³ ≥ g'''/6 − M4σ/24. 0 for a generic
// start or when the leading derivative is not positive.
template <class S>
S CertifiedWindow(FlightStart start, const FlightJetT<S>& j, const S& H) {
  const auto cap = [&](const S& w) { return w < H ? w : H; };
  switch (start) {
    case FlightStart::kGeneric:
      return S(0);
    case FlightStart::kAfterImpact: {
      const S v = j.g1, a = j.g2, M = j.M3;
      if (!(v > 0)) return S(0);
      const S w = M > 0 ? S((S(0.5) * a + Real<S>::sqrt(S(0.25) * a * a + S(2) * M * v / 3)) / (M / 3))
                        : S(a < 0 ? S(S(2) * v / -a) : H);
      return cap(w);
    }
    case FlightStart::kDeparture:
      if (!(j.g2 > 0)) return S(0);
      return j.M3 > 0 ? cap(S(3) * j.g2 / j.M3) : H;
    case FlightStart::kAfterRelease:
      if (!(j.g3 > 0)) return S(0);
      return j.M4 > 0 ? cap(S(4) * j.g3 / j.M4) : H;
  }
  return S(0);
}

// Largest step of the certified searches: a quarter of the fastest period in the model.
template <class S>
S StepCap(const ModelT<S>& m) {
  S fastest = m.w;
  if (m.harmonics.fastest > fastest) fastest = m.harmonics.fastest;
  for (int i = 0; i < m.dof(); ++i)
    if (m.omega[i] > fastest) fastest = m.omega[i];
  for (Eigen::Index k = 0; k < m.stick_frequencies.size(); ++k)
    if (m.stick_frequencies[k] > fastest) fastest = m.stick_frequencies[k];
  return S(0.25) * S(2) * Real<S>::pi() / fastest;
}

// The double forms used by the CVODE engine.
FlightJet StartJet(const System& system, const Eigen::VectorXd& X, const Eigen::VectorXd& V,
                   double phase, double H);
double StepCap(const System& system);

}  // namespace vibro::detail
