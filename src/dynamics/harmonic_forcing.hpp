// The forcing as a sum of harmonics in the engine's scalar (docs/harmonics.md): harmonic h acts with
// phase φ_h = n_h φ + ψ_h, φ = ω_b t the base phase the automaton carries, and pulsation
// ω_h = n_h ω_b. Empty for today's single harmonic, whose closed forms the engines keep to the bit;
// with a sum, ModelT's f is 0 (the single-harmonic terms vanish) and every forcing term is a sum
// over these harmonics.
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "dynamics/scalar.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

template <class S>
struct HarmonicsT {
  using Vec = Eigen::Matrix<S, Eigen::Dynamic, 1>;
  struct One {
    S omega;      // ω_h
    S psi;        // ψ_h
    int n = 1;    // n_h
    Vec forcing;  // T_A^(h) f_h, (n)
    S contact;    // s_A,j^(h) f_h: the forcing the contact sees
    Vec stick;    // l_kᵀF_c^(h) f_h: the constrained modes of the contact held alone
  };
  std::vector<One> h;
  S fastest{0};  // max ω_h

  HarmonicsT() = default;
  // Contact j's view of the system's harmonics; empty without a sum.
  HarmonicsT(const System& sys, int j) {
    if (!sys.harmonic_sum()) return;
    for (size_t k = 0; k < sys.harmonics().size(); ++k) {
      const Harmonic& hk = sys.harmonics()[k];
      const S f(hk.amplitude);
      One o;
      o.omega = S(hk.frequency);
      o.psi = S(hk.phase);
      o.n = hk.multiple;
      o.forcing = hk.forcing.cast<S>() * f;
      o.contact = S(sys.HarmonicSA(j, static_cast<int>(k))) * f;
      o.stick = sys.HarmonicStickForcing(j, static_cast<int>(k)).cast<S>() * f;
      if (o.omega > fastest) fastest = o.omega;
      h.push_back(std::move(o));
    }
  }

  bool empty() const { return h.empty(); }
  size_t size() const { return h.size(); }
  // φ_h for the base phase φ.
  S PhaseOf(size_t k, const S& phi) const { return S(h[k].n) * phi + h[k].psi; }

  // d-th time derivative of sin(φ_h(t)) over ω_h^d: sin(φ_h + dπ/2).
  static S Turn(const S& s, const S& c, int d) {
    switch (d & 3) {
      case 0: return s;
      case 1: return c;
      case 2: return -s;
      default: return -c;
    }
  }
  static S Pow(const S& w, int d) {
    S p(1);
    for (int i = 0; i < d; ++i) p *= w;
    return p;
  }
  // d-th time derivative of the forcing the contact sees, Σ_h s_A^(h) f_h sin φ_h, at base phase φ.
  S Contact(const S& phi, int d = 0) const {
    S out(0);
    for (size_t k = 0; k < h.size(); ++k) {
      const S p = PhaseOf(k, phi);
      out += h[k].contact * Pow(h[k].omega, d) * Turn(Real<S>::sin(p), Real<S>::cos(p), d);
    }
    return out;
  }
  // Σ_h |s_A^(h) f_h| ω_h^d: a bound of |Contact(·, d)|.
  S ContactBound(int d) const {
    S out(0);
    for (const One& o : h) out += Real<S>::abs(o.contact) * Pow(o.omega, d);
    return out;
  }
  // d-th time derivative of the modal forcing vector Σ_h T_A^(h) f_h sin φ_h.
  Vec Vector(const S& phi, int d = 0) const {
    Vec out = Vec::Zero(h.empty() ? 0 : h.front().forcing.size());
    for (size_t k = 0; k < h.size(); ++k) {
      const S p = PhaseOf(k, phi);
      out += h[k].forcing * (Pow(h[k].omega, d) * Turn(Real<S>::sin(p), Real<S>::cos(p), d));
    }
    return out;
  }
};

}  // namespace vibro::detail
