// What the contacts endure, per event (docs/loads.md): the impulse and dissipated energy of an
// impact, the summed tail of a chattering sequence, and the duration, ∫R dt and max R of a
// sticking phase. The automaton (automaton.hpp) calls these at its events and after every sticking
// segment; everything is in the contact's physical units (impulse = effective mass m = 1/s_B
// times a gap velocity, the paper's eq. (10)-(11); R of the paper's eq. (5)).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "dynamics/model_t.hpp"
#include "dynamics/propagator.hpp"
#include "vibro/observer.hpp"

namespace vibro::detail {

// An impact of one contact with gap velocities v⁻ → v⁺. `impulse` ≥ 0 is P when the caller knows it
// (the impact LCP); otherwise P = (v⁺ − v⁻)/s_B, exact for an impact of this contact alone
// (the paper's eq. (11): v⁺ − v⁻ = s_B P). The energy dissipated is −P(v⁻ + v⁺)/2, which is
// ½(1 − r)P|v⁻| whenever v⁺ = −r v⁻ (docs/loads.md §1): the share of this contact in the loss of
// kinetic energy ΔT = Σ_j P_j(v_j⁻ + v_j⁺)/2 of the impact.
template <class S>
void ImpactLoads(Event& e, const ModelT<S>& m, const S& v_before, const S& v_after, const S& impulse) {
  using R = Real<S>;
  const S P = impulse >= S(0) ? impulse : S((v_after - v_before) / m.s_B);
  e.impulse = R::to_double(P);
  e.energy_dissipated = std::max(0.0, R::to_double(-P * (v_before + v_after) / S(2)));
}

// The tail of a chattering sequence not followed (docs/loads.md §2): after an impact that leaves
// at gap speed u = v⁺ with restitution r under a constant pull s_B R, the impacts not followed
// arrive at u, r u, r² u, …, so their impulses and losses sum to
//   P_tail = Σ (1 + r) m rⁿ u = (1 + r) m u / (1 − r),   E_tail = Σ ½(1 − r²) m r²ⁿ u² = ½ m u²,
// m = 1/s_B (all the relative kinetic energy left after the last impact followed). When R falls
// over the tail (ε = −ṘΔ0/R of the prediction, docs/model.md §5.4a) each arrival speed shrinks
// by κs_n/(3R) of its flight s_n; to first order in ε the sums become
//   P_tail (1 − ε/(3(1 + r))),   E_tail (1 − 2ε/(3(1 + r + r²))),
// with a residual O(ε²) (ε ≤ 0.1 and far smaller where a prediction is taken).
template <class S>
void TailLoads(const ModelT<S>& m, const S& u, const S& epsilon, S& impulse, S& energy) {
  impulse = (S(1) + m.r) * u / ((S(1) - m.r) * m.s_B) * (S(1) - epsilon / (S(3) * (S(1) + m.r)));
  energy = u * u / (S(2) * m.s_B) * (S(1) - S(2) * epsilon / (S(3) * (S(1) + m.r + m.r * m.r)));
}

// The sticking phase of one contact, accumulated segment by segment. A phase that was held
// together with other contacts for a while has no max R (its held-set segments give ∫λ dt, not
// the maximum of λ): max_unknown keeps it NaN.
struct StickAccount {
  double duration = 0, integral = 0, max = std::numeric_limits<double>::quiet_NaN();
  bool open = false;
  bool max_unknown = false;
};

template <class S>
class ContactLoadsT {
 public:
  using Vec = typename ModelT<S>::Vec;
  using R = Real<S>;

  void Resize(size_t contacts) { phases_.assign(contacts, {}); }
  void Begin(int j) { phases_[static_cast<size_t>(j)] = {0, 0, std::numeric_limits<double>::quiet_NaN(), true, false}; }
  // Sticking on several contacts at once: every open account is abandoned (its release reports NaN).
  void Invalidate() {
    for (StickAccount& a : phases_) a = {};
  }
  // Impulsive reaction received by a held contact (an impact elsewhere while it sticks).
  void AddImpulse(int j, const S& P) { phases_[static_cast<size_t>(j)].integral += R::to_double(P); }
  // A release: the phase's account into the event, then closed.
  void End(int j, Event& e) {
    StickAccount& a = phases_[static_cast<size_t>(j)];
    if (a.open) {
      e.stick_duration = a.duration;
      e.reaction_integral = a.integral;
      e.reaction_max = a.max;
    }
    a = {};
  }
  // The state at the start of a sticking segment (kept before the propagator advances).
  void SegmentStart(const Vec& X, const Vec& V) {
    X0_ = X;
    V0_ = V;
  }
  // A sticking segment of the held contact m over local time sigma from forcing phase `phase`,
  // ending at (X1, V1): duration, ∫R dt in closed form and max R on the dense output of p.
  void Segment(int j, const ModelT<S>& m, const PropagatorT<S>& p, const S& phase, const S& sigma,
               const Vec& X1, const Vec& V1) {
    StickAccount& a = phases_[static_cast<size_t>(j)];
    if (!a.open) return;  // a phase begun before a resume whose checkpoint had no account
    a.duration += R::to_double(sigma);
    if (a.max_unknown) {
      a.integral += R::to_double(ReactionIntegral(m, phase, sigma, X0_, V0_, X1, V1));
      return;
    }
    // max R first: it evaluates cos φ0 and cos(φ0 + ωσ), which ∫R dt needs too.
    const double mx = R::to_double(ReactionMax(m, p, phase, sigma, X1, V1));
    a.integral += R::to_double(ReactionIntegral(m, phase, sigma, X0_, V0_, X1, V1, &cos_ends_));
    if (!(a.max >= mx)) a.max = mx;
  }

  // A segment held on the set `held` of several contacts (models[j] each contact's), over local
  // time sigma from forcing phase `phase`, ending at (X1, V1): every held contact's duration and
  // ∫λ_j dt in closed form (SetReactionIntegrals); their max λ is left unknown. A set whose
  // flexibility matrix cannot be solved (dependent contacts) abandons its contacts' accounts.
  void SetSegment(const std::vector<int>& held, const std::vector<const ModelT<S>*>& models, const S& phase,
                  const S& sigma, const Vec& X1, const Vec& V1) {
    Vec lambda;
    const bool ok = SetReactionIntegrals(held, models, phase, sigma, X0_, V0_, X1, V1, lambda);
    for (size_t a = 0; a < held.size(); ++a) {
      StickAccount& acc = phases_[static_cast<size_t>(held[a])];
      if (!acc.open) continue;
      if (!ok) {
        acc = {};
        continue;
      }
      acc.duration += R::to_double(sigma);
      acc.integral += R::to_double(lambda[static_cast<Eigen::Index>(a)]);
      acc.max = std::numeric_limits<double>::quiet_NaN();
      acc.max_unknown = true;
    }
  }

  // ∫λ_j dt of every contact j of a held set S over a segment, in closed form from the end states
  // (docs/loads.md, "Phases held on several contacts"): the modal equations of motion
  //   Ẍ + DẊ + ΩX = T_A f sin ωt + Σ_{j∈S} T_j λ_j
  // integrated over [0, σ] give Ω∫X dt = Σ T_j Λ_j − b, b = [Ẋ] + D[X] − T_A f ∫sin ωt dt, and the
  // held constraints c_jᵀX = x0_j give c_jᵀ∫X dt = x0_j σ; so, with u_j = Ω⁻¹c_j,
  //   Σ_k (u_jᵀT_k) Λ_k = x0_j σ + u_jᵀ b   for every j ∈ S,
  // the flexibility matrix of the set times Λ (for one contact: ReactionIntegral). False when that
  // matrix is singular.
  static bool SetReactionIntegrals(const std::vector<int>& held, const std::vector<const ModelT<S>*>& models,
                                   const S& phase, const S& sigma, const Vec& X0, const Vec& V0, const Vec& X1,
                                   const Vec& V1, Vec& lambda) {
    const size_t zs = held.size();
    if (zs == 0 || zs > 4096) return false;
    const auto z = static_cast<Eigen::Index>(zs);
    const ModelT<S>& m0 = *models[static_cast<size_t>(held.front())];
    const Eigen::Index n = m0.omega.size();
    const S sin_integral = (R::cos(phase) - R::cos(phase + m0.w * sigma)) / m0.w;
    Vec b(n);
    for (Eigen::Index i = 0; i < n; ++i)
      b[i] = (V1[i] - V0[i]) + S(2) * m0.zeta[i] * m0.omega[i] * (X1[i] - X0[i]) - m0.forcing[i] * m0.f * sin_integral;
    // The augmented system [F | rhs], solved by Gaussian elimination with partial pivoting.
    std::vector<std::vector<S>> A(zs, std::vector<S>(zs + 1, S(0)));
    S scale(0);
    for (Eigen::Index a = 0; a < z; ++a) {
      const ModelT<S>& ma = *models[static_cast<size_t>(held[static_cast<size_t>(a)])];
      auto& row = A[static_cast<size_t>(a)];
      S rhs = ma.x0 * sigma;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (ma.shape[i] == S(0)) continue;
        const S u = ma.shape[i] / (m0.omega[i] * m0.omega[i]);
        rhs += u * b[i];
        for (Eigen::Index k = 0; k < z; ++k)
          row[static_cast<size_t>(k)] += u * models[static_cast<size_t>(held[static_cast<size_t>(k)])]->contact[i];
      }
      row[zs] = rhs;
      for (Eigen::Index k = 0; k < z; ++k) scale = std::max(scale, R::abs(row[static_cast<size_t>(k)]));
    }
    for (size_t c = 0; c < zs; ++c) {
      size_t piv = c;
      for (size_t r = c + 1; r < zs; ++r)
        if (R::abs(A[r][c]) > R::abs(A[piv][c])) piv = r;
      if (!(R::abs(A[piv][c]) > S(1e-12) * scale)) return false;
      std::swap(A[c], A[piv]);
      for (size_t r = c + 1; r < zs; ++r) {
        const S q = A[r][c] / A[c][c];
        for (size_t k = c; k <= zs; ++k) A[r][k] -= q * A[c][k];
      }
    }
    lambda.resize(z);
    for (size_t c = zs; c-- > 0;) {
      S v = A[c][zs];
      for (size_t k = c + 1; k < zs; ++k) v -= A[c][k] * lambda[static_cast<Eigen::Index>(k)];
      lambda[static_cast<Eigen::Index>(c)] = v / A[c][c];
    }
    return true;
  }

  // Checkpoint (open phases) and resume.
  void Save(Checkpoint& cp) const {
    cp.stick_duration.resize(phases_.size());
    cp.reaction_integral.resize(phases_.size());
    cp.reaction_max.resize(phases_.size());
    for (size_t j = 0; j < phases_.size(); ++j) {
      const StickAccount& a = phases_[j];
      cp.stick_duration[j] = a.open ? a.duration : std::numeric_limits<double>::quiet_NaN();
      cp.reaction_integral[j] = a.open ? a.integral : std::numeric_limits<double>::quiet_NaN();
      cp.reaction_max[j] = a.open ? a.max : std::numeric_limits<double>::quiet_NaN();
    }
  }
  void Restore(const Checkpoint& cp) {
    if (cp.stick_duration.size() != phases_.size() || cp.reaction_integral.size() != phases_.size() ||
        cp.reaction_max.size() != phases_.size())
      return;
    for (size_t j = 0; j < phases_.size(); ++j) {
      const bool open = !std::isnan(cp.stick_duration[j]);
      // An open phase with time held and no max was held with other contacts: its max stays unknown.
      phases_[j] = {open ? cp.stick_duration[j] : 0.0, open ? cp.reaction_integral[j] : 0.0, cp.reaction_max[j],
                    open, open && cp.stick_duration[j] > 0 && std::isnan(cp.reaction_max[j])};
    }
  }

  // ∫R dt over a sticking segment in closed form (docs/loads.md §3). With u = Ω⁻¹c / φ, φ = cᵀΩ⁻¹T_B
  // the static flexibility of the contact (uᵀT_B = 1, uᵀΩ = cᵀ/φ), uᵀ of the equation of motion
  // Ẍ + DẊ + ΩX = T_A f sin ωt + T_B R integrated over [0, σ], with cᵀX = x0 held, gives
  //   ∫R dt = uᵀ[Ẋ] + uᵀD[X] + x0 σ / φ − (uᵀT_A) f (cos φ0 − cos(φ0 + ωσ)) / ω
  // from the end states alone (exact: no quadrature).
  // cos_ends: cos φ0 and cos(φ0 + ωσ) when the caller has them.
  static S ReactionIntegral(const ModelT<S>& m, const S& phase, const S& sigma, const Vec& X0,
                            const Vec& V0, const Vec& X1, const Vec& V1, const S (*cos_ends)[2] = nullptr) {
    S uV(0), uDX(0), uTA(0);
    for (Eigen::Index i = 0; i < m.omega.size(); ++i) {
      if (m.shape[i] == S(0)) continue;
      const S ui = m.shape[i] / (m.omega[i] * m.omega[i]);
      uV += ui * (V1[i] - V0[i]);
      uDX += ui * S(2) * m.zeta[i] * m.omega[i] * (X1[i] - X0[i]);
      uTA += ui * m.forcing[i];
    }
    const S phi = m.flexibility;
    const S forcing = uTA * m.f *
                      (cos_ends ? S((*cos_ends)[0] - (*cos_ends)[1]) : S(R::cos(phase) - R::cos(phase + m.w * sigma))) /
                      m.w;
    return (uV + uDX - forcing) / phi + m.x0 * sigma / phi;
  }

  // max R over a sticking segment (docs/loads.md §3): R and Ṙ at the ends and on a grid of spacing
  // at most h = 1/ω_max (ω_max the largest of ω and the ω_i: R is a sum of oscillations no faster,
  // whose consecutive extrema are at least about π/ω_max apart), and in every cell where Ṙ goes
  // from + to −, the zero of Ṙ by regula falsi (Illinois) from the cubic Hermite guess, until two
  // estimates agree to 1e-7 h: R is flat there, so its error ½|R̈|δs² is at the rounding of R.
  // A maximum is missed only where Ṙ has two zeros inside one cell; R exceeds the larger cell end
  // there by at most max|R̈| h²/8.
  // X1, V1: the state at sigma (the segment's end, already evaluated); the start is X0_, V0_.
  S ReactionMax(const ModelT<S>& m, const PropagatorT<S>& p, const S& phase, const S& sigma, const Vec& X1,
                const Vec& V1) {
    S wmax = m.w;
    for (Eigen::Index i = 0; i < m.omega.size(); ++i) wmax = std::max(wmax, S(m.omega[i]));
    const int n = std::max(1, std::min(4096, static_cast<int>(R::to_double(sigma * wmax)) + 1));
    const S h = sigma / S(n);
    S rate_prev(0);
    S best = At(m, X0_, V0_, phase, rate_prev);
    cos_ends_[0] = cos_;
    S s_prev(0), R_prev = best;
    for (int i = 1; i <= n; ++i) {
      const S s = i == n ? sigma : S(h * S(i));
      S rate(0);
      const S Rv = i == n ? At(m, X1, V1, phase + m.w * sigma, rate) : At(m, p, phase, s, rate);
      if (i == n) cos_ends_[1] = cos_;
      if (Rv > best) best = Rv;
      if (rate_prev > S(0) && rate < S(0)) {
        S a = s_prev, b = s, fa = rate_prev, fb = rate;
        int side = 0;
        // First guess: the zero of the derivative of the cubic Hermite interpolant of R on the cell.
        S c0 = HermiteZero(s - s_prev, R_prev, rate_prev, Rv, rate);
        S c_last(-1);
        const S first = c0 > S(0) && c0 < s - s_prev ? S(s_prev + c0) : S(b - fb * (b - a) / (fb - fa));
        // With the engine's R̈: Newton's steps on Ṙ from the same guess, kept inside the bracket.
        const bool newton = NewtonMax(p, first, a, b, h, R::abs(rate_prev) + R::abs(rate), best);
        for (int it = 0; it < 12 && !newton; ++it) {
          const S c = it == 0 && c0 > S(0) && c0 < s - s_prev ? S(s_prev + c0) : S(b - fb * (b - a) / (fb - fa));
          // Converged when two estimates agree to 1e-7 h: R is flat there, its error ½|R̈|δs² is
          // below 1e-14 R (|R̈| ≲ ω_max² max|R| and h ω_max ≤ 1).
          if (c_last >= S(0) && R::abs(c - c_last) < S(1e-7) * h) break;
          c_last = c;
          S fc(0);
          const S Rc = At(m, p, phase, c, fc);
          if (Rc > best) best = Rc;
          if (R::abs(b - a) < S(1e-9) * h || fc == S(0)) break;
          if ((fc > S(0)) == (fa > S(0))) {
            a = c;
            fa = fc;
            if (side == -1) fb /= S(2);
            side = -1;
          } else {
            b = c;
            fb = fc;
            if (side == 1) fa /= S(2);
            side = 1;
          }
          if (R::abs(fc) <= S(64) * Eps<S>() * (R::abs(rate_prev) + R::abs(rate))) break;
        }
      }
      rate_prev = rate;
      s_prev = s;
      R_prev = Rv;
    }
    return best;
  }

  // The refinement of one cell (a, b) with Ṙ(a) > 0 > Ṙ(b) when the engine gives R̈
  // (HeldReactionJet): Newton's steps c ← c − Ṙ/R̈ on the zero of Ṙ from the guess c, the bracket
  // kept (a step outside it, or with R̈ ≥ 0, bisects), until the next step is below 1e-7 h — the
  // criterion of the regula falsi it replaces, so the value kept is within ½|R̈|(1e-7 h)² of the
  // maximum, at the rounding of R. Newton converges quadratically from the Hermite guess: two
  // evaluations per refined cell on chain3.toml (counted over vibro_loads_bench). False when the
  // engine has no R̈.
  bool NewtonMax(const PropagatorT<S>& p, S c, S a, S b, const S& h, const S& rate_scale, S& best) const {
    S Rc(0), fc(0), gc(0);
    if (!p.HeldReactionJet(c, Rc, fc, gc)) return false;
    for (int it = 0; it < 16; ++it) {
      if (Rc > best) best = Rc;
      if (fc == S(0) || R::abs(fc) <= S(64) * Eps<S>() * rate_scale) break;
      if (fc > S(0))
        a = c;
      else
        b = c;
      if (R::abs(b - a) < S(1e-9) * h) break;
      S next = gc < S(0) ? S(c - fc / gc) : S(-1);
      if (!(next > a && next < b)) next = S(S(0.5) * (a + b));
      if (R::abs(next - c) < S(1e-7) * h) break;
      c = next;
      p.HeldReactionJet(c, Rc, fc, gc);
    }
    return true;
  }

  // The zero in (0, h) of the derivative of the cubic with values y0, y1 and slopes d0 > 0 > d1 at
  // 0 and h (−1 when none).
  static S HermiteZero(const S& h, const S& y0, const S& d0, const S& y1, const S& d1) {
    // p'(t) = d0 + (6Δ/h − 4d0 − 2d1)(t/h) + (3d0 + 3d1 − 6Δ/h)(t/h)², Δ = y1 − y0.
    const S D = (y1 - y0) / h;
    const S A = S(3) * (d0 + d1) - S(6) * D, B = S(6) * D - S(4) * d0 - S(2) * d1, C = d0;
    S u(-1);
    if (R::abs(A) <= S(1e-12) * (R::abs(B) + R::abs(C))) {
      if (B != S(0)) u = -C / B;
    } else {
      const S disc = B * B - S(4) * A * C;
      if (disc >= S(0)) {
        const S q = -(B + R::copysign(R::sqrt(disc), B)) / S(2);
        const S u1 = q / A, u2 = q != S(0) ? C / q : S(-1);
        u = (u1 > S(0) && u1 < S(1)) ? u1 : u2;
      }
    }
    return u > S(0) && u < S(1) ? S(u * h) : S(-1);
  }

  // R (the paper's eq. (5), damped as docs/model.md §7) and Ṙ along the held flow at local time s,
  // without allocation: Ṙ = Σ c_i(ω_i² Ẋ_i + 2ζ_iω_i Ẍ_i) − s_A f ω cos φ over s_B, with Ẍ the
  // constrained acceleration (the free one less T_B times the gap's).
  // The engine's own R and Ṙ when it has them (the exact engine: no state formed), else from the state.
  S At(const ModelT<S>& m, const PropagatorT<S>& p, const S& phase, const S& s, S& rate) const {
    S held(0);
    if (p.HeldReaction(s, held, rate)) return held;
    p.Evaluate(s, Xs_, Vs_);
    return At(m, Xs_, Vs_, phase + m.w * s, rate);
  }
  // Keeps cos φ in cos_.
  S At(const ModelT<S>& m, const Vec& X, const Vec& V, const S& ph, S& rate) const {
    S sn(0), cs(0);
    R::sincos(ph, sn, cs);
    cos_ = cs;
    S elastic(0), r(0), gap_acc(0);
    if (m.damped)
      for (Eigen::Index i = 0; i < X.size(); ++i)
        gap_acc += m.shape[i] * (-m.omega[i] * m.omega[i] * X[i] - S(2) * m.zeta[i] * m.omega[i] * V[i] +
                                 m.forcing[i] * m.f * sn);
    for (Eigen::Index i = 0; i < X.size(); ++i) {
      if (m.shape[i] == S(0)) continue;
      const S w2 = m.omega[i] * m.omega[i], d = S(2) * m.zeta[i] * m.omega[i];
      elastic += m.shape[i] * (w2 * X[i] + d * V[i]);
      r += m.shape[i] * w2 * V[i];
      if (m.damped) {
        const S acc = -w2 * X[i] - d * V[i] + m.forcing[i] * m.f * sn - m.contact[i] * gap_acc / m.s_B;
        r += m.shape[i] * d * acc;
      }
    }
    rate = (r - m.s_A * m.f * m.w * cs) / m.s_B;
    return (elastic - m.s_A * m.f * sn) / m.s_B;
  }

 private:
  std::vector<StickAccount> phases_;
  Vec X0_, V0_;
  mutable Vec Xs_, Vs_;
  mutable S cos_{0};     // cos φ of the last state-based At
  S cos_ends_[2] = {};   // cos φ0, cos(φ0 + ωσ) of the last ReactionMax
};

}  // namespace vibro::detail
