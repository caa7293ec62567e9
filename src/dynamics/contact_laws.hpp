// The contact laws of several contacts (docs/contacts.md): the impact LCP (I2), the
// acceleration-level LCP (S3) that decides which contacts at rest stick, the plastic projection
// onto a set, and the automaton's transitions that use them: a start on several stops, impacts
// in free flight and while one contact or a set is held, entry into and release from a held set,
// and a chattering sequence beside a held set (pseudocode in include/vibro/simulator.hpp).
// The laws first, as free functions of the contacts' models; then the members of Automaton
// (dynamics/automaton.hpp, which includes this file after its class).
#pragma once

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "dynamics/model_t.hpp"

namespace vibro::detail {

template <class S>
using ContactModelsT = std::vector<const ModelT<S>*>;

// W_jk = c_jᵀT_k between two contacts, 0 when it is within the rounding of the model's (double)
// mode shapes, whatever S: contacts on different masses of a diagonal mass matrix are decoupled
// (MODEL §11.10), and a rounding-level coupling would push a held contact off its stop.
template <class S>
S DelassusOffDiagonal(const ModelT<S>& a, const ModelT<S>& b) {
  const S w = a.shape.dot(b.contact);
  const S scale = Real<S>::sqrt(a.s_B * b.s_B);
  return Real<S>::abs(w) <= S(64 * std::numeric_limits<double>::epsilon()) * scale ? S(0) : w;
}

// The Delassus matrix W_ZZ of the contacts Z: W_jj = c_jᵀT_j computed in S (s_B of j to the model's
// double rounding; the same product as the update V += T_j P, so that an impulse solved from W
// leaves a gap velocity at S's rounding, not double's: a plastic pair of contacts in quad otherwise
// closed again at 1e-17 after their joint impact, an endless cascade at one instant), W_jk as above.
template <class S>
typename ModelT<S>::Mat Delassus(const ContactModelsT<S>& models, const std::vector<int>& Z) {
  const auto z = static_cast<Eigen::Index>(Z.size());
  typename ModelT<S>::Mat W(z, z);
  for (Eigen::Index a = 0; a < z; ++a) {
    const ModelT<S>& ma = *models[static_cast<size_t>(Z[static_cast<size_t>(a)])];
    for (Eigen::Index b = 0; b < z; ++b)
      W(a, b) = a == b ? ma.shape.dot(ma.contact) : DelassusOffDiagonal(ma, *models[static_cast<size_t>(Z[static_cast<size_t>(b)])]);
  }
  return W;
}

// The free modal acceleration Ẍ = −ΩX − DẊ + T_A f sin φ (every contact's model has the same).
template <class S>
typename ModelT<S>::Vec FreeAcceleration(const ModelT<S>& m, const typename ModelT<S>::Vec& X,
                                         const typename ModelT<S>::Vec& V, const S& phase) {
  if (!m.harmonics.empty())  // a sum of harmonics (docs/harmonics.md)
    return -m.omega.cwiseAbs2().cwiseProduct(X) - S(2) * m.zeta.cwiseProduct(m.omega).cwiseProduct(V) +
           m.harmonics.Vector(phase);
  return -m.omega.cwiseAbs2().cwiseProduct(X) - S(2) * m.zeta.cwiseProduct(m.omega).cwiseProduct(V) +
         m.forcing * (m.f * Real<S>::sin(phase));
}

// Gap acceleration g_k'' under the flow with contact `held` stuck: c_kᵀ Π Ẍ_free, Π = I − T cᵀ/s.
template <class S>
S HeldGapAcceleration(const ModelT<S>& held, const ModelT<S>& k, const typename ModelT<S>::Vec& X,
                      const typename ModelT<S>::Vec& V, const S& phase) {
  using Vec = typename ModelT<S>::Vec;
  const Vec acc = FreeAcceleration(k, X, V, phase);
  const Vec held_acc = acc - held.contact * (held.shape.dot(acc) / held.s_B);
  return k.shape.dot(held_acc);
}

// The LCP w = W x + q, 0 ≤ x ⊥ w ≥ 0 by enumerating the index sets (W positive definite: exactly
// one fits), within tol[a] of each sign condition of row a. False when none fits (W singular:
// dependent contacts).
template <class S>
bool SolveLcp(const typename ModelT<S>::Mat& W, const typename ModelT<S>::Vec& q,
              const typename ModelT<S>::Vec& tol, typename ModelT<S>::Vec& x) {
  using Mat = typename ModelT<S>::Mat;
  using Vec = typename ModelT<S>::Vec;
  const auto z = q.size();
  for (unsigned mask = 0; mask < (1u << z); ++mask) {
    std::vector<Eigen::Index> act;
    for (Eigen::Index a = 0; a < z; ++a)
      if (mask & (1u << a)) act.push_back(a);
    const auto na = static_cast<Eigen::Index>(act.size());
    Vec xt = Vec::Zero(z);
    if (na > 0) {
      Mat Wa(na, na);
      Vec qa(na);
      for (Eigen::Index a = 0; a < na; ++a) {
        qa[a] = -q[act[static_cast<size_t>(a)]];
        for (Eigen::Index b = 0; b < na; ++b) Wa(a, b) = W(act[static_cast<size_t>(a)], act[static_cast<size_t>(b)]);
      }
      const Vec xa = Wa.fullPivLu().solve(qa);
      for (Eigen::Index a = 0; a < na; ++a) xt[act[static_cast<size_t>(a)]] = xa[a];
    }
    const Vec w = W * xt + q;
    // Each sign condition within tol[a] and the rounding of its row's terms (a resting contact,
    // q_a = 0, has w_a = Σ W_ab x_b ≈ 0 only to the rounding of the products).
    const Vec row_scale = W.cwiseAbs() * xt.cwiseAbs();
    bool ok = true;
    for (Eigen::Index a = 0; a < z; ++a) {
      const S slack = tol[a] + S(64) * Eps<S>() * row_scale[a];
      if (xt[a] < -slack || w[a] < -slack) ok = false;
    }
    if (ok) {
      x = xt.cwiseMax(S(0));
      return true;
    }
  }
  return false;
}

// Plastic projection onto {g_j = ġ_j = 0, j ∈ Z} (MODEL §11.5.3): Ẋ ← Ẋ − T_Z W_ZZ⁻¹ C_Z Ẋ and
// X ← X − T_Z W_ZZ⁻¹ (C_Z X − e_Z).
template <class S>
void ProjectOnto(const ContactModelsT<S>& models, const std::vector<int>& Z, typename ModelT<S>::Vec& X,
                 typename ModelT<S>::Vec& V) {
  using Vec = typename ModelT<S>::Vec;
  const auto z = static_cast<Eigen::Index>(Z.size());
  const auto model = [&](Eigen::Index a) -> const ModelT<S>& { return *models[static_cast<size_t>(Z[static_cast<size_t>(a)])]; };
  if (z == 1) {
    model(0).ProjectOntoStop(X, V);
    return;
  }
  Vec gx(z), gv(z);
  for (Eigen::Index a = 0; a < z; ++a) {
    gx[a] = model(a).ContactDisplacement(X) - model(a).x0;
    gv[a] = model(a).ContactVelocity(V);
  }
  const auto lu = Delassus(models, Z).fullPivLu();
  const Vec px = lu.solve(gx), pv = lu.solve(gv);
  for (Eigen::Index a = 0; a < z; ++a) {
    X -= model(a).contact * px[a];
    V -= model(a).contact * pv[a];
  }
}

// Π_Z v = v − T_Z W_ZZ⁻¹ C_Z v: v with the contacts of Z held (a velocity or an acceleration).
template <class S>
typename ModelT<S>::Vec ProjectAlong(const ContactModelsT<S>& models, const std::vector<int>& Z,
                                     const typename ModelT<S>::Vec& v) {
  using Vec = typename ModelT<S>::Vec;
  const auto z = static_cast<Eigen::Index>(Z.size());
  Vec cv(z);
  for (Eigen::Index a = 0; a < z; ++a) cv[a] = models[static_cast<size_t>(Z[static_cast<size_t>(a)])]->shape.dot(v);
  const Vec x = Delassus(models, Z).fullPivLu().solve(cv);
  Vec out = v;
  for (Eigen::Index a = 0; a < z; ++a) out -= models[static_cast<size_t>(Z[static_cast<size_t>(a)])]->contact * x[a];
  return out;
}

// The gradient of the jump time of a chattering tail beside held contacts (Automaton::
// TryHeldAccumulation, MODEL §11.6), for the Jacobian of the jump (docs/contacts.md, "Periodic
// orbits"); length 2n in (X, Ẋ), at the post-impact state (X, Ẋ) of contact k with the set S held.
// The prediction: (Xs, Ẋs) = the state projected onto Z = S ∪ {k} (∂ = P_Z on both), a = the free
// acceleration there, p = Π_Sᵀc_k, A = −pᵀa, Ȧ = −pᵀ(−ΩẊs − D P_Z a + Ḟ), u = c_kᵀẊ and
//   Δ∞ = Δ0 − ȦΔ0²/(3A),  Δ0 = 2u/((1 − r)A),
//   ∂Δ∞ = ∂Δ0 (1 + 2ε/3) − Δ0²/(3A) ∂Ȧ − εΔ0/(3A) ∂A,  ∂Δ0 = 2∂u/((1 − r)A) − Δ0 ∂A/A,  ε = −ȦΔ0/A,
// with ∂A = (P_ZᵀΩp, P_ZᵀDp) and ∂Ȧ = (−P_ZᵀΩP_ZᵀDp, P_ZᵀΩp − P_ZᵀDP_ZᵀDp). As for one contact
// (chatter_tail.hpp, DeltaGradient): a perturbation after the impact is a state at the nominal
// impact time, off the stop by δg = c_kᵀδX, whose impact was τ = −δg/u later; so the gradient of
// the jump taken is ∇Δ∞ − (1 + dΔ∞/dt)(c_k, 0)/u, dΔ∞/dt its rate along the S-flow from (X, Ẋ)
// (the state's field and the forcing's phase).
template <class S>
Eigen::VectorXd HeldTailGradient(const ContactModelsT<S>& models, int k, const std::vector<int>& held,
                                 const std::vector<int>& Z, const typename ModelT<S>::Vec& X,
                                 const typename ModelT<S>::Vec& V, const S& phase) {
  using Vec = typename ModelT<S>::Vec;
  using Mat = typename ModelT<S>::Mat;
  using Rl = Real<S>;
  const ModelT<S>& mk = *models[static_cast<size_t>(k)];
  const auto n = mk.dof();
  Mat PZ(n, n), PS(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec e = Vec::Unit(n, i);
    PZ.col(i) = ProjectAlong(models, Z, e);
    PS.col(i) = ProjectAlong(models, held, e);
  }
  const Vec w2 = mk.omega.cwiseAbs2();
  const Vec D = S(2) * mk.zeta.cwiseProduct(mk.omega);
  const Mat Om = w2.asDiagonal(), Dm = D.asDiagonal();
  const Vec p = PS.transpose() * mk.shape;
  // The projected state: ProjectOnto (not linear in X: the stops' positions), as the prediction.
  Vec Xp = X, Vp = V;
  ProjectOnto<S>(models, Z, Xp, Vp);
  const auto forcing = [&](int d) -> Vec {  // d-th time derivative of the modal forcing
    if (!mk.harmonics.empty()) return mk.harmonics.Vector(phase, d);
    const S w_d = d == 0 ? S(1) : d == 1 ? mk.w : mk.w * mk.w;
    const S s = d == 0 ? Rl::sin(phase) : d == 1 ? Rl::cos(phase) : S(-Rl::sin(phase));
    return mk.forcing * (mk.f * w_d * s);
  };
  const Vec a = -w2.cwiseProduct(Xp) - D.cwiseProduct(Vp) + forcing(0);
  const S u = mk.ContactVelocity(V), r = mk.r;
  const S A = -p.dot(a);
  const S A_rate = -p.dot(-w2.cwiseProduct(Vp) - D.cwiseProduct(PZ * a) + forcing(1));
  const S d0 = S(2) * u / ((S(1) - r) * A);
  const S eps = -A_rate * d0 / A;
  Vec gA(2 * n), gAr(2 * n), gu = Vec::Zero(2 * n);
  gA << PZ.transpose() * (Om * p), PZ.transpose() * (Dm * p);
  gAr << -(PZ.transpose() * (Om * (PZ.transpose() * (Dm * p)))),
      PZ.transpose() * (Om * p) - PZ.transpose() * (Dm * (PZ.transpose() * (Dm * p)));
  gu.tail(n) = mk.shape;
  const S dD_du = S(2) / ((S(1) - r) * A) * (S(1) + S(2) * eps / 3);
  const S dD_dA = -d0 / A * (S(1) + S(2) * eps / 3) - eps * d0 / (S(3) * A);
  const S dD_dAr = -d0 * d0 / (S(3) * A);
  Vec g = dD_du * gu + dD_dA * gA + dD_dAr * gAr;
  // dΔ∞/dt along the S-flow from (X, Ẋ): the state's field, and the forcing's explicit rates.
  Vec field(2 * n);
  field << V, PS * (-w2.cwiseProduct(X) - D.cwiseProduct(V) + forcing(0));
  const Vec F1 = forcing(1), F2 = forcing(2);
  const S dA_dt = -p.dot(F1);
  const S dAr_dt = -p.dot(-D.cwiseProduct(PZ * F1) + F2);
  const S rate = g.dot(field) + dD_dA * dA_dt + dD_dAr * dAr_dt;
  g.head(n) -= (S(1) + rate) * mk.shape / u;
  return g.template cast<double>();
}

// The automaton's transitions at several contacts ------------------------------------------------

// A start with several contacts: which gaps are closed (docs/contacts.md).
template <class S>
void Automaton<S>::ClassifyInitialContacts() {
  // Which gaps are closed (within the rounding of the initial state, as
  // System::StopTolerance for one contact); one closed contact is classified as the single stop
  // is, on its own model; none starts a free flight. The decision is taken within double's
  // rounding whatever S, as for the single stop (ClassifyInitialState): the quad engine solves
  // the problem the double one is given, whose data are double, so a start on several stops in
  // double (e.g. at rest on preloaded stops) is on them in quad too, not 1e-17 above them.
  const S eps_d(std::numeric_limits<double>::epsilon());
  const auto closed_tol = [&](const ModelT<S>& c) {
    return S(System::kStopUlps) * eps_d * (R::abs(c.x0) + c.shape.cwiseProduct(X_).cwiseAbs().sum());
  };
  int on = -1, closed = 0;
  for (int j = 0; j < static_cast<int>(models_.size()); ++j) {
    const ModelT<S>& c = M(j);
    const S g = c.ContactDisplacement(X_) - c.x0;
    gaps_[static_cast<size_t>(j)] = g;
    starts_[static_cast<size_t>(j)] = FlightStart::kGeneric;
    if (g <= closed_tol(c)) {
      on = j;
      ++closed;
    }
  }
  if (closed > 1) {
    // Several closed gaps: those moving away leave, the others are at rest on their stops and the
    // acceleration LCP decides which stick (their stick events follow the initial section).
    std::vector<int> Z0;
    std::vector<char> is_closed(models_.size(), 0);
    for (int j = 0; j < static_cast<int>(models_.size()); ++j)
      is_closed[static_cast<size_t>(j)] = gaps_[static_cast<size_t>(j)] <= closed_tol(M(j)) ? 1 : 0;
    for (int j = 0; j < static_cast<int>(models_.size()); ++j) {
      const ModelT<S>& c = M(j);
      if (!is_closed[static_cast<size_t>(j)]) continue;
      gaps_[static_cast<size_t>(j)] = 0;
      X_ -= c.contact * ((c.ContactDisplacement(X_) - c.x0) / c.s_B);
      const S vtol = S(System::kStopUlps) * eps_d * c.shape.cwiseProduct(V_).cwiseAbs().sum();
      if (c.ContactVelocity(V_) > vtol) starts_[static_cast<size_t>(j)] = FlightStart::kAfterImpact;
      else Z0.push_back(j);
    }
    active_ = Z0.empty() ? on : Z0.front();
    EnterActiveSet(Z0, {}, false);  // a failure ends the run before its first segment
    return;
  }
  if (closed == 0) {
    active_ = 0;
    gap_ = gaps_[0];
    Depart(FlightStart::kGeneric);
    return;
  }
  active_ = on;
  const ModelT<S>& m = M(on);
  gap_ = 0;
  gaps_[static_cast<size_t>(on)] = 0;
  X_ -= m.contact * ((m.ContactDisplacement(X_) - m.x0) / m.s_B);
  if (m.ContactVelocity(V_) > 0) {
    Depart(FlightStart::kAfterImpact);
    return;
  }
  V_ -= m.contact * (m.ContactVelocity(V_) / m.s_B);
  const S phase = Phase(clock_);
  const S Rc = m.Reaction(X_, V_, phase);
  if (Rc > 0) {
    EnterSticking(StickStart::kGeneric);
  } else if (Rc < 0) {
    m.ProjectOntoStop(X_, V_);
    Depart(FlightStart::kDeparture);
  } else if (m.ReactionRate(X_, V_, phase) >= 0) {
    EnterSticking(StickStart::kRising);
  } else {
    m.ProjectOntoStop(X_, V_);
    Depart(FlightStart::kAfterRelease);
  }
}

template <class S>
void Automaton<S>::UpdateGaps(PropagatorT<S>& p, const S& sigma) {
  const bool resting = held_set_.empty() && &p != engine_.get();
  for (size_t j = 0; j < models_.size(); ++j) {
    const int jj = static_cast<int>(j);
    if (mode_ == Mode::kSticking && (jj == active_ || Held(jj)))
      gaps_[j] = S(0);
    else if (resting)
      gaps_[j] = models_[j]->ContactDisplacement(X_) - models_[j]->x0;  // constant at rest
    else
      gaps_[j] = p.GapOf(jj, sigma);
    // A start kind (a zero divided out at the segment's start, MODEL §11.2.3) holds for a gap that
    // is 0 where the next segment starts: one the segment left (σ > 0, the gap open again) starts
    // generic; one still at its zero within rounding keeps it (σ within the window of its start).
    // A kind kept past its zero would let the next search divide out a zero that is not there and
    // skip the gap's next root (issue 37: a pair's departure while another contact stuck, its gap
    // flown through after that contact's release).
    if (sigma > S(0) && !(mode_ == Mode::kSticking && (jj == active_ || Held(jj)))) {
      if (gaps_[j] > S(0)) starts_[j] = FlightStart::kGeneric;
      else if (starts_[j] != FlightStart::kGeneric) gaps_[j] = S(0);
    }
  }
  if (sigma > S(0) && mode_ == Mode::kSticking) stick_start_ = StickStart::kGeneric;
  if (mode_ == Mode::kFree) {
    gap_ = gaps_[static_cast<size_t>(active_)];
    flight_start_ = starts_[static_cast<size_t>(active_)];
  }
}

// Whether the free flow over a chattering tail at the active contact keeps every other gap open
// (certified search of their first roots over [0, Δ∞], the tail's own contact left out).
template <class S>
bool Automaton<S>::TailClearOfOtherContacts(const S& delta) {
  std::vector<FlightStart> starts = starts_;
  starts[static_cast<size_t>(active_)] = FlightStart::kAfterImpact;
  engine_->Begin({Mode::kFree, Phase(clock_), clock_.offset, X_, V_, S(0), FlightStart::kAfterImpact,
                  StickStart::kGeneric, active_, &gaps_, &starts, active_});
  const auto r = engine_->Advance(delta, true, {});
  return r.end == SegmentEnd::kLimit;
}

// Whether another contact had an impact within 10 tail lengths Δ∞ before now: the sequence at k is
// then interleaved with that contact's impacts (two contacts chattering together, whose joint tail
// is not predicted, MODEL §11.6), not one contact's tail. Its impacts are followed instead: they
// either end (the tail at k alone is predicted a few impacts later) or meet PairChatter.
template <class S>
bool Automaton<S>::RecentOtherImpact(int k, const S& delta) const {
  const double now = AbsTime(clock_), window = 10 * R::to_double(delta);
  for (size_t j = 0; j < last_impact_t_.size(); ++j)
    if (static_cast<int>(j) != k && now - last_impact_t_[j] < window) return true;
  return false;
}

// Two contacts chattering at once toward one accumulation point (MODEL §11.6, docs/contacts.md):
// impacts that alternate between two contacts with flights below 1e-9 T, closing slower and
// slower. Their tail is not predicted (no geometric tail with one ratio exists); after more than
// three such alternations in a row, once the closing speed at k has fallen below half its first
// speed in the cascade, the run ends undetermined instead of following them to the rounding floor
// and guessing there: the criterion of the independent reference (tests/reference/contacts/
// reference.py). Half the first speed, not each impact slower than the last: speeds that wobble
// on the way down still end (random search scenes 377, 433), while elastic bouncing between two
// stops closer than 1e-9 T of flight, which accumulates nowhere, goes on (10⁹ impacts per time
// unit meet the pace check, docs/cli.md). False when it ended.
template <class S>
bool Automaton<S>::PairChatter(int k) {
  const S v = M(k).ContactVelocity(V_);
  const S speed = v < S(0) ? S(-v) : S(0);
  const double now = AbsTime(clock_);
  const bool alternating = pair_last_ >= 0 && pair_last_ != k && now - pair_t_ < 1e-9 * R::to_double(period_);
  pair_cascade_ = alternating ? pair_cascade_ + 1 : 0;
  const auto kk = static_cast<size_t>(k);
  if (!alternating) std::fill(pair_first_speed_.begin(), pair_first_speed_.end(), -1.0);
  if (pair_first_speed_[kk] < 0) pair_first_speed_[kk] = R::to_double(speed);
  const int other = pair_last_;
  pair_last_ = k;
  pair_t_ = now;
  if (pair_cascade_ <= 3 || !(R::to_double(speed) < 0.5 * pair_first_speed_[kk])) return true;
  return Fail(fmt::format("contacts {} ({}) and {} ({}) chatter together toward one accumulation point "
                          "near t = {:.17g}: {} alternating impacts within 1e-9 T (last closing speed "
                          "{:.3g}). The accumulation point of two contacts chattering at once is not "
                          "predicted (docs/contacts.md): undetermined, not guessed. Move the parameter.",
                          std::min(k, other), labels_[static_cast<size_t>(std::min(k, other))],
                          std::max(k, other), labels_[static_cast<size_t>(std::max(k, other))], now,
                          pair_cascade_ + 1, R::to_double(speed)),
              RunStatus::kUndetermined);
}

// Whether contacts j and k chatter together: the impacts since the last event of another kind end
// with impacts at j and at k only, the earliest of them within 1e-6 T of now (one cluster).
template <class S>
bool Automaton<S>::ChatteringTogether(int j, int k) const {
  const double now = AbsTime(clock_), window = 1e-6 * R::to_double(period_);
  bool seen_j = false, seen_k = false;
  for (auto it = recent_impacts_.rbegin(); it != recent_impacts_.rend(); ++it) {
    if ((it->first != j && it->first != k) || now - it->second > window) break;
    seen_j = seen_j || it->first == j;
    seen_k = seen_k || it->first == k;
  }
  return seen_j && seen_k;
}

// Two coupled contacts whose chattering sequences interleave toward one accumulation point (MODEL
// §11.6): a run of impacts at j, then at k (each run perhaps ended by its predicted accumulation,
// or lifting the other contact off its stop), then at j again, and so on, every run's first closing
// speed below 0.9 of the last run's at the same contact and no flight longer than 1e-2 T. The runs
// shrink toward one instant where both contacts come to rest at once; no tail of one contact
// describes that. Such an interleaving may still end (one contact drops out and the other's tail
// is predicted: random search scene 328, which the 60-digit reference resolves the same way), so it
// is followed while the run can tell its order: k's gap, closing at speed v, moved by v·Δ since
// contact j's last event (Δ before), and the order of the two is known while v·Δ is well above the
// rounding δ of a gap (the held flows' data are double whatever S: δ = 32 ulps of double of the
// contact's displacement). Once v·Δ < kInterleavedResolution·δ (after kInterleavedRuns runs), k's
// arrival is within the timing uncertainty δ/v of j's: the precisions part there (random search
// scenes 1126, 1312, 1520, 1588, 1626: double and quad took different orders at closing speeds
// 1e-7 … 1e-9, the reference following the runs to 1e-27 and stopping undetermined), and the run
// ends undetermined, not guessed. False when it ended.
template <class S>
bool Automaton<S>::InterleavedChatter(int k) {
  const double v = -R::to_double(M(k).ContactVelocity(V_));
  if (!(v > 0)) return true;  // a tangential arrival is no impact
  const double now = AbsTime(clock_);
  if (!runs_.empty() && now - runs_t_ > 1e-2 * R::to_double(period_)) runs_.clear();
  runs_t_ = now;
  if (!runs_.empty() && runs_.back().contact == k) return true;  // the same run goes on
  // A new run: it extends the interleaving if it is at the other contact of the two (coupled), and
  // slower than that contact's last run; else the interleaving starts again from the last run.
  const auto extends = [&] {
    if (runs_.empty()) return false;
    const int j = runs_.back().contact;
    if (DelassusOffDiagonal(M(j), M(k)) == S(0)) return false;
    if (runs_.size() == 1) return true;
    const ChatterRun& same = runs_[runs_.size() - 2];
    return same.contact == k && v < 0.9 * same.speed;
  };
  if (!extends()) {
    if (runs_.empty() || DelassusOffDiagonal(M(runs_.back().contact), M(k)) == S(0)) {
      runs_.assign(1, ChatterRun{k, v});
      return true;
    }
    runs_.erase(runs_.begin(), runs_.end() - 1);
  }
  runs_.push_back(ChatterRun{k, v});
  if (static_cast<int>(runs_.size()) < kInterleavedRuns) return true;
  const int j = runs_[runs_.size() - 2].contact;
  const ModelT<S>& mk = M(k);
  const double delta = now - last_event_t_[static_cast<size_t>(j)];
  const double rounding = System::kStopUlps * std::numeric_limits<double>::epsilon() *
                          R::to_double(R::abs(mk.x0) + mk.shape.cwiseProduct(X_).cwiseAbs().sum());
  if (!(v * delta < kInterleavedResolution * rounding)) return true;
  const int lo = std::min(j, k), hi = std::max(j, k);
  return Fail(fmt::format("contacts {} ({}) and {} ({}) chatter together toward one accumulation point "
                          "near t = {:.17g}: {} interleaved chattering sequences, each slower than the "
                          "one before at its contact; contact {} arrives at closing speed {:.3g}, {:.3g} "
                          "after contact {}'s last event, within {:.3g} times the timing its gap's rounding "
                          "allows, so their order is below this run's resolution. The accumulation point "
                          "of two contacts chattering at once is not predicted (docs/contacts.md): "
                          "undetermined, not guessed. Move the parameter.",
                          lo, labels_[static_cast<size_t>(lo)], hi, labels_[static_cast<size_t>(hi)], now,
                          runs_.size(), k, v, delta, j, v * delta / rounding),
              RunStatus::kUndetermined);
}

// The same resolution one run earlier: contact j's run is about to end in its predicted accumulation
// point t∞ (state X, Ẋ there, the contacts `held` held after it), and the contact k it interleaves
// with (the run before j's, coupled) is within the rounding of its stop there: with its gap g, gap
// velocity ġ and acceleration g̈ under the held flow, its next arrival (the next run) comes after
// Δ with v·Δ ≈ g + 2 max(ġ, 0)²/|g̈| (closing: the gap itself; opening: the excursion to its apex
// and back) at speed v ≈ (ġ² + 2|g̈|g)^½. When that is below kInterleavedResolution·δ and the run
// would extend the interleaving (slower than k's last run), the next run would meet the rule above,
// and whether k arrives after j's accumulation point or inside its tail is itself below the
// resolution (random search scenes 1312, 1520: double predicted the tail and met k 1.6e-7 and
// 1.8e-8 after it; quad, whose target is smaller, followed one or two more of j's impacts, and on
// 1520 met k inside the tail, as the 60-digit reference does). So the run ends undetermined here,
// before the accumulation, in either precision: the events up to there are those both precisions
// resolve. True (and nothing changes) otherwise.
template <class S>
bool Automaton<S>::AccumulationOrdered(int j, const std::vector<int>& held, const Vec& X, const Vec& V,
                                       const S& phase, double t_inf) {
  if (runs_.size() + 1 < static_cast<size_t>(kInterleavedRuns) || runs_.size() < 2 || runs_.back().contact != j)
    return true;
  const ChatterRun& before = runs_[runs_.size() - 2];
  const int k = before.contact;
  const ModelT<S>& mk = M(k);
  if (k == j || DelassusOffDiagonal(M(j), mk) == S(0)) return true;
  if (std::find(held.begin(), held.end(), k) != held.end()) return true;  // held: it arrives nowhere
  const double gap = R::to_double(mk.ContactDisplacement(X) - mk.x0);
  const double rate = R::to_double(mk.ContactVelocity(V));
  const double accel = R::to_double(mk.shape.dot(ProjectAlong(models_, held, FreeAcceleration(mk, X, V, phase))));
  const double rounding = System::kStopUlps * std::numeric_limits<double>::epsilon() *
                          R::to_double(R::abs(mk.x0) + mk.shape.cwiseProduct(X).cwiseAbs().sum());
  if (!(gap < kInterleavedResolution * rounding)) return true;
  if (rate > 0 && !(accel < 0)) return true;  // opening and not pulled back: it leaves
  const double reach = std::max(gap, 0.0) + (rate > 0 ? 2 * rate * rate / -accel : 0.0);
  const double v = std::sqrt(rate * rate + 2 * std::abs(accel) * std::max(gap, 0.0));
  if (!(reach < kInterleavedResolution * rounding) || !(v < 0.9 * before.speed)) return true;
  const int lo = std::min(j, k), hi = std::max(j, k);
  return Fail(fmt::format("contacts {} ({}) and {} ({}) chatter together toward one accumulation point "
                          "near t = {:.17g}: {} interleaved chattering sequences, each slower than the "
                          "one before at its contact; contact {}'s sequence would accumulate at t = {:.17g}, "
                          "where contact {} is within {:.3g} times its gap's rounding of its stop (gap {:.3g}, "
                          "gap velocity {:.3g}): whether it arrives before or after that accumulation point "
                          "is below this run's resolution. The accumulation point of two contacts "
                          "chattering at once is not predicted (docs/contacts.md): undetermined, not "
                          "guessed. Move the parameter.",
                          lo, labels_[static_cast<size_t>(lo)], hi, labels_[static_cast<size_t>(hi)],
                          AbsTime(clock_), runs_.size(), j, t_inf, k, reach / rounding, gap, rate),
              RunStatus::kUndetermined);
}

template <class S>
bool Automaton<S>::OnContactMulti(int k) {
  if (Compliant(k)) {  // a compliant stop (docs/compliant.md): a contact phase, no impact law
    if (mode_ == Mode::kFree) return EnterContactPhase(k);
    return Fail(fmt::format("contact {} ({}), a compliant stop, closes while the body is held on contact {}: "
                            "a contact phase beside a held contact is not supported",
                            k, labels_[static_cast<size_t>(k)], active_));
  }
  if (!PairChatter(k)) return false;
  if (!InterleavedChatter(k)) return false;
  if (mode_ == Mode::kSticking) {
    // A free contact resting at zero gap beside the held ones (e.g. one that left at zero velocity
    // at this instant) is reached by the impact's impulse: it joins the LCP, or the impulse would
    // drive it through its stop unseen (its start divides that zero out).
    const std::vector<int> was = held_set_.empty() ? std::vector<int>{active_} : held_set_;
    const std::vector<int> resting = RestingBeside(k);
    if (!DecidableBesideHeld(k)) return false;
    if (!resting.empty() || !held_set_.empty()) return ImpactWhileSetHeld(k, was, resting);
    return ImpactWhileHeld(k);
  }
  // Contacts closed at the same instant, within the rounding of their gaps and a window of a few
  // ulps of the period at their closing speed (MODEL §11.2.3): one impact LCP (§11.4). A contact
  // that had its own impact at this instant (within a few ulps of the period in double, the
  // resolution of event times) and is not opening faster than the floor of the model's double data
  // is at zero gap whatever S's rounding of the flight since: it takes its share of the impulse
  // (quad otherwise met a cascade of impacts at one instant that double had merged).
  std::vector<int> Z{k};
  const S window = S(64) * Eps<S>() * period_;
  const double now = AbsTime(clock_), instant = 64 * std::numeric_limits<double>::epsilon() * R::to_double(period_);
  for (int j = 0; j < static_cast<int>(models_.size()); ++j) {
    if (j == k) continue;
    const ModelT<S>& c = M(j);
    const S v = c.ContactVelocity(V_);
    const S tol = S(System::kStopUlps) * Eps<S>() *
                      (R::abs(c.x0) + c.shape.cwiseProduct(X_).cwiseAbs().sum()) +
                  window * R::abs(v);
    const S floor = S(1000 * std::numeric_limits<double>::epsilon()) * c.shape.cwiseProduct(V_).cwiseAbs().sum();
    const bool just_hit = now - last_impact_t_[static_cast<size_t>(j)] <= instant;
    if ((gaps_[static_cast<size_t>(j)] <= tol && v <= S(0)) || (just_hit && v <= floor)) Z.push_back(j);
  }
  if (Z.size() > 1) {
    // Two coupled contacts (W_jk ≠ 0) at zero gap within rounding, one closing (the other closing
    // too, or at rest after its own impact), while they chatter together: which one hits first, or
    // whether the one at rest has left, is below this precision's resolution (at closing speed v a
    // gap's rounding δ is a time δ/|v|), and the impact map is discontinuous there (MODEL §11.4.3):
    // the order decides the motion. The exact motion is a cascade of alternating impacts toward one
    // accumulation point, where the independent reference stops undetermined (random search scenes
    // 111, 615, 646: quad followed the cascade, double took one simultaneous impact). Not guessed.
    for (size_t a = 0; a < Z.size(); ++a)
      for (size_t b = a + 1; b < Z.size(); ++b) {
        const ModelT<S>& ma = M(Z[a]);
        const ModelT<S>& mb = M(Z[b]);
        const auto closing = [&](const ModelT<S>& c) {
          const S floor = S(1000 * std::numeric_limits<double>::epsilon()) * c.shape.cwiseProduct(V_).cwiseAbs().sum();
          return c.ContactVelocity(V_) < -floor;
        };
        if (DelassusOffDiagonal(ma, mb) != S(0) && (closing(ma) || closing(mb)) && ChatteringTogether(Z[a], Z[b])) {
          const int lo = std::min(Z[a], Z[b]), hi = std::max(Z[a], Z[b]);
          return Fail(fmt::format("contacts {} ({}) and {} ({}) chatter together and meet at zero gap "
                                  "within rounding at t = {:.17g} (closing speeds {:.3g} and {:.3g}): "
                                  "they are coupled, so the order of their impacts decides the motion, "
                                  "and this precision cannot tell it. The accumulation point of "
                                  "two contacts chattering at once is not predicted (docs/contacts.md): "
                                  "undetermined, not guessed. Move the parameter.",
                                  lo, labels_[static_cast<size_t>(lo)], hi, labels_[static_cast<size_t>(hi)],
                                  AbsTime(clock_), -R::to_double(M(lo).ContactVelocity(V_)),
                                  -R::to_double(M(hi).ContactVelocity(V_))),
                      RunStatus::kUndetermined);
        }
      }
    return SimultaneousImpact(Z);
  }
  if (k != active_) chatter_first_ = chatter_last_ = 0;  // a sequence is at one contact
  active_ = k;
  for (size_t j = 0; j < starts_.size(); ++j) starts_[j] = FlightStart::kGeneric;
  return OnContact();
}

// Contact k meets its stop while contacts are held, at the instant of a coupled contact j's own
// impact (within double's resolution of event times, 64 ulps of the period), the two chattering
// together: j at rest after its impact (a plastic landing, held since or resting beside the held
// ones) and k arriving within the rounding of that instant. Whether k hit first, at once, or just
// after, is below the resolution of the run, and the impact map is discontinuous there (MODEL
// §11.4.3): merged into one impact LCP (double) or followed as alternating impacts (quad), the two
// precisions part. The exact motion goes on alternating toward one accumulation point, where the
// independent reference stops undetermined (random search scenes 189, 523, 833, 1926, each beside a
// held contact). The rule of the free flight (OnContactMulti), beside held contacts. False when the
// run ended.
template <class S>
bool Automaton<S>::DecidableBesideHeld(int k) {
  const double now = AbsTime(clock_), instant = 64 * std::numeric_limits<double>::epsilon() * R::to_double(period_);
  for (int j = 0; j < static_cast<int>(models_.size()); ++j) {
    if (j == k || now - last_impact_t_[static_cast<size_t>(j)] > instant) continue;
    if (DelassusOffDiagonal(M(j), M(k)) == S(0) || !ChatteringTogether(j, k)) continue;
    const int lo = std::min(j, k), hi = std::max(j, k);
    std::string held;
    for (const int h : held_set_.empty() ? std::vector<int>{active_} : held_set_)
      held += (held.empty() ? "" : ", ") + std::to_string(h);
    return Fail(fmt::format("contacts {} ({}) and {} ({}) chatter together and meet at zero gap "
                            "within rounding at t = {:.17g} while contact(s) {} stick: contact {} "
                            "arrives (gap velocity {:.3g}) at the instant of contact {}'s own impact. "
                            "They are coupled, so the order of their impacts decides the motion, and "
                            "this precision cannot tell it. The accumulation point of two contacts "
                            "chattering at once is not predicted (docs/contacts.md): undetermined, "
                            "not guessed. Move the parameter.",
                            lo, labels_[static_cast<size_t>(lo)], hi, labels_[static_cast<size_t>(hi)],
                            now, held, k, R::to_double(M(k).ContactVelocity(V_)), j),
                RunStatus::kUndetermined);
  }
  return true;
}

// A free contact k closes while contact j = active_ sticks: the impact LCP on {j, k} (MODEL §11.4.2).
template <class S>
bool Automaton<S>::ImpactWhileHeld(int k) {
  const int j = active_;
  const ModelT<S>& mj = M(j);
  const ModelT<S>& mk = M(k);
  X_ -= mk.contact * ((mk.ContactDisplacement(X_) - mk.x0) / mk.s_B);  // snap g_k to 0
  mj.ProjectOntoStop(X_, V_);
  gaps_[static_cast<size_t>(k)] = 0;
  const S phase = Phase(clock_);
  const S v_minus = mk.ContactVelocity(V_);
  // The held flow's constrained modes are double data whatever S: its rounding floor is double's.
  const S floor = S(1000 * std::numeric_limits<double>::epsilon()) * mk.shape.cwiseProduct(V_).cwiseAbs().sum();
  if (v_minus > floor) {
    // Opening faster than the floor, at a gap within rounding: k has just left its stop (lifted off
    // by an impact at j, whose chattering tail was jumped over to this instant) and is still at it.
    // Contacts lifting each other off their stops in turn, each sequence shorter (random search
    // scene 441): two contacts chattering together toward one accumulation point, whose tail is
    // not predicted (MODEL §11.6). Held here, k was cut short where the true motion goes on
    // alternating; which precision cut it where was a matter of rounding. Not decided, not guessed.
    const int lo = std::min(j, k), hi = std::max(j, k);
    return Fail(fmt::format("contacts {} ({}) and {} ({}) chatter together toward one accumulation point "
                            "near t = {:.17g}: contact {} is at its stop within the rounding of its gap, "
                            "leaving it at {:.3g}, where contact {} is held after its impacts, as when two "
                            "contacts lift each other off in turn. The accumulation point of two contacts chattering at once is "
                            "not predicted (docs/contacts.md): undetermined, not guessed. Move the parameter.",
                            lo, labels_[static_cast<size_t>(lo)], hi, labels_[static_cast<size_t>(hi)],
                            AbsTime(clock_), k, R::to_double(v_minus), j),
                RunStatus::kUndetermined);
  }
  if (!(v_minus < -floor)) {
    // Tangential arrival: it leaves only if the held flow pulls it off.
    Emit(EventKind::kGrazing, v_minus, v_minus, k);
    NotifyReset(ResetKind::kGrazing, X_, V_, k);
    if (HeldGapAcceleration(mj, mk, X_, V_, phase) > 0) {
      starts_[static_cast<size_t>(k)] = FlightStart::kDeparture;
      return true;
    }
    NotifyReset(ResetKind::kHeldSet, X_, V_, k, false, HeldSetCause::kGrazing);
    return EnterActiveSet({j, k}, {j});
  }
  const S Wjj(mj.s_B), Wkk(mk.s_B), Wjk = DelassusOffDiagonal(mj, mk);
  const S rk = mk.r;
  // P_j = 0 first: contact k alone, and j's velocity after it.
  S Pk = -(S(1) + rk) * v_minus / Wkk, Pj(0);
  const S vj_after = Wjk * Pk;
  const S tiny = S(64) * Eps<S>() * (R::abs(Wjk * Pk) + S(1e-300));
  Vb_ = V_;
  if (vj_after > tiny) {
    // Contact j is pushed off the stop (liftoff, reported as its release with the speed after).
    V_ += mk.contact * Pk;
    NotifyReset(ResetKind::kImpact, X_, Vb_, k);
    Emit(EventKind::kImpact, v_minus, mk.ContactVelocity(V_), k);
    Emit(EventKind::kRelease, S(0), mj.ContactVelocity(V_), j);
    mode_ = Mode::kFree;
    gaps_[static_cast<size_t>(j)] = 0;
    starts_[static_cast<size_t>(j)] = FlightStart::kAfterImpact;
    if (rk == S(0)) return EnterActiveSet({k}, {});  // k at rest alone: stick or leave
    active_ = k;
    gap_ = 0;
    flight_start_ = FlightStart::kAfterImpact;
    starts_[static_cast<size_t>(k)] = FlightStart::kAfterImpact;
    chatter_first_ = chatter_last_ = 0;
    return true;
  }
  // j stays: both impulses from the 2×2 law (W P = −(1 + R) v⁻ with v_j⁻ = 0).
  const S det = Wjj * Wkk - Wjk * Wjk;
  Pk = -(S(1) + rk) * v_minus * Wjj / det;
  Pj = (S(1) + rk) * v_minus * Wjk / det;
  V_ += mk.contact * Pk + mj.contact * Pj;
  mj.ProjectOntoStop(X_, V_);
  NotifyReset(ResetKind::kImpact, X_, Vb_, k);
  Emit(EventKind::kImpact, v_minus, mk.ContactVelocity(V_), k, false, Pk);
  loads_.AddImpulse(j, Pj);
  if (rk == S(0)) {  // both at rest: the acceleration LCP on {j, k}
    NotifyReset(ResetKind::kHeldSet, X_, V_, k, false, HeldSetCause::kEntry);
    return EnterActiveSet({j, k}, {j});
  }
  // A chattering sequence at k while j sticks: predicted to its accumulation point when it can be.
  starts_[static_cast<size_t>(k)] = FlightStart::kAfterImpact;
  const int chatter = HeldChatter(k, -v_minus, floor);
  if (chatter != 0) return chatter > 0;
  const S Rj = mj.Reaction(X_, V_, phase);
  if (!(Rj > 0)) {  // j leaves at zero velocity: its release
    Emit(EventKind::kRelease, S(0), S(0), j);
    Depart(FlightStart::kDeparture);
    gap_ = 0;
    gaps_[static_cast<size_t>(j)] = 0;
  }
  return true;
}

// Two or more contacts close at one instant (free flight): the impact LCP (I2) of MODEL §11.4,
// W_ZZ P + (I + R) v⁻ = w, 0 ≤ P ⊥ w ≥ 0, solved by enumerating the index sets (W_ZZ is positive
// definite for independent contacts, so exactly one set fits).
template <class S>
bool Automaton<S>::SimultaneousImpact(const std::vector<int>& Z) {
  const auto z = static_cast<Eigen::Index>(Z.size());
  Vec vm(z), q(z), tol(z);
  for (Eigen::Index a = 0; a < z; ++a) {
    const ModelT<S>& ma = M(Z[static_cast<size_t>(a)]);
    X_ -= ma.contact * ((ma.ContactDisplacement(X_) - ma.x0) / ma.s_B);
    vm[a] = ma.ContactVelocity(V_);
    q[a] = (S(1) + ma.r) * vm[a];
    tol[a] = S(64) * Eps<S>() * (R::abs(q[a]) + S(1e-300));
  }
  Vec P;
  if (!SolveLcp<S>(Delassus(models_, Z), q, tol, P))
    return Fail(fmt::format("simultaneous impact of {} contacts at t = {:.17g}: the impact law has no "
                            "solution (dependent contacts)",
                            Z.size(), AbsTime(clock_)));
  Vb_ = V_;
  for (Eigen::Index a = 0; a < z; ++a) V_ += M(Z[static_cast<size_t>(a)]).contact * P[a];
  NotifyReset(ResetKind::kImpact, X_, Vb_, Z.front(), true);
  std::vector<int> resting;
  for (Eigen::Index a = 0; a < z; ++a) {
    const int j = Z[static_cast<size_t>(a)];
    const ModelT<S>& mj = M(j);
    const S vp = mj.ContactVelocity(V_);
    Emit(EventKind::kImpact, vm[a], vp, j, true, P[a]);
    gaps_[static_cast<size_t>(j)] = 0;
    const S floor = S(1000) * Eps<S>() * mj.shape.cwiseProduct(V_).cwiseAbs().sum();
    if (vp > floor) {
      starts_[static_cast<size_t>(j)] = FlightStart::kAfterImpact;
      active_ = j;
    } else {
      resting.push_back(j);
    }
  }
  chatter_first_ = chatter_last_ = 0;
  mode_ = Mode::kFree;
  if (resting.size() > 1) {
    NotifyReset(ResetKind::kHeldSet, X_, V_, -1, false, HeldSetCause::kSimultaneous);
    return EnterActiveSet(resting, {});
  }
  if (resting.size() == 1) {
    // One contact at rest (r = 0): stick or leave as the single stop (docs/model.md §4.4).
    const int j = resting.front();
    active_ = j;
    const ModelT<S>& mj = M(j);
    const S phase = Phase(clock_);
    const S Rc = mj.Reaction(X_, V_, phase);
    if (Rc > 0 || (Rc == 0 && mj.ReactionRate(X_, V_, phase) > 0)) {
      EnterSticking(Rc > 0 ? StickStart::kGeneric : StickStart::kRising);
      for (size_t i = 0; i < starts_.size(); ++i)
        if (static_cast<int>(i) != j && starts_[i] != FlightStart::kAfterImpact) starts_[i] = FlightStart::kGeneric;
      Emit(EventKind::kStick, S(0), S(0), j);
      return true;
    }
    mj.ProjectOntoStop(X_, V_);
    Depart(Rc < 0 ? FlightStart::kDeparture : FlightStart::kAfterRelease);
  }
  gap_ = 0;
  flight_start_ = starts_[static_cast<size_t>(active_)];
  return true;
}

// The closed-form flow held on `set` (made once per set met), or null with the reason.
template <class S>
SetStickingT<S>* Automaton<S>::SetEngineFor(const std::vector<int>& set, std::string& why) {
  for (auto& e : set_engines_)
    if (e->set() == set) return e.get();
  if (cvode_) {
    why = "the CVODE engine does not hold several contacts at once; use run.engine = \"exact\"";
    return nullptr;
  }
  if (!m_.harmonics.empty()) {
    why = "sticking on several contacts at once under a sum of harmonics has no closed form in vibro yet "
          "(docs/harmonics.md)";
    return nullptr;
  }
  try {
    auto e = std::make_unique<SetStickingT<S>>(sys_, models_, set);
    if (!e->ok()) {
      why = "the damped flow held on them is defective (a critically damped held mode): no closed "
            "form; change structure.damping_ratios slightly";
      return nullptr;
    }
    set_engines_.push_back(std::move(e));
  } catch (const std::invalid_argument& e) {
    why = e.what();
    return nullptr;
  }
  return set_engines_.back().get();
}

template <class S>
SetStickingT<S>* Automaton<S>::SetEngine() {
  std::string why;
  if (SetStickingT<S>* e = SetEngineFor(held_set_, why)) return e;
  std::string who;
  for (const int j : held_set_) who += (who.empty() ? "" : ", ") + std::to_string(j);
  Fail(fmt::format("contacts {} stick together at t = {:.17g}: {} (docs/contacts.md)", who,
                   AbsTime(clock_), why),
       RunStatus::kUndetermined);
  return nullptr;
}

template <class S>
void Automaton<S>::ProjectOntoSet(const std::vector<int>& Z) {
  ProjectOnto<S>(models_, Z, X_, V_);
}

// Contacts Z0 at zero gap and zero gap velocity (a plastic landing, a tangential arrival, impacts
// that leave several contacts at rest, the start of a run): after the projection onto them, the
// acceleration LCP (S3) a = a⁰ + W λ, 0 ≤ λ ⊥ a ≥ 0 decides which stick (λ > 0) and which leave at
// zero velocity (a > 0, start g = g' = 0, g'' > 0). `was_held`: the contacts held before, whose
// leaving is a release. λ = a = 0 at once is the degenerate entry: undetermined, never guessed.
template <class S>
bool Automaton<S>::EnterActiveSet(std::vector<int> Z0, const std::vector<int>& was_held,
                                  bool emit_sticks) {
  using Mat = typename ModelT<S>::Mat;
  std::sort(Z0.begin(), Z0.end());
  const auto before = [&](int j) { return std::find(was_held.begin(), was_held.end(), j) != was_held.end(); };
  chatter_first_ = chatter_last_ = 0;
  held_chatter_ = 0;
  std::vector<int> stick;
  if (!Z0.empty()) {
    ProjectOntoSet(Z0);
    const auto z = static_cast<Eigen::Index>(Z0.size());
    const S phase = Phase(clock_);
    const Mat W = Delassus(models_, Z0);
    Vec a0(z);
    S scale(0);
    for (Eigen::Index a = 0; a < z; ++a) {
      const ModelT<S>& ma = M(Z0[static_cast<size_t>(a)]);
      const Vec acc = FreeAcceleration(ma, X_, V_, phase);
      a0[a] = ma.shape.dot(acc);
      scale += ma.shape.cwiseProduct(acc).cwiseAbs().sum();
    }
    // The held flow's data are double whatever S: decisions within double rounding of the forces.
    const S tol = S(1e3 * std::numeric_limits<double>::epsilon()) * (scale + S(1e-300));
    Vec lam;
    if (!SolveLcp<S>(W, a0, Vec::Constant(z, tol), lam))
      return Fail(fmt::format("{} contacts at rest at t = {:.17g}: the contact-force LCP has no "
                              "solution (dependent contacts)", Z0.size(), AbsTime(clock_)));
    const Vec acc = W * lam + a0;
    for (Eigen::Index a = 0; a < z; ++a) {
      const int j = Z0[static_cast<size_t>(a)];
      if (lam[a] <= tol && acc[a] <= tol)
        return Fail(fmt::format("contact {} at rest at t = {:.17g} with zero force and zero "
                                "acceleration (a degenerate entry into sticking, docs/contacts.md): "
                                "undetermined at this order. Move the parameter.",
                                j, AbsTime(clock_)),
                    RunStatus::kUndetermined);
      gaps_[static_cast<size_t>(j)] = 0;
      if (lam[a] > tol) {
        stick.push_back(j);
      } else {
        starts_[static_cast<size_t>(j)] = FlightStart::kDeparture;
        if (before(j)) Emit(EventKind::kRelease, S(0), S(0), j);
      }
    }
  }
  // Every gap from the state, but those at an exact zero with a start kind (a contact that bounced
  // or lifted off at this instant) stay 0: their next search divides that zero out, and a gap
  // rounded to ±1e-17 from the state would instead be searched from scratch (a false touch).
  const auto refresh_gaps = [&] {
    for (size_t j = 0; j < models_.size(); ++j) {
      if (gaps_[j] == S(0) && starts_[j] != FlightStart::kGeneric) continue;
      gaps_[j] = std::find(stick.begin(), stick.end(), static_cast<int>(j)) != stick.end()
                     ? S(0) : models_[j]->ContactDisplacement(X_) - models_[j]->x0;
    }
    for (const int j : Z0) gaps_[static_cast<size_t>(j)] = 0;
  };
  if (stick.empty()) {  // every contact leaves: a free flight
    held_set_.clear();
    mode_ = Mode::kFree;
    refresh_gaps();
    // The flight's start contact: one that just bounced or lifted off, else one that leaves.
    int start = Z0.empty() ? active_ : Z0.front();
    for (size_t j = 0; j < starts_.size(); ++j)
      if (starts_[j] == FlightStart::kAfterImpact && gaps_[j] == S(0)) start = static_cast<int>(j);
    active_ = start;
    flight_start_ = starts_[static_cast<size_t>(active_)];
    gap_ = gaps_[static_cast<size_t>(active_)];
    return true;
  }
  if (stick.size() == 1) {
    held_set_.clear();
    active_ = stick.front();
    EnterSticking(StickStart::kGeneric);
    refresh_gaps();
  } else {
    held_set_ = stick;
    active_ = stick.front();
    if (!SetEngine()) return false;
    mode_ = Mode::kSticking;
    stick_start_ = StickStart::kGeneric;
    gap_ = 0;
    refresh_gaps();
  }
  if (emit_sticks)
    for (const int j : stick)
      if (!before(j)) Emit(EventKind::kStick, S(0), S(0), j);
  return true;
}

// After an impact at contact k that bounced while the held contacts stay held: a run of impacts of
// decreasing speed with flights far shorter than the period is a chattering sequence toward rest
// beside them. Its accumulation point is predicted when the tail allows it (TryHeldAccumulation);
// a sequence that reaches the rounding floor (or kHeldChatterImpacts impacts) first is undetermined,
// never guessed. Returns 1 when the jump was taken, −1 when the run ends, 0 to follow the flight.
template <class S>
int Automaton<S>::HeldChatter(int k, const S& speed, const S& floor) {
  const double now = AbsTime(clock_);
  const bool short_flight = k == held_chatter_contact_ && now - held_chatter_t_ < 1e-2 * R::to_double(period_);
  const bool converging = short_flight && chatter_last_ > 0 && speed < chatter_last_;
  held_chatter_ = short_flight ? held_chatter_ + 1 : 0;
  held_chatter_contact_ = k;
  held_chatter_t_ = now;
  chatter_last_ = speed;
  if (converging && run_.chatter != ChatterTreatment::kNone) {
    const int jumped = TryHeldAccumulation(k);
    if (jumped != 0) return jumped;
  }
  const S r = M(k).r;
  if ((converging && r * speed <= floor) || held_chatter_ >= kHeldChatterImpacts) {
    std::string held;
    for (const int j : held_set_.empty() ? std::vector<int>{active_} : held_set_)
      held += (held.empty() ? "" : ", ") + std::to_string(j);
    Fail(fmt::format("contact {} chatters {} at t = {:.17g} while contact(s) {} stick, and its "
                     "accumulation point could not be predicted within run.chatter_tolerance = "
                     "{:.3g} T before its impact speeds reached {:.3g} (docs/contacts.md). {}",
                     k, converging && r * speed <= floor ? "to rest" : "toward rest", AbsTime(clock_),
                     held, R::to_double(chatter_tol_ / period_), R::to_double(r * speed),
                     UndeterminedHint()),
         RunStatus::kUndetermined);
    return -1;
  }
  return 0;
}

// MODEL §11.6 (docs/contacts.md): contact k chatters while the set S (held_set_, or the one held
// contact) sticks. On the tail's mean path, the state projected onto Z = S ∪ {k}, the contact
// forces of Z must all be positive and k's gap decelerates under the S-flow at A = −c_kᵀΠ_S a > 0
// (a the free acceleration, Π_S = I − T_S W_SS⁻¹ C_S); then Δ0 = 2u/((1 − r)A), ε = −ȦΔ0/A
// (Ȧ along the Z-flow) and Δ∞ = Δ0(1 + ε/3). The prediction is taken only when the whole tail,
// Δ0, is within run.chatter_tolerance (so is any error of Δ∞ inside it), |ε| ≤ 0.1, and no other
// contact's gap closes and no held force vanishes over Δ∞ (certified search, k left out).
template <class S>
int Automaton<S>::TryHeldAccumulation(int k) {
  const ModelT<S>& mk = M(k);
  const S u = mk.ContactVelocity(V_), r = mk.r;
  if (!(u > 0) || !(r > 0) || !(r < 1)) return 0;
  const std::vector<int> held = held_set_.empty() ? std::vector<int>{active_} : held_set_;
  std::vector<int> Z = held;
  Z.push_back(k);
  std::sort(Z.begin(), Z.end());
  const auto delassus = [&](const std::vector<int>& set) { return Delassus(models_, set); };
  const auto project = [&](const std::vector<int>& set, const Vec& v) { return ProjectAlong(models_, set, v); };
  const Vec X0 = X_, V0 = V_;
  ProjectOntoSet(Z);
  const Vec Xs = X_, Vs = V_;
  X_ = X0;
  V_ = V0;
  const S phase = Phase(clock_);
  const Vec a_free = FreeAcceleration(mk, Xs, Vs, phase);
  // Contact forces of Z on the mean path (all at rest there): W_ZZ λ = −C_Z a_free.
  {
    const auto z = static_cast<Eigen::Index>(Z.size());
    Vec a0(z);
    for (Eigen::Index a = 0; a < z; ++a) a0[a] = -M(Z[static_cast<size_t>(a)]).shape.dot(a_free);
    const Vec lam = delassus(Z).fullPivLu().solve(a0);
    for (Eigen::Index a = 0; a < z; ++a)
      if (!(lam[a] > 0)) return 0;
  }
  // A = uᵀX − κ f sin along the Z-flow (undamped), u = Ω Π_Sᵀc_k, κ = c_kᵀΠ_S T_A / f, with
  // Π_Sᵀc_k = c_k − C_Sᵀ W_SS⁻¹ W_Sk.
  Vec pc = mk.shape;
  {
    const auto h = static_cast<Eigen::Index>(held.size());
    Vec wsk(h);
    for (Eigen::Index a = 0; a < h; ++a) wsk[a] = DelassusOffDiagonal(M(held[static_cast<size_t>(a)]), mk);
    const Vec x = delassus(held).fullPivLu().solve(wsk);
    for (Eigen::Index a = 0; a < h; ++a) pc -= M(held[static_cast<size_t>(a)]).shape * x[a];
  }
  const S A = -mk.shape.dot(project(held, a_free));
  if (!(A > 0)) return 0;
  const Vec acc_Z = project(Z, a_free);
  const Vec jerk_free = -mk.omega.cwiseAbs2().cwiseProduct(Vs) -
                        S(2) * mk.zeta.cwiseProduct(mk.omega).cwiseProduct(acc_Z) +
                        (mk.harmonics.empty() ? Vec(mk.forcing * (mk.f * mk.w * R::cos(phase)))
                                              : Vec(mk.harmonics.Vector(phase, 1)));
  const S A_rate = -mk.shape.dot(project(held, jerk_free));
  const S delta0 = S(2) * u / ((S(1) - r) * A);
  const S eps = -A_rate * delta0 / A;
  if (!(R::abs(eps) <= S(kTailEpsilonMax))) return 0;
  // The estimated error of Δ∞, as for one contact (dynamics/chatter_tail.hpp): the residual of the
  // linear-A correction, what a quadratic and cubic change of A over [0, 2Δ0] can do (Ä, and a
  // bound of |A'''| from the modes of the flow held on Z), and k's own stiffness with S held acting
  // on the O(u²) gap of the tail, and the damping k's velocity feels (3 times its first-order
  // effect, as for one contact). Without the Z-flow (a defective damped one), the whole tail, Δ0.
  S error = delta0;
  std::string why;
  if (SetStickingT<S>* zf = SetEngineFor(Z, why)) {
    const Vec u_vec = mk.omega.cwiseAbs2().cwiseProduct(pc);
    const Vec D = S(2) * mk.zeta.cwiseProduct(mk.omega);
    const Vec u_v = D.cwiseProduct(pc);
    const S kappa = pc.dot(mk.forcing);
    zf->Begin({Mode::kSticking, phase, clock_.offset, Xs, Vs, S(0), FlightStart::kGeneric,
               StickStart::kGeneric, Z.front(), nullptr, nullptr, -1});
    const ProbeT<S> pa = zf->Functional(u_vec, u_v, kappa, S(0), S(2) * delta0);
    const Vec tk = project(held, mk.contact);  // the velocity change of a unit impulse at k, S held
    const S s_kS = mk.shape.dot(tk);
    const S wc2 = s_kS > 0 ? S(R::abs(u_vec.dot(tk)) / s_kS) : S(0);
    // β: the damping k's own gap velocity feels with S held (g'' = −A − β g' over a flight).
    const S beta = s_kS > 0 ? S(R::abs(u_v.dot(tk)) / s_kS) : S(0);
    const S d = delta0;
    error = d * (S(0.3) * eps * eps + R::abs(pa.jet.g2) * d * d / (S(2) * A) +
                 pa.M * d * d * d / (S(6) * A) + wc2 * d * d / 4 + beta * d / 2);
  }
  if (!(error <= chatter_tol_)) return 0;
  const S delta = delta0 * (S(1) + eps / 3);
  if (RecentOtherImpact(k, delta)) return 0;
  // The held flow over the tail, k left out: nothing else may happen in it.
  PropagatorT<S>* p = held_set_.empty() ? engine_.get() : static_cast<PropagatorT<S>*>(SetEngine());
  if (!p) return -1;
  const SegmentStartT<S> start{Mode::kSticking, phase, clock_.offset, X_, V_, S(0), flight_start_,
                               StickStart::kGeneric, active_, &gaps_, &starts_, k};
  p->Begin(start);
  const auto probe = p->Advance(delta, true, {});
  if (probe.end == SegmentEnd::kFailure) return 0;  // a stop request is seen by the next segment
  if (probe.end != SegmentEnd::kLimit) return 0;
  {
    Vec Xe, Ve;
    p->Evaluate(delta, Xe, Ve);
    ProjectOnto<S>(models_, Z, Xe, Ve);
    ClockT<S> e = clock_;
    AdvanceClock(e, delta, period_ - clock_.offset);
    if (!AccumulationOrdered(k, Z, Xe, Ve, Phase(e), AbsTime(e))) return -1;
  }
  p->Begin(start);
  const ClockT<S> from = clock_;
  p->Advance(delta, false, [&](const S& lo, const S& hi) { EmitStretch(from, *p, lo, hi); });
  const Vec X_k = X_, V_k = V_;  // the post-impact state the tail starts from
  p->Evaluate(delta, X_, V_);
  const Vec X_end = X_, V_end = V_;
  AdvanceClock(clock_, delta, period_ - clock_.offset);
  ProjectOntoSet(Z);
  ++result_.chatter.accumulations_predicted;
  const double err = R::to_double(error / period_);
  if (err > result_.chatter.max_estimated_error) result_.chatter.max_estimated_error = err;
  if (resets_wanted_) {
    // The jump for the tangent map (docs/contacts.md, "Periodic orbits"): from the post-impact
    // state over Δ∞ on the S-flow, then the projection onto Z; ∇Δ∞ of the prediction taken.
    Eigen::VectorXd a, b, c, d, xe, ve;
    const Eigen::VectorXd grad = HeldTailGradient<S>(models_, k, held, Z, X_k, V_k, phase);
    const Reset jump{ResetKind::kHeldSet, R::to_double(phase), D(X_k, a), D(V_k, b), D(X_, c), D(V_, d),
                     R::to_double(delta), 0.0, &grad, &D(X_end, xe), &D(V_end, ve),
                     R::to_double(mk.ContactVelocity(V_k)), k, false, HeldSetCause::kAccumulation};
    for (auto* o : opt_.observers) o->OnReset(jump);
  }
  Emit(EventKind::kAccumulation, S(0), S(0), k);
  return EnterActiveSet(Z, held) ? 1 : -1;
}

// A free contact k closes while the set S = held_set_ sticks: the impact LCP (I2) on S ∪ {k}
// with v_S⁻ = 0 (MODEL §11.4.2). Held contacts the impulse pushes off lift off (a release with
// their speed after); those left at rest, and k if it lands plastically or arrives tangentially,
// go to the acceleration LCP (S3).
template <class S>
std::vector<int> Automaton<S>::RestingBeside(int k) const {
  std::vector<int> out;
  for (int j = 0; j < static_cast<int>(models_.size()); ++j) {
    if (j == k || j == active_ || Held(j)) continue;
    const ModelT<S>& c = M(j);
    const S scale = R::abs(c.x0) + c.shape.cwiseProduct(X_).cwiseAbs().sum();
    const S floor = S(1000 * std::numeric_limits<double>::epsilon()) * c.shape.cwiseProduct(V_).cwiseAbs().sum();
    if (gaps_[static_cast<size_t>(j)] <= S(System::kStopUlps) * Eps<S>() * scale && c.ContactVelocity(V_) <= floor)
      out.push_back(j);
  }
  return out;
}

template <class S>
bool Automaton<S>::ImpactWhileSetHeld(int k, const std::vector<int>& was, const std::vector<int>& resting) {
  const ModelT<S>& mk = M(k);
  X_ -= mk.contact * ((mk.ContactDisplacement(X_) - mk.x0) / mk.s_B);
  std::vector<int> Z = was;
  std::vector<int> still = was;  // the held and resting contacts at g = ġ = 0
  for (const int j : resting) {
    // A contact at zero gap closing faster than the floor is not at rest: it hits at this instant
    // (a simultaneous impact beside the held ones) and takes the impact law with its own
    // restitution below; only its gap is snapped. Projecting its velocity away would stop it with
    // no impact (its event, impulse and bounce lost).
    const ModelT<S>& mj = M(j);
    const S floor_j = S(1000 * std::numeric_limits<double>::epsilon()) * mj.shape.cwiseProduct(V_).cwiseAbs().sum();
    if (mj.ContactVelocity(V_) < -floor_j)
      X_ -= mj.contact * ((mj.ContactDisplacement(X_) - mj.x0) / mj.s_B);
    else
      still.push_back(j);
  }
  Z.insert(Z.end(), resting.begin(), resting.end());
  ProjectOnto<S>(models_, still, X_, V_);
  gaps_[static_cast<size_t>(k)] = 0;
  for (const int j : resting) gaps_[static_cast<size_t>(j)] = 0;
  const S v_minus = mk.ContactVelocity(V_);
  const S floor = S(1000 * std::numeric_limits<double>::epsilon()) * mk.shape.cwiseProduct(V_).cwiseAbs().sum();
  Z.push_back(k);
  if (!(v_minus < -floor)) {
    Emit(EventKind::kGrazing, v_minus, v_minus, k);
    NotifyReset(ResetKind::kHeldSet, X_, V_, k, false, HeldSetCause::kGrazing);
    return EnterActiveSet(Z, was);
  }
  const auto z = static_cast<Eigen::Index>(Z.size());
  Vec q(z);
  for (Eigen::Index a = 0; a < z; ++a) {
    const ModelT<S>& ma = M(Z[static_cast<size_t>(a)]);
    q[a] = (S(1) + ma.r) * ma.ContactVelocity(V_);
  }
  Vec P;
  if (!SolveLcp<S>(Delassus(models_, Z), q, Vec::Constant(z, S(64) * Eps<S>() * (R::abs(q[z - 1]) + S(1e-300))), P)) {
    std::string who;
    for (size_t a = 0; a + 1 < Z.size(); ++a) who += (who.empty() ? "" : ", ") + std::to_string(Z[a]);
    return Fail(fmt::format("contact {} ({}) hits at t = {:.17g} while contacts {} are at rest: the impact "
                            "law has no solution (dependent contacts)",
                            k, labels_[static_cast<size_t>(k)], AbsTime(clock_), who));
  }
  Vb_ = V_;
  for (Eigen::Index a = 0; a < z; ++a) V_ += M(Z[static_cast<size_t>(a)]).contact * P[a];
  for (size_t a = 0; a < was.size(); ++a) loads_.AddImpulse(was[a], P[static_cast<Eigen::Index>(a)]);  // held ones
  NotifyReset(ResetKind::kHeldSet, X_, Vb_, k, false, HeldSetCause::kImpact);
  const S vk = mk.ContactVelocity(V_);
  Emit(EventKind::kImpact, v_minus, vk, k);
  std::vector<int> rest, stay;
  for (size_t a = 0; a < resting.size(); ++a) {
    // A resting free contact: pushed against its stop (an impact of zero speed, P > 0) or off it.
    const int j = resting[a];
    const S vj = M(j).ContactVelocity(V_);
    const S Pj = P[static_cast<Eigen::Index>(was.size() + a)];
    if (Pj > S(0)) Emit(EventKind::kImpact, M(j).ContactVelocity(Vb_), vj, j, true, Pj);
    if (vj > floor) {
      starts_[static_cast<size_t>(j)] = FlightStart::kAfterImpact;
    } else {
      rest.push_back(j);
    }
  }
  for (const int j : was) {
    const S vj = M(j).ContactVelocity(V_);
    if (vj > floor) {  // pushed off its stop
      Emit(EventKind::kRelease, S(0), vj, j);
      starts_[static_cast<size_t>(j)] = FlightStart::kAfterImpact;
      gaps_[static_cast<size_t>(j)] = 0;
    } else {
      rest.push_back(j);
      stay.push_back(j);
    }
  }
  if (vk > floor) {
    starts_[static_cast<size_t>(k)] = FlightStart::kAfterImpact;
  } else {
    rest.push_back(k);
    // k bounced (r > 0) at a speed within the rounding floor of the held flow's (double) data: a
    // chattering sequence followed to that floor, whose remaining tail (each flight 2 r v/((1 − r)
    // |a|) at speed v, MODEL §11.6) is below the resolution. Its accumulation point is here: the
    // event says so, as a predicted one does (quad's 1e-28 T target stops the prediction first).
    if (mk.r > S(0) && vk > S(0)) Emit(EventKind::kAccumulation, S(0), S(0), k);
  }
  const int followed = held_chatter_, contact = held_chatter_contact_;
  const double t = held_chatter_t_;
  const S last = chatter_last_;
  if (!EnterActiveSet(rest, stay)) return false;
  const bool same_hold = held_set_.empty() ? was.size() == 1 && active_ == was.front() : held_set_ == was;
  if (vk > floor && mode_ == Mode::kSticking && same_hold) {
    // The set holds and k bounced: a chattering sequence beside it, its bookkeeping kept.
    held_chatter_ = followed;
    held_chatter_contact_ = contact;
    held_chatter_t_ = t;
    chatter_last_ = last;
    const int chatter = HeldChatter(k, -v_minus, floor);
    if (chatter != 0) return chatter > 0;
  }
  return true;
}

// A held set's force λ_c reached 0 at the end of a segment of length sigma: a release candidate.
template <class S>
void Automaton<S>::ReleaseFromSet(const SetStickingT<S>& set, int c, const S& sigma) {
  // A release when λ_c crosses 0 downwards (MODEL (S4) in docs/contacts_reference.md): c leaves
  // with g = g' = g'' = 0, g''' > 0 under the flow of the others, which stay held.
  const JetT<S> jf = set.Force(c, sigma);
  if (jf.g1 < 0 || (jf.g1 == S(0) && jf.g2 < 0)) {
    ProjectOntoSet(held_set_);
    NotifyReset(ResetKind::kHeldSet, X_, V_, c, false, HeldSetCause::kRelease);
    Emit(EventKind::kRelease, S(0), S(0), c);
    held_set_.erase(std::find(held_set_.begin(), held_set_.end(), c));
    starts_[static_cast<size_t>(c)] = FlightStart::kAfterRelease;
    gaps_[static_cast<size_t>(c)] = 0;
    active_ = held_set_.front();
    if (held_set_.size() == 1) held_set_.clear();
    stick_start_ = StickStart::kGeneric;
  } else {
    stick_start_ = StickStart::kTangent;  // the force touches 0 without crossing: stay
  }
}

}  // namespace vibro::detail
