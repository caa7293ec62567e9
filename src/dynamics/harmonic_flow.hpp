// One oscillator q'' + 2ζνq' + ν²q = Σ_h F_h sin(φ_h + ω_h σ) in closed form (docs/harmonics.md):
// by linearity, the homogeneous flow from (q0, v0) plus, per harmonic, its own closed-form
// response from rest (oscillator.hpp's forced part, resonance-safe). Undamped, the half angle of
// νσ is evaluated once for every harmonic, so that H harmonics cost one sincos per mode and one per
// harmonic per probe.
#pragma once

#include <vector>

#include "dynamics/oscillator.hpp"

namespace vibro::detail {

// What a probe needs of the harmonics at its local time σ: each one's angle ω_hσ (ForcingTrigT)
// and sin, cos of φ_h(σ) = φ_h + ω_hσ.
template <class S>
struct HarmonicTrigT {
  std::vector<ForcingTrigT<S>> fw;
  std::vector<S> s, c;
  void At(const std::vector<S>& omega, const std::vector<PhaseTrigT<S>>& ph, const S& sigma) {
    fw.clear();
    s.resize(omega.size());
    c.resize(omega.size());
    for (size_t h = 0; h < omega.size(); ++h) {
      fw.emplace_back(omega[h], sigma);
      s[h] = fw[h].SinPhase(ph[h]);
      c[h] = fw[h].CosPhase(ph[h]);
    }
  }
};

// Σ_h |F_h|, Σ_h |F_h| ω_h, Σ_h |F_h| ω_h² of one mode: its forcing's bounds.
template <class S>
struct HarmonicSumsT {
  S f{0}, fw{0}, fw2{0};
};

// Bounds of |q''|, |q'''|, |q''''| over a window where the energy amplitude stays ≤ A
// (oscillator.hpp's Bounds with the forcing Σ_h F_h sin φ_h, each derivative bounded by its sum).
template <class S>
DerivativeBoundsT<S> BoundsSum(const OscillatorT<S>& o, const HarmonicSumsT<S>& F, const S& A) {
  const S nu = o.nu, tz = S(2) * o.zeta * nu;
  DerivativeBoundsT<S> b{};
  b.d2 = nu * A + tz * A + F.f;
  b.d3 = nu * nu * A + tz * b.d2 + F.fw;
  b.d4 = nu * nu * b.d2 + tz * b.d3 + F.fw2;
  return b;
}

// The flow over σ of mode o (o.F unused) forced by F[h] sin(φ_h + ω_h σ), h < H.
template <class S>
OscillatorStateT<S> FlowSum(const OscillatorT<S>& o, const S* F, const std::vector<S>& omega,
                            const std::vector<PhaseTrigT<S>>& ph, const HarmonicTrigT<S>& t, const S& q0,
                            const S& v0, const S& sigma) {
  using R = Real<S>;
  const size_t H = omega.size();
  if (o.zeta > S(0)) {
    OscillatorT<S> free = o;
    free.F = S(0);
    OscillatorStateT<S> out = osc::Damped<S>(free, omega[0], ph[0], q0, v0, sigma, t.fw[0]);
    for (size_t h = 0; h < H; ++h) {
      if (F[h] == S(0)) continue;
      OscillatorT<S> oh = o;
      oh.F = F[h];
      const auto r = osc::Damped<S>(oh, omega[h], ph[h], S(0), S(0), sigma, t.fw[h]);
      out.dq += r.dq;
      out.v += r.v;
    }
    return out;
  }
  // Undamped: oscillator.hpp's osc::Undamped, its half angle shared by the harmonics.
  const S nu = o.nu;
  S half, half_c;
  R::sincos(S(0.5) * nu * sigma, half, half_c);
  const S sn = S(2) * half * half_c;
  const S cn = S(1) - S(2) * half * half;
  OscillatorStateT<S> out{q0 * (S(-2) * half * half) + v0 * sn / nu, -q0 * nu * sn + v0 * cn};
  for (size_t h = 0; h < H; ++h) {
    if (F[h] == S(0)) continue;
    const S w = omega[h];
    const ForcingTrigT<S>& fw = t.fw[h];
    const S sum = nu + w, diff = nu - w;
    const S x = S(0.5) * diff * sigma;
    const S sc = R::abs(x) < S(0.5) ? osc::Sinc<S>(x) : S((half * fw.c2 - half_c * fw.s2) / x);
    const S s_half = half * fw.c2 + half_c * fw.s2, c_half = half_c * fw.c2 - half * fw.s2;
    const S C = sigma * s_half * sc / sum;
    const S Sk = (sn - nu * sigma * c_half * sc) / (nu * sum);
    const S E = (nu * sigma * c_half * sc + fw.s) / sum;
    out.dq += F[h] * (ph[h].s * C + ph[h].c * Sk);
    out.v += F[h] * (ph[h].s * E + ph[h].c * w * C);
  }
  return out;
}

}  // namespace vibro::detail
