// Sticking on two or more contacts at once (docs/contacts.md, "Sticking on several contacts"):
// the held flow X = X_p + V y of System::HeldOn in closed form (undamped constrained modes, one
// oscillator each; damped, the first-order closed form of dynamics/damped_sticking.hpp), the
// contact force of every held contact and the gap of every other contact as
// linear functionals of y, and the first certified root over all of them (docs/model.md §2.1):
// a held contact's force reaching 0 ends the segment as a release candidate (SegmentEnd::kRelease,
// `contact` the contact), another gap reaching 0 as a contact (kContact).
// The constrained data are double whatever S (as for one held contact): in quad the flow is exact
// for the double-rounded constrained modes.
#pragma once

#include <algorithm>
#include <vector>

#include "dynamics/damped_sticking.hpp"
#include "dynamics/flight_window.hpp"
#include "dynamics/model_t.hpp"
#include "dynamics/oscillator.hpp"
#include "dynamics/propagator.hpp"
#include "dynamics/root_finder.hpp"
#include "vibro/system.hpp"

namespace vibro::detail {

template <class S>
class SetStickingT final : public PropagatorT<S> {
 public:
  using Vec = typename ModelT<S>::Vec;
  using Mat = typename ModelT<S>::Mat;
  using R = Real<S>;

  // `models` are every contact's model (index = contact); `set` the held contacts, ascending.
  SetStickingT(const System& sys, const std::vector<const ModelT<S>*>& models, const std::vector<int>& set)
      : h_(sys.HeldOn(set)),
        omega_(S(sys.frequency())),
        f_(S(sys.amplitude())),
        base_(h_.base.cast<S>()),
        vectors_(h_.vectors.cast<S>()),
        left_(h_.left.cast<S>()),
        lam_static_(h_.reaction_static.cast<S>()),
        lam_rho_(h_.reaction.cast<S>()),
        lam_forcing_(h_.reaction_forcing.cast<S>()) {
    for (Eigen::Index k = 0; k < h_.frequencies.size(); ++k)
      modes_.push_back({S(h_.frequencies[k]), S(0), S(h_.modal_forcing[k]) * f_});
    damped_ = h_.damping.size() > 0 && h_.damping.cwiseAbs().maxCoeff() > 0;
    if (damped_) {
      // One damped closed form per held force (the same flow, each with its force's data).
      for (Eigen::Index a = 0; a < static_cast<Eigen::Index>(set.size()); ++a) {
        const DampedFlowData d{sys.frequency(), sys.amplitude(), h_.frequencies, h_.modal_forcing,
                               h_.damping, h_.reaction_static[a],
                               h_.reaction_forcing[a] * sys.amplitude(),
                               h_.reaction.row(a).transpose(), h_.reaction_velocity.row(a).transpose()};
        flows_.emplace_back(d);
        ok_ = ok_ && flows_.back().ok();
      }
    }
    S fastest = omega_;
    for (const auto& o : modes_) fastest = o.nu > fastest ? o.nu : fastest;
    h_cap_ = S(0.25) * S(2) * R::pi() / fastest;
    const auto m = models.size();
    weights_.resize(m);
    bases_.resize(m);
    held_.assign(m, false);
    for (int j : set) held_[static_cast<size_t>(j)] = true;
    for (size_t j = 0; j < m; ++j) {
      if (held_[j]) continue;
      weights_[j] = vectors_.transpose() * models[j]->shape;
      bases_[j] = models[j]->shape.dot(base_) - models[j]->x0;
    }
  }

  const std::vector<int>& set() const { return h_.set; }
  // The damped closed form exists (false for a defective system, e.g. exactly critical damping).
  bool ok() const { return ok_; }
  bool damped() const { return damped_; }

  void Begin(const SegmentStartT<S>& s) override {
    phase_ = s.phase;
    trig_ = PhaseTrigT<S>(s.phase);
    y0_ = left_ * (s.X - base_);
    dy0_ = left_ * s.V;
    for (auto& fl : flows_) fl.Begin(y0_, dy0_, s.phase);
    starts_.assign(held_.size(), FlightStart::kGeneric);
    if (s.starts) starts_ = *s.starts;
    skip_ = s.skip;
    // Every free gap as its start value plus increments (exactly the automaton's at σ = 0).
    gap0_.assign(held_.size(), S(0));
    for (size_t k = 0; k < held_.size(); ++k)
      if (!held_[k]) gap0_[k] = s.gaps ? (*s.gaps)[k] : bases_[k] + weights_[k].dot(y0_);
  }

  SegmentResultT<S> Advance(S sigma_max, bool detect, const StretchCallbackT<S>& cb) override {
    SegmentResultT<S> best{SegmentEnd::kLimit, sigma_max, {}};
    if (detect) {
      // Contact forces: a force starting at zero (rising, or a tangency that did not cross)
      // divides out its known zero as a sticking phase on one contact does.
      for (size_t a = 0; a < h_.set.size(); ++a) {
        const auto probe = [this, a](const S& u, const S& H, const S&) { return ForceProbe(a, u, H); };
        const ProbeT<S> p0 = probe(S(0), h_cap_, S(0));
        S w(0);
        const S scale = R::abs(lam_static_[static_cast<Eigen::Index>(a)]) +
                        R::abs(lam_forcing_[static_cast<Eigen::Index>(a)] * f_) + S(1e-300);
        if (!(p0.jet.g > S(64) * Eps<S>() * scale)) {
          const auto cap = [&](const S& x) { return x < h_cap_ ? x : h_cap_; };
          const S v = p0.jet.g1, acc = p0.jet.g2, M = p0.M;
          if (v > 0)
            w = cap(M > 0 ? S((S(0.5) * acc + R::sqrt(S(0.25) * acc * acc + S(2) * M * v / 3)) / (M / 3))
                          : S(acc < 0 ? S(S(2) * v / -acc) : h_cap_));
          else if (acc > 0)
            w = M > 0 ? cap(S(3) * acc / M) : h_cap_;
          else
            w = S(0);  // at zero and not rising: a release candidate at the start
        }
        if (w >= best.sigma) continue;
        auto r = Search(probe, w, best.sigma, SegmentEnd::kRelease);
        if (r.end == SegmentEnd::kFailure) return r;
        Keep(best, r, h_.set[a]);
      }
      for (size_t k = 0; k < held_.size(); ++k) {
        if (held_[k] || static_cast<int>(k) == skip_ || weights_[k].size() == 0 || weights_[k].cwiseAbs().maxCoeff() == S(0)) continue;
        // A known zero only while the gap is 0 (as the exact engine's flights).
        const FlightStart start = gap0_[k] == S(0) ? starts_[k] : FlightStart::kGeneric;
        S w(0);
        if (start != FlightStart::kGeneric) w = CertifiedWindow<S>(start, GapStartJet(k), h_cap_);
        if (w >= best.sigma) continue;
        auto r = Search([this, k](const S& u, const S& H, const S&) { return GapProbe(k, u, H); }, w,
                        best.sigma, SegmentEnd::kContact);
        if (r.end == SegmentEnd::kFailure) return r;
        Keep(best, r, static_cast<int>(k));
      }
    }
    if (cb) cb(S(0), best.sigma);
    return best;
  }

  void Evaluate(S sigma, Vec& X, Vec& V) const override {
    Vec y, dy;
    Modes(sigma, y, dy);
    X = base_ + vectors_ * y;
    V = vectors_ * dy;
  }
  S Gap(S) const override { return S(0); }
  S GapOf(int j, S sigma) const override {
    if (held_[static_cast<size_t>(j)]) return S(0);
    return GapProbe(static_cast<size_t>(j), sigma, S(0)).jet.g;
  }
  // A linear functional uᵀX − κ f sin(φ + ωσ) of the held flow: its two derivatives at σ and a
  // bound of its third over [σ, σ + H] (a chattering tail's gap deceleration, docs/contacts.md).
  // Damped, the functional may also depend on the velocity: uᵀX + u_vᵀẊ − κ f sin.
  ProbeT<S> Functional(const Vec& u, const Vec& u_v, const S& kappa, const S& sigma, const S& H) const {
    if (damped_)
      return flows_.front().FunctionalProbe(vectors_.transpose() * u, vectors_.transpose() * u_v,
                                            u.dot(base_), kappa * f_, sigma);
    return LinearProbe(vectors_.transpose() * u, u.dot(base_), kappa * f_, sigma, H);
  }
  // The contact force of held contact `contact` and its two derivatives at σ.
  JetT<S> Force(int contact, const S& sigma) const {
    const auto it = std::find(h_.set.begin(), h_.set.end(), contact);
    return ForceProbe(static_cast<size_t>(it - h_.set.begin()), sigma, S(0)).jet;
  }
  // A bound on the third derivative of that force over [0, H] (the one its release search steps
  // with; damped, valid for every σ ≥ 0).
  S ForceBound(int contact, const S& H) const {
    const auto it = std::find(h_.set.begin(), h_.set.end(), contact);
    return ForceProbe(static_cast<size_t>(it - h_.set.begin()), S(0), H).M;
  }

 private:
  void Modes(const S& sigma, Vec& y, Vec& dy) const {
    if (damped_) {
      flows_.front().Evaluate(sigma, y, dy);
      return;
    }
    const auto k = static_cast<Eigen::Index>(modes_.size());
    y.resize(k);
    dy.resize(k);
    const ForcingTrigT<S> fw(omega_, sigma);
    for (Eigen::Index q = 0; q < k; ++q) {
      const auto st = Flow<S>(modes_[static_cast<size_t>(q)], omega_, trig_, y0_[q], dy0_[q], sigma, fw);
      y[q] = y0_[q] + st.dq;
      dy[q] = st.v;
    }
  }

  // base + wᵀy − c f sin(φ + ωσ) (`increments`: base + wᵀ(y − y0), base the value at σ = 0) with
  // its jet and a bound of its third derivative over [σ, σ + H].
  ProbeT<S> LinearProbe(const Vec& w, const S& base, const S& c, const S& sigma, const S& H,
                        bool increments = false) const {
    const ForcingTrigT<S> fw(omega_, sigma);
    const S sf = fw.SinPhase(trig_), cf = fw.CosPhase(trig_);
    ProbeT<S> p{{base - c * sf, -c * omega_ * cf, c * omega_ * omega_ * sf},
                R::abs(c) * omega_ * omega_ * omega_};
    for (size_t q = 0; q < modes_.size(); ++q) {
      const auto qq = static_cast<Eigen::Index>(q);
      if (w[qq] == S(0)) continue;
      const OscillatorT<S>& o = modes_[q];
      const auto st = Flow<S>(o, omega_, trig_, y0_[qq], dy0_[qq], sigma, fw);
      const S y = y0_[qq] + st.dq;
      const S acc = -o.nu * o.nu * y + o.F * sf;
      p.jet.g += w[qq] * (increments ? st.dq : y);
      p.jet.g1 += w[qq] * st.v;
      p.jet.g2 += w[qq] * acc;
      p.M += R::abs(w[qq]) * Bounds<S>(o, omega_, Amplitude<S>(o, y, st.v) + R::abs(o.F) * H).d3;
    }
    p.M *= S(1) + S(1e-9);
    return p;
  }
  ProbeT<S> ForceProbe(size_t a, const S& sigma, const S& H) const {
    if (damped_) return flows_[a].ReactionProbe(sigma);
    const auto aa = static_cast<Eigen::Index>(a);
    return LinearProbe(lam_rho_.row(aa).transpose(), lam_static_[aa], lam_forcing_[aa] * f_, sigma, H);
  }
  ProbeT<S> GapProbe(size_t k, const S& sigma, const S& H) const {
    if (damped_) return flows_.front().LinearProbe(weights_[k], gap0_[k], sigma);
    return LinearProbe(weights_[k], gap0_[k], S(0), sigma, H, true);
  }
  // A gap's derivatives at σ = 0 and bounds of its third and fourth over [0, h_cap] (a contact
  // that starts at zero: after an impact, a departure or a release while the set is held).
  FlightJetT<S> GapStartJet(size_t k) const {
    if (damped_) return flows_.front().StartJet(weights_[k]);
    FlightJetT<S> j{S(0), S(0), S(0), S(0), S(0)};
    const Vec& w = weights_[k];
    for (size_t q = 0; q < modes_.size(); ++q) {
      const auto qq = static_cast<Eigen::Index>(q);
      if (w[qq] == S(0)) continue;
      const OscillatorT<S>& o = modes_[q];
      const S acc = -o.nu * o.nu * y0_[qq] + o.F * trig_.s;
      const S jerk = -o.nu * o.nu * dy0_[qq] + o.F * omega_ * trig_.c;
      const auto b = Bounds<S>(o, omega_, Amplitude<S>(o, y0_[qq], dy0_[qq]) + R::abs(o.F) * h_cap_);
      j.g1 += w[qq] * dy0_[qq];
      j.g2 += w[qq] * acc;
      j.g3 += w[qq] * jerk;
      j.M3 += R::abs(w[qq]) * b.d3;
      j.M4 += R::abs(w[qq]) * b.d4;
    }
    j.M3 *= S(1) + S(1e-9);
    j.M4 *= S(1) + S(1e-9);
    return j;
  }
  template <class ProbeFn>
  SegmentResultT<S> Search(const ProbeFn& probe, const S& from, const S& to, SegmentEnd end) {
    const auto rs = FirstRootPolled<S>(probe, from, to, h_cap_, [this] { return this->StopRequested(); });
    if (rs.stopped) return {SegmentEnd::kFailure, rs.result.sigma, "stopped inside a root search", S(-1), true};
    if (!rs.result.found) return {SegmentEnd::kLimit, to, {}};
    return {end, rs.result.sigma, {}};
  }
  static void Keep(SegmentResultT<S>& best, SegmentResultT<S>& r, int j) {
    if (r.end == SegmentEnd::kLimit) return;
    if (r.sigma < S(0)) r.sigma = S(0);
    if (best.end == SegmentEnd::kLimit || r.sigma < best.sigma) {
      best = r;
      best.contact = j;
    }
  }

  HeldSetModes h_;
  S omega_, f_, h_cap_{0};
  bool damped_ = false, ok_ = true;
  std::vector<DampedStickingT<S>> flows_;  // damped: one per held force
  Vec base_;
  Mat vectors_, left_;
  Vec lam_static_;
  Mat lam_rho_;
  Vec lam_forcing_;
  std::vector<OscillatorT<S>> modes_;
  std::vector<Vec> weights_;  // g_k = bases_[k] + weights_[k]ᵀ y for a contact not held
  std::vector<S> bases_, gap0_;
  std::vector<bool> held_;
  std::vector<FlightStart> starts_;
  int skip_ = -1;  // a contact left out of the search (a chattering tail's own)
  S phase_{0};
  PhaseTrigT<S> trig_{S(0)};
  Vec y0_, dy0_;
};

}  // namespace vibro::detail
