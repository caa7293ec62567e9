// max R of a sticking segment (docs/loads.md §3): certified on the engine's closed form of the held
// flow, from the jets (R, Ṙ, R̈) at the segment's ends and the engine's bounds on R''' and R⁽⁵⁾,
// with one evaluation of R and its four derivatives at each maximum; a grid search for the
// integrators, which have no bound (on each stretch of their dense output as they report it). The
// jets at the ends come from the states (JetAt), with coefficients made once per model, which
// ∫R dt (contact_loads.hpp) shares.
#pragma once

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <utility>
#include <vector>

#include "dynamics/model_t.hpp"
#include "dynamics/propagator.hpp"

namespace vibro::detail {

template <class S>
class ReactionMaxT {
 public:
  using Vec = typename ModelT<S>::Vec;
  using R = Real<S>;

  ReactionMaxT() = default;
  ReactionMaxT(const ReactionMaxT&) = delete;  // last_coefs_ points into coefs_
  ReactionMaxT& operator=(const ReactionMaxT&) = delete;

  // cos φ of the last JetAt or state-based evaluation.
  S LastCos() const { return cos_; }

  // The grid search on a stretch [lo, hi] of an integrator's dense output (valid there only), the
  // segment starting at forcing phase `phase`.
  S OnStretch(const ModelT<S>& m, const PropagatorT<S>& p, const S& phase, const S& lo, const S& hi) {
    p.Evaluate(lo, Xs_, Vs_);
    const Jet ja = JetAt(m, Xs_, Vs_, phase + m.w * lo);
    p.Evaluate(hi, Xs_, Vs_);
    const Jet jb = JetAt(m, Xs_, Vs_, phase + m.w * hi);
    return GridMax(m, p, phase, CoefsOf(m).wmax, {lo, ja}, {hi, jb});
  }

  // R, Ṙ, R̈ at a point of the held flow.
  struct Jet {
    S R, rate, accel;
  };
  // A point of a cell of the certified search.
  struct Node {
    S s;
    Jet j;
    bool zero = false;  // a zero of Ṙ found by Peak (its cells' Ṙ may change sign at it by rounding)
    S rate_err{0};      // |Ṙ − j.rate| ≤ rate_err (a point placed by Peak's Taylor polynomial)
  };

  // max R over a sticking segment of local time sigma from forcing phase `phase`, held on m, with the
  // jets j0, j1 at its ends (docs/loads.md §3). With the engine's bound M ≥ |R'''| over the segment
  // (the exact engine, RestingStick), the maximum is certified: a cell [a, b] with the jets
  // (R, Ṙ, R̈) at its ends holds no R above `level` when the two Taylor lower bounds of level − R,
  //   level − R(a + t) ≥ (level − R_a) − Ṙ_a t − R̈_a t²/2 − M t³/6   (from a)
  //   level − R(b − u) ≥ (level − R_b) + Ṙ_b u − R̈_b u²/2 − M u³/6   (from b)
  // are positive on two stretches that cover it (Below). A cell where Ṙ goes from + to − holds a
  // maximum: Peak places it (one evaluation of R and its four derivatives, usually) and the cell
  // is split there; any other cell that is not certified is split at its midpoint. The level is the
  // largest R found plus 1024 ε of the R at hand and the most R can exceed the maxima found beside
  // them (their Taylor remainders): max R over the segment is within that of the value returned.
  // Most segments need their two ends only. Without a bound (an integrator): the grid search.
  // P: a PropagatorT, or any source of R with its HeldReactionJet, HeldReactionTaylor and
  // HeldReactionBound (a contact of a held set: λ_j), which has no grid search to fall back on.
  template <class P>
  S Max(const ModelT<S>& m, const P& p, const S& phase, const S& sigma, const Jet& j0, const Jet& j1) {
    S best = j0.R > j1.R ? j0.R : j1.R;
    if (!(sigma > S(0))) return best;
    const S wmax = CoefsOf(m).wmax;
    S M(0), M5(0);
    if (!p.HeldReactionBound(sigma, M, &M5) || !R::isfinite(M)) {
      if constexpr (std::is_base_of_v<PropagatorT<S>, P>) return GridMax(m, p, phase, wmax, {S(0), j0}, {sigma, j1});
      return best;
    }
    const S h = std::min(sigma, S(S(1) / wmax));  // the scale of the Newton steps' tolerance
    const S rounding = S(1024) * Eps<S>() * (R::abs(j0.R) + R::abs(j1.R));
    S excess(0);
    cells_.clear();
    cells_.push_back({{S(0), j0}, {sigma, j1}});
    // A segment where R stays within rounding of its maximum over a stretch (a body at rest on the
    // stop: R flat to third order) cannot be certified at rounding: after 24 refinements the grid
    // search takes over, and the larger of the two is kept.
    int refined = 0;
    for (; !cells_.empty() && refined < 24;) {
      const auto [a, b] = cells_.back();
      cells_.pop_back();
      const S level = best + excess + rounding + S(1024) * Eps<S>() * R::abs(best);
      // A cell where Ṙ goes from + to − holds a maximum above its ends: refined at once, unless
      // one end is the zero of Ṙ found there.
      const bool peak = a.j.rate > S(0) && b.j.rate < S(0);
      if ((!peak || a.zero || b.zero) && Below(a, b, M, level)) continue;
      ++refined;
      Node c;
      if (peak) {
        c = Peak(p, a, b, h, M, M5, phase, m.w, best);
        // Beside c, R(c + t) ≤ R_c + Ṙ_c t + R̈_c t²/2 + M|t|³/6: at most R_c + Ṙ_c²/(2|R̈_c|) +
        // (4/3)M|δ|³ for |t| ≤ 2|δ|, δ = Ṙ_c/|R̈_c| (Below certifies beyond).
        if (c.j.accel < S(0)) {
          const S d = R::abs(c.j.rate / c.j.accel);
          excess = std::max(excess, S(c.j.R + c.j.rate * c.j.rate / (S(-2) * c.j.accel) +
                                      S(4) / S(3) * M * d * d * d - best));
        }
      } else {
        c.s = S(0.5) * (a.s + b.s);
        p.HeldReactionJet(c.s, c.j.R, c.j.rate, c.j.accel);
      }
      if (c.j.R > best) best = c.j.R;
      if (!(c.s > a.s && c.s < b.s)) continue;  // a cell at the resolution of s
      // The cell where Ṙ goes from + to − is refined first (its maximum raises the level).
      if (c.j.rate > S(0) && b.j.rate < S(0)) {
        cells_.push_back({a, c});
        cells_.push_back({c, b});
      } else {
        cells_.push_back({c, b});
        cells_.push_back({a, c});
      }
    }
    if constexpr (std::is_base_of_v<PropagatorT<S>, P>) {
      if (!cells_.empty()) {
        const S grid = GridMax(m, p, phase, wmax, {S(0), j0}, {sigma, j1});
        if (grid > best) best = grid;
      }
    }
    return best;
  }

  // Whether R ≤ level on a cell [a, b] with the jets at its ends and |R'''| ≤ M there:
  // the lower bounds of level − R from each end, positive on two stretches that cover the cell
  // (the whole cell from either end, else split at L/2, L/4 or 3L/4). A few products each: no root
  // is located.
  static bool Below(const Node& na, const Node& nb, const S& M, const S& level) {
    const Jet &ja = na.j, &jb = nb.j;
    const S L = nb.s - na.s;
    const S ga = level - ja.R, gb = level - jb.R;
    if (!(ga > S(0) && gb > S(0))) return false;
    // From a: p(t) = ga − Ṙ_a t − R̈_a t²/2 − M t³/6; from b: p(u) = gb + Ṙ_b u − R̈_b u²/2 − M u³/6
    // (a rate known within rate_err taken at its worst); covered by their positive stretches from
    // each end (the whole cell from either end, else split at L/2, L/4 or 3L/4).
    const Cubic pa(ga, S(-ja.rate - na.rate_err), S(-ja.accel), M);
    if (pa.Positive(L)) return true;
    const Cubic pb(gb, S(jb.rate - nb.rate_err), S(-jb.accel), M);
    if (pb.Positive(L)) return true;
    for (const double f : {0.5, 0.25, 0.75})
      if (pa.Positive(S(f * L)) && pb.Positive(S((1 - f) * L))) return true;
    return false;
  }
  // p(t) = g + g1 t + g2 t²/2 − M t³/6 with g > 0, M ≥ 0: Positive(T) when p > 0 on [0, T]. Its
  // minimum there is at T or at its local minimum, the smaller root of p'(t) = g1 + g2 t − M t²/2
  // (found once per cubic).
  struct Cubic {
    S g, g1, g2h, m6, t_min{-1};
    bool min_positive = true;
    Cubic(const S& g0, const S& d1, const S& d2, const S& M) : g(g0), g1(d1), g2h(S(0.5) * d2), m6(M / S(6)) {
      if (M > S(0)) {
        const S disc = d2 * d2 + S(2) * M * d1;
        if (disc > S(0)) t_min = (d2 - R::sqrt(disc)) / M;
      } else if (d2 > S(0)) {
        t_min = -d1 / d2;
      }
      if (t_min > S(0)) min_positive = (*this)(t_min) > S(0);
    }
    S operator()(const S& t) const { return g + t * (g1 + t * (g2h - t * m6)); }
    bool Positive(const S& T) const { return (*this)(T) > S(0) && (min_positive || !(t_min < T)); }
  };

  // The zero of Ṙ in a cell (a, b) with Ṙ(a) > 0 > Ṙ(b), the phase's maximum there; every value
  // seen raises `best`. First from the forcing phases of the last maxima found (a periodic motion
  // repeats them: the guess is then exact to rounding), else from the zero of the derivative of the
  // cell's quintic Hermite interpolant, by TaylorPeak (one evaluation); else by Newton's steps
  // c ← c − Ṙ/R̈ from there, the bracket kept (a step outside it, or R̈ ≥ 0, bisects), until the
  // maximum near c is known to rounding (below) or the next step is below 1e-7 h. Returns the point
  // with its jet. phase, w: the segment's start phase and the forcing frequency.
  template <class P>
  Node Peak(const P& p, const Node& a0, const Node& b0, const S& h, const S& M, const S& M5,
            const S& phase, const S& w, S& best) {
    S a = a0.s, b = b0.s;
    Node c;
    if (M5 > S(0)) {
      for (int k = 0; k < peaks_; ++k) {
        const S sg = Wrap(S(peak_phases_[k] - phase)) / w;
        if (!(sg > a && sg < b)) continue;
        if (TaylorPeak(p, sg, a, b, M5, best, c)) return Found(c, phase, w);
        break;
      }
    }
    const S L = b - a;
    const S z = QuinticZero(L, a0.j, b0.j);
    c.s = z > S(0) ? S(a + z) : S(a - a0.j.rate * L / (b0.j.rate - a0.j.rate));
    if (!(c.s > a && c.s < b)) c.s = S(0.5) * (a + b);
    const S rate_scale = R::abs(a0.j.rate) + R::abs(b0.j.rate);
    if (M5 > S(0) && TaylorPeak(p, c.s, a, b, M5, best, c)) return Found(c, phase, w);
    if (!(M5 > S(0))) p.HeldReactionJet(c.s, c.j.R, c.j.rate, c.j.accel);
    for (int it = 0; it < 40; ++it) {
      if (c.j.R > best) best = c.j.R;
      if (c.j.rate == S(0) || R::abs(c.j.rate) <= S(64) * Eps<S>() * rate_scale) break;
      // Close enough: with δ = Ṙ/|R̈|, R(c + δ) ≥ R_c + Ṙ²/(2|R̈|) − M|δ|³/6, the maximum within
      // 2M|δ|³ of that, below the rounding of R.
      if (c.j.accel < S(0)) {
        const S dt = R::abs(c.j.rate / c.j.accel);
        if (S(2) * M * dt * dt * dt <= S(16) * Eps<S>() * R::abs(c.j.R)) {
          const S low = c.j.R + c.j.rate * c.j.rate / (S(-2) * c.j.accel) - M * dt * dt * dt / S(6);
          if (low > best) best = low;
          break;
        }
      }
      if (c.j.rate > S(0))
        a = c.s;
      else
        b = c.s;
      if (R::abs(b - a) < S(1e-9) * h) break;
      S next = c.j.accel < S(0) ? S(c.s - c.j.rate / c.j.accel) : S(-1);
      if (!(next > a && next < b)) next = S(0.5) * (a + b);
      if (R::abs(next - c.s) < S(1e-7) * h) break;
      c.s = next;
      p.HeldReactionJet(c.s, c.j.R, c.j.rate, c.j.accel);
    }
    return Found(c, phase, w);
  }

  // With R's first four derivatives at s0 (the engine's HeldReactionTaylor) and M5 ≥ |R⁽⁵⁾|, the
  // zero of Ṙ is placed on the Taylor polynomial T of degree 4 at s0: at s0 + t,
  // |R − T| ≤ M5|t|⁵/120, |Ṙ − T'| ≤ M5|t|⁴/24, |R̈ − T''| ≤ M5|t|³/6. Taken (true, the point in
  // `out` with its jet at worst within those errors) when R there is known to the rounding of R,
  // inside (a, b); else `out` is the jet at s0 (false).
  template <class P>
  bool TaylorPeak(const P& p, const S& s0, const S& a, const S& b, const S& M5, S& best,
                  Node& out) const {
    S d[5];
    out.s = s0;
    if (!p.HeldReactionTaylor(s0, d)) {
      p.HeldReactionJet(s0, out.j.R, out.j.rate, out.j.accel);
      return false;
    }
    out.j = {d[0], d[1], d[2]};
    if (d[0] > best) best = d[0];
    if (!(d[2] < S(0))) return false;
    const S sixth = S(1) / S(6);
    S t = -d[1] / d[2];
    for (int it = 0; it < 6; ++it) {
      const S f = d[1] + t * (d[2] + t * (S(0.5) * d[3] + t * d[4] * sixth));
      const S fp = d[2] + t * (d[3] + S(0.5) * t * d[4]);
      if (!(fp < S(0))) return false;
      const S step = f / fp;
      t -= step;
      if (R::abs(step) <= S(4) * Eps<S>() * R::abs(t)) break;
    }
    const S at = R::abs(t), s1 = s0 + t, at3 = at * at * at;
    const S e0 = M5 * at3 * at * at / S(120);
    if (!(R::isfinite(t) && s1 > a && s1 < b && e0 <= S(4) * Eps<S>() * R::abs(d[0]))) return false;
    const S T = d[0] + t * (d[1] + t * (S(0.5) * d[2] + t * (d[3] * sixth + t * d[4] / S(24))));
    const S T1 = d[1] + t * (d[2] + t * (S(0.5) * d[3] + t * d[4] * sixth));  // ≈ 0
    const S T2 = d[2] + t * (d[3] + S(0.5) * t * d[4]);
    const S e2 = M5 * at3 * sixth;
    if (!(T2 + e2 < S(0))) return false;
    if (T - e0 > best) best = T - e0;  // R(s0 + t) ≥ T − e0
    out = {s1, {T + e0, S(0), T2 + e2}, true, R::abs(T1) + M5 * at3 * at / S(24)};
    return true;
  }

  // x reduced to [0, 2π) (one step for the phases of a segment, which spans at most a period).
  static S Wrap(S x) {
    const S two_pi = S(2) * R::pi();
    if (x >= S(0) && x < two_pi) return x;
    if (x >= two_pi && x < S(2) * two_pi) return S(x - two_pi);
    if (x < S(0) && x >= -two_pi) return S(x + two_pi);
    x = R::fmod(x, two_pi);
    return x < S(0) ? S(x + two_pi) : x;
  }

  // A maximum found: marked, and its forcing phase kept for the next guesses (the last four).
  Node Found(Node c, const S& phase, const S& w) {
    c.zero = true;
    const S ph = Wrap(S(phase + w * c.s));
    for (int k = std::min(peaks_, 3); k > 0; --k) peak_phases_[k] = peak_phases_[k - 1];
    peak_phases_[0] = ph;
    peaks_ = std::min(peaks_ + 1, 4);
    return c;
  }

  // The zero in (0, L) of the derivative of the quintic Hermite interpolant of R on a cell of length
  // L with the jets ja (Ṙ > 0) and jb (Ṙ < 0) at its ends: the guess of Peak's Newton steps (−1 when
  // none is found). In t = s/L, p = Σ c_k t^k with c0..c2 from ja and
  //   c3 = 10A − 4B + C/2, c4 = −15A + 7B − C, c5 = 6A − 3B + C/2,
  // A = y1 − c0 − c1 − c2, B = y1' − c1 − 2c2, C = y1'' − 2c2 (the conditions at t = 1).
  static S QuinticZero(const S& L, const Jet& ja, const Jet& jb) {
    const S c1 = ja.rate * L, c2 = S(0.5) * ja.accel * L * L;
    const S A = jb.R - ja.R - c1 - c2, B = jb.rate * L - c1 - S(2) * c2, C = jb.accel * L * L - S(2) * c2;
    const S c3 = S(10) * A - S(4) * B + S(0.5) * C, c4 = S(-15) * A + S(7) * B - C, c5 = S(6) * A - S(3) * B + S(0.5) * C;
    const auto d = [&](const S& t) { return c1 + t * (S(2) * c2 + t * (S(3) * c3 + t * (S(4) * c4 + t * S(5) * c5))); };
    const auto dd = [&](const S& t) { return S(2) * c2 + t * (S(6) * c3 + t * (S(12) * c4 + t * S(20) * c5)); };
    // Safeguarded Newton on p' (p'(0) > 0 > p'(1)), from the zero of its chord.
    S lo(0), hi(1), t = c1 / (c1 - jb.rate * L);
    for (int it = 0; it < 30; ++it) {
      const S v = d(t);
      if (v == S(0)) break;
      (v > S(0) ? lo : hi) = t;
      const S g = dd(t);
      S next = g != S(0) ? S(t - v / g) : S(-1);
      if (!(next > lo && next < hi)) next = S(0.5) * (lo + hi);
      if (R::abs(next - t) < S(1e-9)) {
        t = next;
        break;
      }
      t = next;
    }
    return t > S(0) && t < S(1) ? S(t * L) : S(-1);
  }

  // The grid search, for an engine without a bound on R''' (the integrators): R and Ṙ on a grid of
  // spacing at most h = 1/ω_max (ω_max the largest of ω and the ω_i: R is a sum of oscillations no
  // faster, whose consecutive extrema are at least about π/ω_max apart), and in every cell where Ṙ
  // goes from + to −, the zero of Ṙ by regula falsi (Illinois) from the cubic Hermite guess, until
  // two estimates agree to 1e-7 h: R is flat there, so its error ½|R̈|δs² is at the rounding of R.
  // A maximum is missed only where Ṙ has two zeros inside one cell; R exceeds the larger cell end
  // there by at most max|R̈| h²/8. start, end: the ends of the stretch searched (local times of the
  // segment, which starts at forcing phase `phase`) with their jets.
  S GridMax(const ModelT<S>& m, const PropagatorT<S>& p, const S& phase, const S& wmax, const Node& start,
            const Node& end) {
    const S span = end.s - start.s;
    const int n = std::max(1, std::min(4096, static_cast<int>(R::to_double(span * wmax)) + 1));
    const S h = span / S(n);
    S rate_prev = start.j.rate;
    S best = start.j.R > end.j.R ? start.j.R : end.j.R;
    S s_prev = start.s, R_prev = start.j.R;
    for (int i = 1; i <= n; ++i) {
      const S s = i == n ? S(end.s) : S(start.s + h * S(i));
      S rate(0);
      const S Rv = i == n ? S(end.j.R) : At(m, p, phase, s, rate);
      if (i == n) rate = end.j.rate;
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
  // maximum, at the rounding of R (the grid search's refinement when the engine has R̈: the flat
  // segments the certified search hands over). False when the engine has no R̈.
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

  // R and Ṙ along the held flow at local time s, without allocation: the engine's own when it has
  // them (no state formed), else from the state (JetAt).
  S At(const ModelT<S>& m, const PropagatorT<S>& p, const S& phase, const S& s, S& rate) const {
    S held(0);
    if (p.HeldReaction(s, held, rate)) return held;
    p.Evaluate(s, Xs_, Vs_);
    const Jet j = JetAt(m, Xs_, Vs_, phase + m.w * s);
    rate = j.rate;
    return j.R;
  }
  // R, Ṙ and R̈ from a state on the held flow of m at forcing phase ph (keeps cos φ in cos_). The
  // constrained acceleration is Ẍ = −ΩX − DẊ + T_A f sin φ + T_B R (R = −cᵀ(free acceleration)/s_B,
  // the paper's eq. (5)), its derivative X⃛ = −ΩẊ − DẌ + T_A fω cos φ + T_B Ṙ, and
  //   s_B R = cᵀ(ΩX + DẊ) − s_A f sin φ,  s_B Ṙ = cᵀ(ΩẊ + DẌ) − s_A fω cos φ,
  //   s_B R̈ = cᵀ(ΩẌ + DX⃛) + s_A fω² sin φ.
  Jet JetAt(const ModelT<S>& m, const Vec& X, const Vec& V, const S& ph) const {
    S sn(0), cs(0);
    R::sincos(ph, sn, cs);
    cos_ = cs;
    if (!m.harmonics.empty()) return JetOfSum(m, X, V, ph);
    const S fs = m.f * sn, fc = m.f * m.w * cs;
    if (!m.damped) {
      // Undamped, with k_i = c_iω_i²: s_B R = Σ k_i X_i − s_A f sin φ, s_B Ṙ = Σ k_i Ẋ_i − s_A fω cos φ,
      // s_B R̈ = Σ k_i Ẍ_i + s_A fω² sin φ = −Σ k_iω_i² X_i + (Σ k_i T_A,i) f sin φ + (Σ k_i T_B,i) R
      // + s_A fω² sin φ: one pass.
      const Coefs& k = CoefsOf(m);
      S e(0), r(0), x4(0);
      for (Eigen::Index i = 0; i < X.size(); ++i) {
        e += k.k2[i] * X[i];
        r += k.k2[i] * V[i];
        x4 += k.k4[i] * X[i];
      }
      Jet j{(e - m.s_A * fs) * k.inv_sB, (r - m.s_A * fc) * k.inv_sB, S(0)};
      j.accel = (-x4 + k.kA * fs + k.kB * j.R + m.s_A * m.w * m.w * fs) * k.inv_sB;
      return j;
    }
    S elastic(0);
    for (Eigen::Index i = 0; i < X.size(); ++i) {
      if (m.shape[i] == S(0)) continue;
      const S w2 = m.omega[i] * m.omega[i];
      elastic += m.shape[i] * (w2 * X[i] + (m.damped ? S(S(2) * m.zeta[i] * m.omega[i] * V[i]) : S(0)));
    }
    const S inv = S(1) / m.s_B;
    Jet j{(elastic - m.s_A * fs) * inv, S(0), S(0)};
    S r(0), a(0);
    for (Eigen::Index i = 0; i < X.size(); ++i) {
      if (m.shape[i] == S(0)) continue;
      const S w2 = m.omega[i] * m.omega[i], d = m.damped ? S(S(2) * m.zeta[i] * m.omega[i]) : S(0);
      const S acc = -w2 * X[i] - d * V[i] + m.forcing[i] * fs + m.contact[i] * j.R;
      r += m.shape[i] * (w2 * V[i] + d * acc);
      a += m.shape[i] * w2 * acc;
    }
    j.rate = (r - m.s_A * fc) * inv;
    if (m.damped)
      for (Eigen::Index i = 0; i < X.size(); ++i) {
        if (m.shape[i] == S(0)) continue;
        const S w2 = m.omega[i] * m.omega[i], d = S(2) * m.zeta[i] * m.omega[i];
        const S acc = -w2 * X[i] - d * V[i] + m.forcing[i] * fs + m.contact[i] * j.R;
        a += m.shape[i] * d * (-w2 * V[i] - d * acc + m.forcing[i] * fc + m.contact[i] * j.rate);
      }
    j.accel = (a + m.s_A * m.f * m.w * m.w * sn) * inv;
    return j;
  }
  // JetAt under a sum of harmonics (docs/harmonics.md): the same relations with the forcing
  // Σ_h T_A^(h) f_h sin φ_h and its derivatives.
  Jet JetOfSum(const ModelT<S>& m, const Vec& X, const Vec& V, const S& ph) const {
    const auto& hs = m.harmonics;
    const Vec f0 = hs.Vector(ph, 0), f1 = hs.Vector(ph, 1);
    const S inv = S(1) / m.s_B;
    S elastic(0);
    for (Eigen::Index i = 0; i < X.size(); ++i)
      elastic += m.shape[i] * (m.omega[i] * m.omega[i] * X[i] + S(2) * m.zeta[i] * m.omega[i] * V[i]);
    Jet j{(elastic - hs.Contact(ph, 0)) * inv, S(0), S(0)};
    Vec acc(X.size());
    S r(0);
    for (Eigen::Index i = 0; i < X.size(); ++i) {
      const S w2 = m.omega[i] * m.omega[i], d = S(2) * m.zeta[i] * m.omega[i];
      acc[i] = -w2 * X[i] - d * V[i] + f0[i] + m.contact[i] * j.R;
      r += m.shape[i] * (w2 * V[i] + d * acc[i]);
    }
    j.rate = (r - hs.Contact(ph, 1)) * inv;
    S a(0);
    for (Eigen::Index i = 0; i < X.size(); ++i) {
      const S w2 = m.omega[i] * m.omega[i], d = S(2) * m.zeta[i] * m.omega[i];
      const S jerk = -w2 * V[i] - d * acc[i] + f1[i] + m.contact[i] * j.rate;
      a += m.shape[i] * (w2 * acc[i] + d * jerk);
    }
    j.accel = (a - hs.Contact(ph, 2)) * inv;
    return j;
  }
  // What JetAt needs of a model, made once per model (the automaton's models live for the run).
  struct Coefs {
    const ModelT<S>* m = nullptr;
    Vec k2, k4;      // c_iω_i², c_iω_i⁴
    Vec u, ud;       // u_i = c_i/ω_i² (ReactionIntegral's Ω⁻¹c) and u_i 2ζ_iω_i
    S uTA{0};        // Σ u_i T_A,i
    S kA{0}, kB{0};  // Σ c_iω_i² T_A,i, Σ c_iω_i² T_B,i
    S inv_sB{0}, wmax{0};
  };
  const Coefs& CoefsOf(const ModelT<S>& m) const {
    if (last_coefs_ && last_coefs_->m == &m) return *last_coefs_;
    return FindCoefs(m);
  }
  const Coefs& FindCoefs(const ModelT<S>& m) const {
    for (const Coefs& c : coefs_)
      if (c.m == &m) {
        last_coefs_ = &c;
        return c;
      }
    Coefs c;
    c.m = &m;
    const Eigen::Index n = m.omega.size();
    c.k2.resize(n);
    c.k4.resize(n);
    c.u.resize(n);
    c.ud.resize(n);
    c.wmax = m.w;
    if (m.harmonics.fastest > c.wmax) c.wmax = m.harmonics.fastest;
    for (Eigen::Index i = 0; i < n; ++i) {
      const S w2 = m.omega[i] * m.omega[i];
      c.k2[i] = m.shape[i] * w2;
      c.k4[i] = c.k2[i] * w2;
      c.kA += c.k2[i] * m.forcing[i];
      c.kB += c.k2[i] * m.contact[i];
      c.wmax = std::max(c.wmax, S(m.omega[i]));
      c.u[i] = m.shape[i] == S(0) ? S(0) : S(m.shape[i] / w2);
      c.ud[i] = c.u[i] * S(2) * m.zeta[i] * m.omega[i];
      c.uTA += c.u[i] * m.forcing[i];
    }
    c.inv_sB = S(1) / m.s_B;
    coefs_.push_back(std::move(c));
    last_coefs_ = &coefs_.back();
    return coefs_.back();
  }

 private:
  mutable Vec Xs_, Vs_;
  std::vector<std::pair<Node, Node>> cells_;  // the certified search's cells (no allocation per segment)
  S peak_phases_[4] = {};  // forcing phases of the last maxima found by Peak, the latest first
  int peaks_ = 0;
  mutable std::vector<Coefs> coefs_;
  mutable const Coefs* last_coefs_ = nullptr;  // the last one used (coefs_ only grows: reset with it)
  mutable S cos_{0};  // cos φ of the last state-based evaluation
};

}  // namespace vibro::detail
