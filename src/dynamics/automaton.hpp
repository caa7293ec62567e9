// The hybrid automaton (pseudocode in include/vibro/simulator.hpp), templated on the scalar S of
// the exact engine: double (the default, with either engine) or quad (run.precision = "quad",
// the reference engine). Observers always see doubles.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>

#include <fmt/format.h>

#include "dynamics/chatter_tail.hpp"
#include "dynamics/contact_loads.hpp"
#include "dynamics/model_t.hpp"
#include "dynamics/propagator.hpp"
#include "dynamics/set_sticking.hpp"
#include "vibro/simulator.hpp"
#include "vibro/stop_request.hpp"

namespace vibro::detail {

// One DOF (no constrained mode): the stuck body rests at x0 and R depends on the phase only, so
// the release phase is closed form (docs/model.md §4.4, §6.1) and no sticking flow is integrated.
// Contact j's force λ_j under the held set's closed form, as a source of the max R search
// (ReactionMaxT::Max, docs/loads.md): its jet and the bound of its third derivative (no Taylor step).
template <class S>
struct SetForce {
  const SetStickingT<S>* set;
  int contact;
  bool HeldReactionJet(const S& s, S& R, S& rate, S& accel) const {
    const JetT<S> j = set->Force(contact, s);
    R = j.g;
    rate = j.g1;
    accel = j.g2;
    return true;
  }
  bool HeldReactionTaylor(const S&, S*) const { return false; }
  bool HeldReactionBound(const S& H, S& M, S* m5) const {
    M = set->ForceBound(contact, H);
    if (m5) *m5 = S(0);
    return true;
  }
};

template <class S>
class RestingStick final : public PropagatorT<S> {
 public:
  using Vec = typename ModelT<S>::Vec;
  explicit RestingStick(const ModelT<S>& m) : m_(m) {}
  void Begin(const SegmentStartT<S>& s) override {
    phase_ = s.phase;
    offset_ = s.offset;
    X_ = m_.x0 * m_.static_shape;
    V_ = Vec::Zero(m_.dof());
  }
  // R = R_st − κ sin(φ + ωσ) with R_st = cᵀΩX/s_B at rest and κ = s_A f/s_B (eq. (5)): its
  // derivatives and their bounds |κ|ω³, |κ|ω⁵ in closed form (the max R search, docs/loads.md §3).
  bool HeldReaction(const S& sigma, S& R, S& rate) const override {
    S d[5];
    HeldReactionTaylor(sigma, d);
    R = d[0];
    rate = d[1];
    return true;
  }
  bool HeldReactionJet(const S& sigma, S& R, S& rate, S& accel) const override {
    S d[5];
    HeldReactionTaylor(sigma, d);
    R = d[0];
    rate = d[1];
    accel = d[2];
    return true;
  }
  bool HeldReactionBound(const S&, S& M, S* m5) const override {
    const S k = Real<S>::abs(Kappa()), w3 = m_.w * m_.w * m_.w;
    const S margin = S(1) + S(1e-9);  // the rounding of the products (as the engines' BoundMargin)
    M = k * w3 * margin;
    if (m5) *m5 = k * w3 * m_.w * m_.w * margin;
    return true;
  }
  bool HeldReactionTaylor(const S& sigma, S* d) const override {
    S sn(0), cs(0);
    Real<S>::sincos(phase_ + m_.w * sigma, sn, cs);
    const S k = Kappa(), w = m_.w, w2 = w * w;
    S elastic(0);
    for (Eigen::Index i = 0; i < X_.size(); ++i) elastic += m_.shape[i] * m_.omega[i] * m_.omega[i] * X_[i];
    d[0] = elastic / m_.s_B - k * sn;
    d[1] = -k * w * cs;
    d[2] = k * w2 * sn;
    d[3] = k * w2 * w * cs;
    d[4] = -k * w2 * w2 * sn;
    return true;
  }
  SegmentResultT<S> Advance(S sigma_max, bool detect, const StretchCallbackT<S>& cb) override {
    const S target = detect ? ReleaseOffset() : S(std::numeric_limits<double>::infinity());
    const bool released = target - offset_ <= sigma_max;
    const S end = released ? S(target - offset_) : sigma_max;
    if (cb) cb(S(0), end);
    if (!released) return {SegmentEnd::kLimit, end, {}};
    return {SegmentEnd::kRelease, end, {}, target};
  }
  void Evaluate(S, Vec& X, Vec& V) const override {
    X = X_;
    V = V_;
  }
  S Gap(S) const override { return S(0); }

 private:
  // R ∝ ω_1² x0 − F sin φ with F = s_A f: release where F sin φ rises through ω_1² x0, i.e.
  // sin φ_1 = β = ω_1² x0 / F with F cos φ_1 > 0. Never when |β| ≥ 1 (permanent sticking).
  // Returned as the clock offset of the next release (possibly ≥ T, then beyond this period).
  S ReleaseOffset() const {
    using R = Real<S>;
    const S F = m_.s_A * m_.f;
    const S k = m_.omega[0] * m_.omega[0] * m_.x0;
    if (F == S(0) || R::abs(k) >= R::abs(F)) return S(std::numeric_limits<double>::infinity());
    const S beta = k / F;
    const S phi1 = R::atan2(beta, R::copysign(R::sqrt(S(1) - beta * beta), F));
    // Offsets o with phase0 + ω o ≡ φ_1 (mod 2π): o_m = (φ_1 − phase0 + 2πm)/ω, the first > now.
    const S w = m_.w, two_pi = S(2) * R::pi();
    const S base = phi1 - (phase_ - w * offset_);
    S mm = R::floor((w * offset_ - base) / two_pi);
    S o = (base + two_pi * mm) / w;
    for (int guard = 0; o <= offset_ && guard < 8; ++guard) {
      mm += 1;
      o = (base + two_pi * mm) / w;
    }
    return o;
  }

  S Kappa() const { return m_.s_A * m_.f / m_.s_B; }

  const ModelT<S>& m_;
  S phase_{0}, offset_{0};
  Vec X_, V_;
};

// Time within the run in the engine's scalar: whole periods plus the offset in [0, T).
template <class S>
struct ClockT {
  long long period = 0;
  S offset{0};
};

template <class S>
class Automaton {
 public:
  using Vec = typename ModelT<S>::Vec;
  using R = Real<S>;

  Automaton(const System& sys, const ModelT<S>& model, const Scene& scene,
            const SimulationOptions& opt, std::unique_ptr<PropagatorT<S>> engine)
      : sys_(sys),
        m_(model),
        run_(scene.run),
        opt_(opt),
        engine_(std::move(engine)),
        period_(model.period),
        t0_(scene.initial_time),
        cvode_(scene.run.engine == Engine::kCvode),
        // CVODE resolves impact velocities only to about √rtol of the sequence's first one.
        switch_ratio_(cvode_ ? std::max(scene.run.chatter_switch, std::sqrt(scene.run.rtol))
                             : scene.run.chatter_switch),
        resolution_ratio_(cvode_ ? std::sqrt(scene.run.rtol) : 0.0),
        // The accuracy target of a predicted accumulation point, in time units (docs/model.md §5.4).
        // CVODE's impacts carry errors of about rtol: no prediction need be closer than that.
        chatter_tol_(S(cvode_ ? std::max(ChatterTolerance(scene.run), scene.run.rtol)
                              : ChatterTolerance(scene.run)) *
                     model.period) {
    for (int j = 1; j < sys.contact_count(); ++j) others_.emplace_back(sys, j);
    models_.push_back(&model);
    for (const ModelT<S>& o : others_) models_.push_back(&o);
    if (model.stick_frequencies.size() == 0)
      for (const ModelT<S>* k : models_) resting_all_.push_back(std::make_unique<RestingStick<S>>(*k));
    counts_.resize(models_.size());
    loads_.Resize(models_.size());
    if (multi()) {
      gaps_.assign(models_.size(), S(0));
      starts_.assign(models_.size(), FlightStart::kGeneric);
    }
    const auto poll = [this] { return StopPolled(); };
    engine_->SetStopPoll(poll);
    if (opt.initial) {
      t0_ = opt.initial->time;
      X_ = opt.initial->X.cast<S>();
      V_ = opt.initial->V.cast<S>();
    } else {
      const auto init = sys.Initial(scene);
      X_ = init.X.cast<S>();
      V_ = init.V.cast<S>();
    }
    phase0_ = R::fmod(S(m_.w) * S(t0_), S(2) * R::pi());
  }

  RunResult Run();

 private:
  bool multi() const { return models_.size() > 1; }
  const ModelT<S>& M(int j) const { return *models_[static_cast<size_t>(j)]; }
  // The one-DOF resting flow of the held contact (no constrained mode), or null.
  PropagatorT<S>* Resting() const {
    return resting_all_.empty() ? nullptr : resting_all_[static_cast<size_t>(active_)].get();
  }
  // Several contacts: every gap from the propagator after a segment (the start contact's without
  // cancellation), and what follows an event at contact k.
  void UpdateGaps(PropagatorT<S>& p, const S& sigma);
  bool OnContactMulti(int k);
  bool ImpactWhileHeld(int k);
  // Sticking on two or more contacts at once (docs/contacts.md): the held set's propagator, a
  // contact closing while the set is held, and the acceleration LCP that decides which contacts
  // at zero gap and zero gap velocity stick.
  bool Held(int j) const { return std::find(held_set_.begin(), held_set_.end(), j) != held_set_.end(); }
  SetStickingT<S>* SetEngine();
  SetStickingT<S>* SetEngineFor(const std::vector<int>& set, std::string& why);
  bool ImpactWhileSetHeld(int k);
  bool EnterActiveSet(std::vector<int> Z0, const std::vector<int>& was_held, bool emit_sticks = true);
  void ProjectOntoSet(const std::vector<int>& Z);
  int HeldChatter(int k, const S& speed, const S& floor);
  int TryHeldAccumulation(int k);
  bool SimultaneousImpact(const std::vector<int>& Z);
  S Phase(const ClockT<S>& c) const { return phase0_ + m_.w * c.offset; }
  double AbsTime(const ClockT<S>& c) const {
    return R::to_double(S(t0_) + S(static_cast<double>(c.period)) * period_ + c.offset);
  }
  Clock ToClock(const ClockT<S>& c) const { return {c.period, R::to_double(c.offset)}; }
  // What may resolve an undetermined sequence: quad precision where it is not already in use (it
  // runs every scene the double engine runs, damped sticking of several modes included).
  std::string UndeterminedHint() const {
    if (std::is_same_v<S, double>)
      return fmt::format("Use run.precision = \"quad\"{}, or move the parameter",
                         cvode_ ? " with run.engine = \"exact\"" : "");
    return "Move the parameter";
  }
  S ContactSpeedFloor() const {
    // Rounding floor of ẋ_B = Σ c_i Ẋ_i (docs/model.md §5.4).
    return S(1000) * Eps<S>() * M(active_).shape.cwiseProduct(V_).cwiseAbs().sum();
  }
  // Observers see doubles: a view of a state vector (no copy for double).
  const Eigen::VectorXd& D(const Vec& v, Eigen::VectorXd& tmp) const {
    if constexpr (std::is_same_v<S, double>) {
      return v;
    } else {
      tmp = v.template cast<double>();
      return tmp;
    }
  }
  bool StopPolled() const {
    return (opt_.stop_requested && opt_.stop_requested->load(std::memory_order_relaxed)) ||
           (process_stop_ && process_stop_->load(std::memory_order_relaxed));
  }

  // impulse/energy: an impact's P when known (else from v⁻, v⁺), an accumulation's tail.
  void Emit(EventKind kind, const S& v_before, const S& v_after, int contact = -1,
            bool simultaneous = false, const S& impulse = S(-1), const S& energy = S(0));
  void NotifyReset(ResetKind kind, const Vec& Xb, const Vec& Vb, int contact = -1,
                   bool simultaneous = false);
  void EmitStretch(const ClockT<S>& start, PropagatorT<S>& p, const S& lo, const S& hi);
  void AdvanceClock(ClockT<S>& c, const S& sigma, const S& sigma_to_boundary,
                    const S& exact_offset = S(-1)) const;
  void ClassifyInitialState();
  void EnterSticking(StickStart how);
  void Depart(FlightStart how);
  bool OnContact();
  bool TryAccumulation(const S& reaction);
  bool TailClearOfOtherContacts(const S& delta);
  void Checkpointed();
  bool Fail(std::string message, RunStatus status = RunStatus::kNumericalFailure);

  // Physics invariants, checked where they arise (docs/reliability.md): a state below the stop
  // beyond tolerance after a flight or in a sample of one, a sticking state off the stop, a
  // non-finite state, a clock that goes backwards. The first violation is kept and ends the run
  // as a numerical failure naming it (Guarded()); the run is never reported ok.
  S GapTolerance(const Vec& X) const;
  void CheckFreeGap(const S& gap, const Vec& X, double t, const char* where);
  void CheckSegment(const ClockT<S>& from, const S& sigma);
  void CheckEventClock();
  bool Guarded();

  const System& sys_;
  const ModelT<S>& m_;
  const RunSpec& run_;
  const SimulationOptions& opt_;
  const std::atomic<bool>* process_stop_ = ProcessStopFlag();  // vibro/stop_request.hpp
  std::unique_ptr<PropagatorT<S>> engine_;
  std::vector<ModelT<S>> others_;              // contacts 1..m−1 (docs/contacts.md)
  std::vector<const ModelT<S>*> models_;       // every contact's model; models_[0] = &m_
  std::vector<std::unique_ptr<PropagatorT<S>>> resting_all_;  // one DOF: resting on each contact
  int active_ = 0;              // sticking: the held contact; free flight: the start contact
  std::vector<S> gaps_;         // several contacts: every gap (0 for the held one)
  std::vector<FlightStart> starts_;  // several contacts: how each gap starts (held flow too)
  std::vector<EventCounts> counts_;  // per contact
  S period_;
  double t0_;
  S phase0_{0};
  bool cvode_;
  double switch_ratio_;      // "threshold": plastic below this fraction of the first speed
  double resolution_ratio_;  // CVODE: impact speeds below this fraction are not resolved
  S chatter_tol_;            // accuracy target of a predicted accumulation point (time)
  int grazing_streak_ = 0;   // consecutive grazings (a degenerate contact loops on them)
  std::vector<int> held_set_;  // sticking on two or more contacts at once: them, ascending
  std::vector<std::unique_ptr<SetStickingT<S>>> set_engines_;  // one per held set met, kept

  ClockT<S> clock_;
  Vec X_, V_, Xs_, Vs_;
  Vec Xb_, Vb_;                          // the state just before a reset (scratch: no allocation per event)
  Eigen::VectorXd dx_, dv_, dx2_, dv2_;  // double views for observers (quad)
  Checkpoint checkpoint_{};              // reused at every period boundary
  Mode mode_ = Mode::kFree;
  S gap_{0};
  FlightStart flight_start_ = FlightStart::kGeneric;
  StickStart stick_start_ = StickStart::kGeneric;
  S chatter_first_{0}, chatter_last_{0};
  // Several contacts: a chattering sequence at one contact while another sticks (ImpactWhileHeld).
  static constexpr int kHeldChatterImpacts = 4096;
  int held_chatter_ = 0, held_chatter_contact_ = -1;
  double held_chatter_t_ = 0;
  TailPrediction<S> last_tail_;  // the last prediction tried in the current sequence
  std::string last_jump_failure_;  // why the engine could not take the last jump tried (CVODE)
  bool project_samples_ = false;
  long long sample_index_ = 0;
  std::string violation_;           // the first physics invariant broken (empty: none)
  ClockT<S> last_event_{-1, S(0)};  // clock of the last event emitted (monotone)
  RunResult result_;
  ContactLoadsT<S> loads_;  // impulses, energies, sticking phases (docs/loads.md)
  bool stretch_loads_ = false;  // the sticking segment under way searches max R per stretch
};

inline void Count(EventCounts& c, EventKind kind, bool simultaneous) {
  switch (kind) {
    case EventKind::kImpact: ++c.impacts; break;
    case EventKind::kAccumulation: ++c.accumulations; break;
    case EventKind::kStick: ++c.sticks; break;
    case EventKind::kRelease: ++c.releases; break;
    case EventKind::kGrazing: ++c.grazings; break;
  }
  if (simultaneous) ++c.simultaneous;
}

template <class S>
void Automaton<S>::Emit(EventKind kind, const S& v_before, const S& v_after, int contact,
                        bool simultaneous, const S& impulse, const S& energy) {
  if (contact < 0) contact = active_;
  const ModelT<S>& m = M(contact);
  grazing_streak_ = kind == EventKind::kGrazing ? grazing_streak_ + 1 : 0;
  CheckEventClock();
  Event e{kind,
          ToClock(clock_),
          AbsTime(clock_),
          R::to_double(m.side * m.ContactDisplacement(X_)),
          R::to_double(v_before),
          R::to_double(v_after),
          contact,
          simultaneous};
  if (kind != EventKind::kImpact && kind != EventKind::kGrazing) e.x_B = R::to_double(m.side * m.x0);
  if (kind == EventKind::kImpact) ImpactLoads(e, m, v_before, v_after, impulse);
  if (kind == EventKind::kAccumulation) {
    e.impulse = R::to_double(impulse);
    e.energy_dissipated = R::to_double(energy);
  }
  if (kind == EventKind::kStick) loads_.Begin(contact);
  if (kind == EventKind::kRelease) loads_.End(contact, e);
  Count(result_.counts, kind, simultaneous);
  // One contact: its counts are the run's (RunResult::contact_counts is filled at the end).
  if (multi()) Count(counts_[static_cast<size_t>(contact)], kind, simultaneous);
  for (auto* o : opt_.observers) o->OnEvent(e);
}

template <class S>
void Automaton<S>::NotifyReset(ResetKind kind, const Vec& Xb, const Vec& Vb, int contact,
                               bool simultaneous) {
  if (opt_.observers.empty()) return;
  if (contact < 0) contact = active_;
  const Reset r{kind, R::to_double(Phase(clock_)), D(Xb, dx_), D(Vb, dv_), D(X_, dx2_), D(V_, dv2_),
                0.0, 0.0, nullptr, nullptr, nullptr, R::to_double(M(contact).ContactVelocity(Vb)),
                contact, simultaneous};
  for (auto* o : opt_.observers) o->OnReset(r);
}

// Dense samples and section points whose times fall in (lo, hi] of a segment started at `start`.
template <class S>
void Automaton<S>::EmitStretch(const ClockT<S>& start, PropagatorT<S>& p, const S& lo,
                               const S& hi) {
  if (opt_.observers.empty()) return;
  // CVODE's dense output is valid on its last stretch only: max R is searched stretch by stretch.
  if (stretch_loads_) loads_.Stretch(M(active_), p, Phase(start), lo, hi);
  const int spp = run_.samples_per_period;
  // Section points: period boundaries t0 + kT.
  for (long long k = start.period + 1;; ++k) {
    const S sigma = S(static_cast<double>(k - start.period)) * period_ - start.offset;
    if (sigma > hi || k > run_.periods) break;
    if (sigma <= lo) continue;
    p.Evaluate(sigma, Xs_, Vs_);
    if (project_samples_) M(active_).ProjectOntoStop(Xs_, Vs_);
    if (mode_ == Mode::kFree && !project_samples_)
      for (const ModelT<S>* c : models_)
        CheckFreeGap(c->ContactDisplacement(Xs_) - c->x0, Xs_,
                     R::to_double(S(t0_) + S(static_cast<double>(k)) * period_), "a section point of a flight");
    const Sample s{{k, 0.0},
                   R::to_double(S(t0_) + S(static_cast<double>(k)) * period_),
                   D(Xs_, dx_),
                   D(Vs_, dv_),
                   R::to_double(m_.side * m_.ContactDisplacement(Xs_)),
                   mode_};
    for (auto* o : opt_.observers) o->OnSection(s);
  }
  if (spp <= 0) return;
  const S dt = period_ / spp;
  for (;; ++sample_index_) {
    const long long k = sample_index_ / spp;
    const S off = S(static_cast<double>(sample_index_ % spp)) * dt;
    const S sigma = S(static_cast<double>(k - start.period)) * period_ + off - start.offset;
    if (sigma > hi) break;
    if (sigma < lo) continue;
    if (k >= run_.periods) break;  // the end state is section row `periods`, not a sample
    p.Evaluate(sigma, Xs_, Vs_);
    if (project_samples_) M(active_).ProjectOntoStop(Xs_, Vs_);
    if (mode_ == Mode::kFree && !project_samples_)
      for (const ModelT<S>* c : models_)
        CheckFreeGap(c->ContactDisplacement(Xs_) - c->x0, Xs_,
                     R::to_double(S(t0_) + S(static_cast<double>(k)) * period_ + off), "a sample of a flight");
    const Sample s{{k, R::to_double(off)},
                   R::to_double(S(t0_) + S(static_cast<double>(k)) * period_ + off),
                   D(Xs_, dx_),
                   D(Vs_, dv_),
                   R::to_double(m_.side * m_.ContactDisplacement(Xs_)),
                   mode_};
    for (auto* o : opt_.observers) o->OnSample(s);
  }
}

template <class S>
void Automaton<S>::AdvanceClock(ClockT<S>& c, const S& sigma, const S& sigma_to_boundary,
                                const S& exact_offset) const {
  if (exact_offset >= 0 && exact_offset < period_) {
    c.offset = exact_offset;
  } else if (sigma >= sigma_to_boundary) {
    // Exactly at (or, after an accumulation jump, past) the boundary.
    S rest = sigma - sigma_to_boundary;
    ++c.period;
    while (rest >= period_) {
      rest -= period_;
      ++c.period;
    }
    c.offset = rest;
  } else {
    c.offset += sigma;
  }
}

template <class S>
void Automaton<S>::EnterSticking(StickStart how) {
  M(active_).ProjectOntoStop(X_, V_);
  gap_ = 0;
  if (multi()) {
    gaps_[static_cast<size_t>(active_)] = 0;
    for (size_t j = 0; j < models_.size(); ++j)
      if (static_cast<int>(j) != active_) gaps_[j] = models_[j]->ContactDisplacement(X_) - models_[j]->x0;
  }
  mode_ = Mode::kSticking;
  stick_start_ = how;
  chatter_first_ = chatter_last_ = 0;
  held_chatter_ = 0;
}

template <class S>
void Automaton<S>::Depart(FlightStart how) {
  mode_ = Mode::kFree;
  flight_start_ = how;
  held_chatter_ = 0;
  if (multi()) starts_[static_cast<size_t>(active_)] = how;
}

// A state on the stop at rest (or the start of a run): stick, leave, or decide with Ṙ.
template <class S>
void Automaton<S>::ClassifyInitialState() {
  if (multi()) {
    // Several contacts: which gaps are closed (within the rounding of the initial state, as
    // System::StopTolerance for one contact); one closed contact is classified as the single stop
    // is, on its own model; none starts a free flight.
    int on = -1, closed = 0;
    for (int j = 0; j < static_cast<int>(models_.size()); ++j) {
      const ModelT<S>& c = M(j);
      const S g = c.ContactDisplacement(X_) - c.x0;
      const S tol = S(System::kStopUlps) * Eps<S>() *
                    (R::abs(c.x0) + c.shape.cwiseProduct(X_).cwiseAbs().sum());
      gaps_[static_cast<size_t>(j)] = g;
      starts_[static_cast<size_t>(j)] = FlightStart::kGeneric;
      if (g <= tol) {
        on = j;
        ++closed;
      }
    }
    if (closed > 1) {
      // Several closed gaps: those moving away leave, the others are at rest on their stops and the
      // acceleration LCP decides which stick (their stick events follow the initial section).
      std::vector<int> Z0;
      for (int j = 0; j < static_cast<int>(models_.size()); ++j) {
        const ModelT<S>& c = M(j);
        const S tol = S(System::kStopUlps) * Eps<S>() *
                      (R::abs(c.x0) + c.shape.cwiseProduct(X_).cwiseAbs().sum());
        if (!(gaps_[static_cast<size_t>(j)] <= tol)) continue;
        gaps_[static_cast<size_t>(j)] = 0;
        X_ -= c.contact * ((c.ContactDisplacement(X_) - c.x0) / c.s_B);
        const S vtol = S(System::kStopUlps) * Eps<S>() * c.shape.cwiseProduct(V_).cwiseAbs().sum();
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
    return;
  }
  // Any positive gap is a free flight; a state at (or, by the rounding of a physical-to-modal
  // conversion, within validation tolerance inside) the stop is on it.
  // The decision is taken on the double state, whatever S: the quad engine solves the problem
  // the double one is given (its data are converted from double, and a start on the stop in
  // double, e.g. the static equilibrium, stays on the stop in quad rather than 1e-16 above it).
  const Eigen::VectorXd Xd = X_.template cast<double>(), Vd = V_.template cast<double>();
  const S xB = m_.ContactDisplacement(X_);
  if (sys_.ContactDisplacement(Xd) - sys_.stop() > 0) {
    gap_ = xB - m_.x0;
    if (!(gap_ > 0)) gap_ = Eps<S>() * (R::abs(m_.x0) + S(1));
    Depart(FlightStart::kGeneric);
    return;
  }
  gap_ = 0;
  X_ -= m_.contact * ((xB - m_.x0) / m_.s_B);
  if (sys_.ContactVelocity(Vd) > 0) {  // leaving the stop: the gap has a simple zero at σ = 0
    Depart(FlightStart::kAfterImpact);
    return;
  }
  if (!std::is_same_v<S, double>) V_ -= m_.contact * (m_.ContactVelocity(V_) / m_.s_B);
  const S phase = Phase(clock_);
  const S Rc = m_.Reaction(X_, V_, phase);
  if (Rc > 0) {
    EnterSticking(StickStart::kGeneric);
  } else if (Rc < 0) {
    m_.ProjectOntoStop(X_, V_);
    Depart(FlightStart::kDeparture);
  } else if (m_.ReactionRate(X_, V_, phase) >= 0) {
    EnterSticking(StickStart::kRising);
  } else {
    m_.ProjectOntoStop(X_, V_);
    Depart(FlightStart::kAfterRelease);
  }
}

template <class S>
bool Automaton<S>::Fail(std::string message, RunStatus status) {
  result_.status = status;
  result_.message = std::move(message);
  return false;
}

// How far below the stop a state may be found without breaking the contact law: the exact
// engine's rounding (relative 1e-6 of the contact displacement's scale is far above it); CVODE's
// local error, rtol of that scale plus atol per modal coordinate, with a margin of 10.
template <class S>
S Automaton<S>::GapTolerance(const Vec& X) const {
  const S scale = S(1) + R::abs(m_.x0) + m_.shape.cwiseProduct(X).cwiseAbs().sum();
  S tol = S(1e-6) * scale;
  if (cvode_) tol += S(10 * run_.rtol) * scale + S(10 * run_.atol) * m_.shape.cwiseAbs().sum();
  return tol;
}

template <class S>
void Automaton<S>::CheckFreeGap(const S& gap, const Vec& X, double t, const char* where) {
  if (!violation_.empty() || gap >= -GapTolerance(X)) return;
  if (!R::isfinite(gap)) return;  // a non-finite state is reported by CheckSegment
  violation_ = fmt::format(
      "state below the stop: x_B − x0 = {:.3g} in {} at t = {:.17g} (tolerance {:.3g}); the {} "
      "engine crossed the stop without detecting the contact{}",
      R::to_double(gap), where, t, R::to_double(GapTolerance(X)), cvode_ ? "CVODE" : "exact",
      cvode_ ? ": tighten run.rtol and run.atol, or use run.engine = \"exact\"" : "");
}

// After a segment from clock `from` over local time `sigma`, with X_, V_, gap_ and clock_ updated.
template <class S>
void Automaton<S>::CheckSegment(const ClockT<S>& from, const S& sigma) {
  if (!violation_.empty()) return;
  bool finite = R::isfinite(sigma);
  for (Eigen::Index i = 0; i < X_.size(); ++i) finite = finite && R::isfinite(X_[i]) && R::isfinite(V_[i]);
  if (!finite) {
    violation_ = fmt::format("state not finite after a {} segment from t = {:.17g} (σ = {:.3g})",
                             mode_ == Mode::kFree ? "free-flight" : "sticking", AbsTime(from),
                             R::to_double(sigma));
    return;
  }
  const bool forward = sigma >= 0 && R::isfinite(clock_.offset) && clock_.offset >= 0 &&
                       clock_.offset < period_ &&
                       (clock_.period > from.period ||
                        (clock_.period == from.period && clock_.offset >= from.offset));
  if (!forward) {
    violation_ = fmt::format(
        "non-monotone clock: a {} segment from period {} + {:.17g} ended at period {} + {:.17g} "
        "(σ = {:.3g})",
        mode_ == Mode::kFree ? "free-flight" : "sticking", from.period, R::to_double(from.offset),
        clock_.period, R::to_double(clock_.offset), R::to_double(sigma));
    return;
  }
  if (mode_ == Mode::kFree) {
    CheckFreeGap(gap_, X_, AbsTime(clock_), "the state at the end of a flight");
  } else {
    const S off = M(active_).ContactDisplacement(X_) - M(active_).x0;
    if (R::abs(off) > GapTolerance(X_))
      violation_ = fmt::format("sticking state off the stop: x_B − x0 = {:.3g} at t = {:.17g} "
                               "(tolerance {:.3g})",
                               R::to_double(off), AbsTime(clock_), R::to_double(GapTolerance(X_)));
  }
}

template <class S>
void Automaton<S>::CheckEventClock() {
  if (violation_.empty() &&
      (clock_.period < last_event_.period ||
       (clock_.period == last_event_.period && clock_.offset < last_event_.offset)))
    violation_ = fmt::format(
        "non-monotone clock: an event at period {} + {:.17g} follows one at period {} + {:.17g}",
        clock_.period, R::to_double(clock_.offset), last_event_.period,
        R::to_double(last_event_.offset));
  last_event_ = clock_;
}

// Ends the run as a numerical failure when an invariant was broken; false then.
template <class S>
bool Automaton<S>::Guarded() {
  if (violation_.empty() || result_.status != RunStatus::kOk) return true;
  return Fail("physics invariant broken: " + violation_);
}

// docs/model.md §5.4, §5.4: predict the accumulation point of a chattering sequence from the impact
// just taken, when the prediction's estimated error is within the run's target.
template <class S>
bool Automaton<S>::TryAccumulation(const S& reaction) {
  const ModelT<S>& m = multi() ? M(active_) : m_;
  const S phase_k = Phase(clock_);
  const TailPrediction<S> tail = PredictTail<S>(m, X_, V_, phase_k, chatter_tol_);
  last_tail_ = tail;
  last_jump_failure_.clear();
  if (!tail.accepted) {
    ++result_.chatter.impacts_followed;
    return false;
  }
  const S delta = tail.delta;
  const SegmentStartT<S> start{Mode::kFree, phase_k, clock_.offset, X_, V_, S(0),
                               FlightStart::kAfterImpact, StickStart::kGeneric, active_};
  // First pass without output: the jump is taken only if R(t∞) > 0 after the projection.
  engine_->Begin(start);
  const auto probe = engine_->Advance(delta, false, {});
  if (probe.end == SegmentEnd::kFailure) {  // a stop request is seen again by the next segment
    if (!probe.stopped) last_jump_failure_ = probe.message;
    return false;
  }
  Vec X, V;
  engine_->Evaluate(delta, X, V);
  const Vec X_end = X, V_end = V;
  m.ProjectOntoStop(X, V);
  ClockT<S> end = clock_;
  AdvanceClock(end, delta, period_ - clock_.offset);
  if (!(m.Reaction(X, V, Phase(end)) > 0)) {  // the sequence would not complete: follow it
    ++result_.chatter.impacts_followed;
    return false;
  }
  // Several contacts (MODEL §11.6): the tail holds only if every other gap stays open over it.
  if (multi() && !TailClearOfOtherContacts(delta)) {
    ++result_.chatter.impacts_followed;
    return false;
  }
  // Commit: the same flow with dense output, then the state at t∞.
  const Vec X_k = X_, V_k = V_;
  engine_->Begin({Mode::kFree, phase_k, clock_.offset, X_k, V_k, S(0), FlightStart::kAfterImpact,
                  StickStart::kGeneric, active_});
  const ClockT<S> from = clock_;
  // Samples inside the tail show the state projected onto the stop: the free flow over Δ∞ sums
  // the tail's impacts into one impulse at its end and dips below the stop on the way; the true
  // bounces stay within O(ẋ_B⁺²/(s_B R)) above it.
  project_samples_ = true;
  engine_->Advance(delta, false,
                   [&](const S& lo, const S& hi) { EmitStretch(from, *engine_, lo, hi); });
  project_samples_ = false;
  clock_ = end;
  X_ = X;
  V_ = V;
  gap_ = 0;
  ++result_.chatter.accumulations_predicted;
  const double err = R::to_double(tail.error / period_);
  if (err > result_.chatter.max_estimated_error) result_.chatter.max_estimated_error = err;
  if (!opt_.observers.empty()) {
    Eigen::VectorXd a, b, c, d, xe, ve;
    const Eigen::VectorXd grad = DeltaGradient<S>(m, X_k, V_k, phase_k, tail);
    const Reset jump{ResetKind::kAccumulation, R::to_double(phase_k), D(X_k, a), D(V_k, b),
                     D(X_, c), D(V_, d), R::to_double(delta), R::to_double(reaction),
                     &grad, &D(X_end, xe), &D(V_end, ve),
                     std::numeric_limits<double>::quiet_NaN(), active_};
    for (auto* o : opt_.observers) o->OnReset(jump);
  }
  // ẋ_B → 0 at the accumulation point: the remaining impacts are summed into one impulse.
  S tail_impulse(0), tail_energy(0);
  TailLoads(m, tail.speed, tail.epsilon, tail_impulse, tail_energy);
  Emit(EventKind::kAccumulation, S(0), S(0), -1, false, tail_impulse, tail_energy);
  mode_ = Mode::kSticking;
  stick_start_ = StickStart::kGeneric;
  if (multi()) {
    for (size_t j = 0; j < models_.size(); ++j)
      gaps_[j] = static_cast<int>(j) == active_ ? S(0) : models_[j]->ContactDisplacement(X_) - models_[j]->x0;
    starts_.assign(models_.size(), FlightStart::kGeneric);
  }
  chatter_first_ = chatter_last_ = 0;
  Emit(EventKind::kStick, S(0), S(0));
  return true;
}

// Free flight reached g = 0 at the current state.
template <class S>
bool Automaton<S>::OnContact() {
  const ModelT<S>& m = multi() ? M(active_) : m_;
  // Snap the contact coordinate onto the stop (docs/model.md §8).
  X_ -= m.contact * ((m.ContactDisplacement(X_) - m.x0) / m.s_B);
  gap_ = 0;
  const S phase = Phase(clock_);
  const S v_minus = m.ContactVelocity(V_);
  const S floor = ContactSpeedFloor();
  const S r = m.r;
  const bool accumulating = run_.chatter == ChatterTreatment::kAccumulation && r > 0 && r < 1;

  // CVODE cannot resolve impact speeds below √rtol of the sequence's first one: a sequence that
  // gets there without a prediction inside its accuracy target is undetermined, as is one that
  // reaches the rounding floor of ẋ_B (docs/model.md §5.4). Sticking there would be a guess.
  const bool touch = !(v_minus < -floor);
  const bool unresolved = cvode_ && accumulating && chatter_last_ > 0 &&
                          -v_minus < S(resolution_ratio_) * chatter_first_;
  if (accumulating && chatter_last_ > 0 && (touch || unresolved)) {
    const S Rc = m.Reaction(X_, V_, phase);
    if (Rc > 0) {
      return Fail(
          fmt::format(
              "chattering sequence undetermined at this precision: its impacts reached speed "
              "{:.3g} ({} floor) near t = {:.17g} before its accumulation point could be "
              "predicted within run.chatter_tolerance = {:.3g} T (last prediction tried: ε = {:.3g}, "
              "estimated error at least {:.3g} T{}; reaction {:.3g}). {}",
              R::to_double(-v_minus), unresolved ? "CVODE's √rtol resolution" : "the rounding",
              AbsTime(clock_), R::to_double(chatter_tol_ / period_),
              R::to_double(last_tail_.epsilon), R::to_double(last_tail_.error / period_),
              last_jump_failure_.empty() ? "" : ", but the jump could not be taken: " + last_jump_failure_,
              R::to_double(Rc), UndeterminedHint()),
          RunStatus::kUndetermined);
    }
  }
  if (touch) {
    // Tangential touch (docs/model.md §2.1): no impact.
    const S Rc = m.Reaction(X_, V_, phase);
    Xb_ = X_;
    Vb_ = V_;
    const Vec& Xb = Xb_;
    const Vec& Vb = Vb_;
    Emit(EventKind::kGrazing, v_minus, v_minus);
    if (Rc > 0) {
      EnterSticking(StickStart::kGeneric);
      NotifyReset(ResetKind::kPlasticStick, Xb, Vb);
      Emit(EventKind::kStick, S(0), S(0));
    } else {
      m.ProjectOntoStop(X_, V_);
      const S rate = m.ReactionRate(X_, V_, phase);
      if (Rc < 0) {
        Depart(FlightStart::kDeparture);
        NotifyReset(ResetKind::kGrazing, Xb, Vb);
      } else if (rate < 0) {
        Depart(FlightStart::kAfterRelease);
        NotifyReset(ResetKind::kGrazing, Xb, Vb);
      } else {
        EnterSticking(StickStart::kRising);
        NotifyReset(ResetKind::kPlasticStick, Xb, Vb);
        Emit(EventKind::kStick, S(0), S(0));
      }
    }
    return true;
  }

  // Chattering sequence bookkeeping: a sequence is a run of impacts of decreasing speed.
  const S speed = -v_minus;
  if (chatter_last_ == 0 || speed > chatter_last_) chatter_first_ = speed;
  chatter_last_ = speed;
  const S v_switch = S(switch_ratio_) * chatter_first_ > floor ? S(S(switch_ratio_) * chatter_first_)
                                                              : floor;
  const bool in_switch = speed < v_switch && chatter_first_ > speed;

  const bool plastic = r == 0 || (run_.chatter == ChatterTreatment::kThreshold && in_switch);
  if (plastic) {
    // docs/model.md §4.4: plastic impact; stick if R > 0, leave at zero velocity if R < 0, decide with Ṙ
    // if R = 0.
    Xb_ = X_;
    Vb_ = V_;
    const Vec& Xb = Xb_;
    const Vec& Vb = Vb_;
    m.ProjectOntoStop(X_, V_);
    Emit(EventKind::kImpact, v_minus, S(0));
    const S Rc = m.Reaction(X_, V_, phase);
    if (Rc > 0) {
      EnterSticking(StickStart::kGeneric);
      NotifyReset(ResetKind::kPlasticStick, Xb, Vb);
      Emit(EventKind::kStick, S(0), S(0));
    } else if (Rc < 0) {
      chatter_first_ = chatter_last_ = 0;
      Depart(FlightStart::kDeparture);
      NotifyReset(ResetKind::kPlasticLeave, Xb, Vb);
    } else if (m.ReactionRate(X_, V_, phase) > 0) {
      EnterSticking(StickStart::kRising);
      NotifyReset(ResetKind::kPlasticStick, Xb, Vb);
      Emit(EventKind::kStick, S(0), S(0));
    } else {
      chatter_first_ = chatter_last_ = 0;
      Depart(FlightStart::kAfterRelease);
      NotifyReset(ResetKind::kPlasticLeave, Xb, Vb);
    }
    return true;
  }

  // Restitution (the paper's eq. (12)).
  Vb_ = V_;
  const Vec& Vb = Vb_;
  m.ApplyImpact(V_, r);
  const S Rc = m.Reaction(X_, V_, phase);
  NotifyReset(ResetKind::kImpact, X_, Vb);
  Emit(EventKind::kImpact, v_minus, m.ContactVelocity(V_));
  if (accumulating && Rc > 0) {
    if (TryAccumulation(Rc)) return true;
  }
  if (run_.chatter == ChatterTreatment::kNone && Rc > 0) {
    // Impacts followed one by one: stop once the next flight is below the resolution.
    const S next_flight = S(2) * r * speed / (m.s_B * Rc);
    if (r * speed <= floor || next_flight <= S(4) * Eps<S>() * period_)
      return Fail(fmt::format(
          "chattering: impacts accumulate near t = {:.17g} and cannot be followed one by one "
          "(contact speed {:.3g}, next flight {:.3g}; run.chatter = \"none\"). Use run.chatter = "
          "\"accumulation\" (or \"threshold\")",
          AbsTime(clock_), R::to_double(r * speed), R::to_double(next_flight)));
  }
  Depart(FlightStart::kAfterImpact);
  return true;
}

// Several contacts (docs/contacts.md) ------------------------------------------------------------

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
  }
  if (mode_ == Mode::kFree) gap_ = gaps_[static_cast<size_t>(active_)];
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

// W_jk = c_jᵀT_k between two contacts, 0 when it is within the rounding of the model's (double)
// mode shapes, whatever S: contacts on different masses of a diagonal mass matrix are decoupled
// (MODEL §11.10), and a rounding-level coupling would push a held contact off its stop.
template <class S>
static S DelassusOffDiagonal(const ModelT<S>& a, const ModelT<S>& b) {
  const S w = a.shape.dot(b.contact);
  const S scale = Real<S>::sqrt(a.s_B * b.s_B);
  return Real<S>::abs(w) <= S(64 * std::numeric_limits<double>::epsilon()) * scale ? S(0) : w;
}

// Gap acceleration g_k'' under the flow with contact `held` stuck: c_kᵀ Π Ẍ_free, Π = I − T cᵀ/s.
template <class S>
static S HeldGapAcceleration(const ModelT<S>& held, const ModelT<S>& k, const typename ModelT<S>::Vec& X,
                             const typename ModelT<S>::Vec& V, const S& phase) {
  using Vec = typename ModelT<S>::Vec;
  const Vec acc = -k.omega.cwiseAbs2().cwiseProduct(X) -
                  S(2) * k.zeta.cwiseProduct(k.omega).cwiseProduct(V) +
                  k.forcing * (k.f * Real<S>::sin(phase));
  const Vec held_acc = acc - held.contact * (held.shape.dot(acc) / held.s_B);
  return k.shape.dot(held_acc);
}

template <class S>
bool Automaton<S>::OnContactMulti(int k) {
  if (mode_ == Mode::kSticking) return held_set_.empty() ? ImpactWhileHeld(k) : ImpactWhileSetHeld(k);
  // Contacts closed at the same instant, within the rounding of their gaps and a window of a few
  // ulps of the period at their closing speed (MODEL §11.2.3): one impact LCP (§11.4).
  std::vector<int> Z{k};
  const S window = S(64) * Eps<S>() * period_;
  for (int j = 0; j < static_cast<int>(models_.size()); ++j) {
    if (j == k) continue;
    const ModelT<S>& c = M(j);
    const S v = c.ContactVelocity(V_);
    const S tol = S(System::kStopUlps) * Eps<S>() *
                      (R::abs(c.x0) + c.shape.cwiseProduct(X_).cwiseAbs().sum()) +
                  window * R::abs(v);
    if (gaps_[static_cast<size_t>(j)] <= tol && v <= S(0)) Z.push_back(j);
  }
  if (Z.size() > 1) return SimultaneousImpact(Z);
  if (k != active_) chatter_first_ = chatter_last_ = 0;  // a sequence is at one contact
  active_ = k;
  for (size_t j = 0; j < starts_.size(); ++j) starts_[j] = FlightStart::kGeneric;
  return OnContact();
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
  if (!(v_minus < -floor)) {
    // Tangential arrival: it leaves only if the held flow pulls it off.
    Emit(EventKind::kGrazing, v_minus, v_minus, k);
    NotifyReset(ResetKind::kGrazing, X_, V_, k);
    if (HeldGapAcceleration(mj, mk, X_, V_, phase) > 0) {
      starts_[static_cast<size_t>(k)] = FlightStart::kDeparture;
      return true;
    }
    NotifyReset(ResetKind::kHeldSet, X_, V_);
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
    NotifyReset(ResetKind::kHeldSet, X_, V_);
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
  using Mat = typename ModelT<S>::Mat;
  const auto z = static_cast<Eigen::Index>(Z.size());
  Mat W(z, z);
  Vec vm(z), q(z);
  for (Eigen::Index a = 0; a < z; ++a) {
    const ModelT<S>& ma = M(Z[static_cast<size_t>(a)]);
    X_ -= ma.contact * ((ma.ContactDisplacement(X_) - ma.x0) / ma.s_B);
    vm[a] = ma.ContactVelocity(V_);
    q[a] = (S(1) + ma.r) * vm[a];
    for (Eigen::Index b = 0; b < z; ++b) {
      const ModelT<S>& mb = M(Z[static_cast<size_t>(b)]);
      W(a, b) = a == b ? ma.s_B : DelassusOffDiagonal(ma, mb);
    }
  }
  Vec P = Vec::Zero(z);
  bool solved = false;
  for (unsigned mask = 1; mask < (1u << z) && !solved; ++mask) {
    std::vector<Eigen::Index> act;
    for (Eigen::Index a = 0; a < z; ++a)
      if (mask & (1u << a)) act.push_back(a);
    const auto na = static_cast<Eigen::Index>(act.size());
    Mat Wa(na, na);
    Vec qa(na);
    for (Eigen::Index a = 0; a < na; ++a) {
      qa[a] = -q[act[static_cast<size_t>(a)]];
      for (Eigen::Index b = 0; b < na; ++b) Wa(a, b) = W(act[static_cast<size_t>(a)], act[static_cast<size_t>(b)]);
    }
    const Vec Pa = Wa.fullPivLu().solve(qa);
    Vec Pt = Vec::Zero(z);
    for (Eigen::Index a = 0; a < na; ++a) Pt[act[static_cast<size_t>(a)]] = Pa[a];
    const Vec w = W * Pt + q;
    bool ok = true;
    for (Eigen::Index a = 0; a < z; ++a) {
      const S scale = R::abs(q[a]) + S(1e-300);
      if (Pt[a] < -S(64) * Eps<S>() * scale || w[a] < -S(64) * Eps<S>() * scale) ok = false;
    }
    if (ok) {
      P = Pt.cwiseMax(S(0));
      solved = true;
    }
  }
  if (!solved)
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
    NotifyReset(ResetKind::kHeldSet, X_, V_);
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

// Sticking on two or more contacts at once (docs/contacts.md) ------------------------------------

// The LCP w = W x + q, 0 ≤ x ⊥ w ≥ 0 by enumerating the index sets (W positive definite: exactly
// one fits), within `tol` of each sign condition. False when none fits.
template <class S>
static bool SolveLcp(const typename ModelT<S>::Mat& W, const typename ModelT<S>::Vec& q, const S& tol,
                     typename ModelT<S>::Vec& x) {
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
    bool ok = true;
    for (Eigen::Index a = 0; a < z; ++a)
      if (xt[a] < -tol || w[a] < -tol) ok = false;
    if (ok) {
      x = xt.cwiseMax(S(0));
      return true;
    }
  }
  return false;
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

// Plastic projection onto {g_j = ġ_j = 0, j ∈ Z} (MODEL §11.5.3): Ẋ ← Ẋ − T_Z W_ZZ⁻¹ C_Z Ẋ and
// X ← X − T_Z W_ZZ⁻¹ (C_Z X − e_Z).
template <class S>
void Automaton<S>::ProjectOntoSet(const std::vector<int>& Z) {
  using Mat = typename ModelT<S>::Mat;
  const auto z = static_cast<Eigen::Index>(Z.size());
  if (z == 1) {
    M(Z.front()).ProjectOntoStop(X_, V_);
    return;
  }
  Mat W(z, z);
  Vec gx(z), gv(z);
  for (Eigen::Index a = 0; a < z; ++a) {
    const ModelT<S>& ma = M(Z[static_cast<size_t>(a)]);
    gx[a] = ma.ContactDisplacement(X_) - ma.x0;
    gv[a] = ma.ContactVelocity(V_);
    for (Eigen::Index b = 0; b < z; ++b)
      W(a, b) = a == b ? ma.s_B : DelassusOffDiagonal(ma, M(Z[static_cast<size_t>(b)]));
  }
  const auto lu = W.fullPivLu();
  const Vec px = lu.solve(gx), pv = lu.solve(gv);
  for (Eigen::Index a = 0; a < z; ++a) {
    const ModelT<S>& ma = M(Z[static_cast<size_t>(a)]);
    X_ -= ma.contact * px[a];
    V_ -= ma.contact * pv[a];
  }
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
    Mat W(z, z);
    Vec a0(z);
    S scale(0);
    for (Eigen::Index a = 0; a < z; ++a) {
      const ModelT<S>& ma = M(Z0[static_cast<size_t>(a)]);
      const Vec acc = -ma.omega.cwiseAbs2().cwiseProduct(X_) -
                      S(2) * ma.zeta.cwiseProduct(ma.omega).cwiseProduct(V_) + ma.forcing * (ma.f * R::sin(phase));
      a0[a] = ma.shape.dot(acc);
      scale += ma.shape.cwiseProduct(acc).cwiseAbs().sum();
      for (Eigen::Index b = 0; b < z; ++b)
        W(a, b) = a == b ? ma.s_B : DelassusOffDiagonal(ma, M(Z0[static_cast<size_t>(b)]));
    }
    // The held flow's data are double whatever S: decisions within double rounding of the forces.
    const S tol = S(1e3 * std::numeric_limits<double>::epsilon()) * (scale + S(1e-300));
    Vec lam;
    if (!SolveLcp<S>(W, a0, tol, lam))
      return Fail(fmt::format("{} contacts at rest at t = {:.17g}: the contact-force LCP has no "
                              "solution (dependent contacts)", Z0.size(), AbsTime(clock_)));
    const Vec acc = W * lam + a0;
    for (Eigen::Index a = 0; a < z; ++a) {
      const int j = Z0[static_cast<size_t>(a)];
      if (lam[a] <= tol && acc[a] <= tol)
        return Fail(fmt::format("contact {} at rest at t = {:.17g} with zero force and zero "
                                "acceleration (a degenerate entry into sticking, docs/contacts.md): "
                                "undetermined at this order. Move the parameter",
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
  const auto refresh_gaps = [&] {
    for (size_t j = 0; j < models_.size(); ++j)
      gaps_[j] = std::find(stick.begin(), stick.end(), static_cast<int>(j)) != stick.end()
                     ? S(0) : models_[j]->ContactDisplacement(X_) - models_[j]->x0;
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
  using Mat = typename ModelT<S>::Mat;
  const ModelT<S>& mk = M(k);
  const S u = mk.ContactVelocity(V_), r = mk.r;
  if (!(u > 0) || !(r > 0) || !(r < 1)) return 0;
  const std::vector<int> held = held_set_.empty() ? std::vector<int>{active_} : held_set_;
  std::vector<int> Z = held;
  Z.push_back(k);
  std::sort(Z.begin(), Z.end());
  const auto delassus = [&](const std::vector<int>& set) {
    const auto z = static_cast<Eigen::Index>(set.size());
    Mat W(z, z);
    for (Eigen::Index a = 0; a < z; ++a)
      for (Eigen::Index b = 0; b < z; ++b)
        W(a, b) = a == b ? M(set[static_cast<size_t>(a)]).s_B
                         : DelassusOffDiagonal(M(set[static_cast<size_t>(a)]), M(set[static_cast<size_t>(b)]));
    return W;
  };
  // Π_set v = v − T_set W⁻¹ C_set v.
  const auto project = [&](const std::vector<int>& set, const Vec& v) {
    const auto z = static_cast<Eigen::Index>(set.size());
    Vec cv(z);
    for (Eigen::Index a = 0; a < z; ++a) cv[a] = M(set[static_cast<size_t>(a)]).shape.dot(v);
    const Vec x = delassus(set).fullPivLu().solve(cv);
    Vec out = v;
    for (Eigen::Index a = 0; a < z; ++a) out -= M(set[static_cast<size_t>(a)]).contact * x[a];
    return out;
  };
  const Vec X0 = X_, V0 = V_;
  ProjectOntoSet(Z);
  const Vec Xs = X_, Vs = V_;
  X_ = X0;
  V_ = V0;
  const S phase = Phase(clock_);
  const Vec a_free = -mk.omega.cwiseAbs2().cwiseProduct(Xs) -
                     S(2) * mk.zeta.cwiseProduct(mk.omega).cwiseProduct(Vs) + mk.forcing * (mk.f * R::sin(phase));
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
                        mk.forcing * (mk.f * mk.w * R::cos(phase));
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
  // The held flow over the tail, k left out: nothing else may happen in it.
  PropagatorT<S>* p = held_set_.empty() ? engine_.get() : static_cast<PropagatorT<S>*>(SetEngine());
  if (!p) return -1;
  const SegmentStartT<S> start{Mode::kSticking, phase, clock_.offset, X_, V_, S(0), flight_start_,
                               StickStart::kGeneric, active_, &gaps_, &starts_, k};
  p->Begin(start);
  const auto probe = p->Advance(delta, true, {});
  if (probe.end == SegmentEnd::kFailure) return 0;  // a stop request is seen by the next segment
  if (probe.end != SegmentEnd::kLimit) return 0;
  p->Begin(start);
  const ClockT<S> from = clock_;
  p->Advance(delta, false, [&](const S& lo, const S& hi) { EmitStretch(from, *p, lo, hi); });
  p->Evaluate(delta, X_, V_);
  AdvanceClock(clock_, delta, period_ - clock_.offset);
  ProjectOntoSet(Z);
  ++result_.chatter.accumulations_predicted;
  const double err = R::to_double(error / period_);
  if (err > result_.chatter.max_estimated_error) result_.chatter.max_estimated_error = err;
  NotifyReset(ResetKind::kHeldSet, X_, V_);
  Emit(EventKind::kAccumulation, S(0), S(0), k);
  return EnterActiveSet(Z, held) ? 1 : -1;
}

// A free contact k closes while the set S = held_set_ sticks: the impact LCP (I2) on S ∪ {k}
// with v_S⁻ = 0 (MODEL §11.4.2). Held contacts the impulse pushes off lift off (a release with
// their speed after); those left at rest, and k if it lands plastically or arrives tangentially,
// go to the acceleration LCP (S3).
template <class S>
bool Automaton<S>::ImpactWhileSetHeld(int k) {
  using Mat = typename ModelT<S>::Mat;
  const ModelT<S>& mk = M(k);
  const std::vector<int> was = held_set_;
  X_ -= mk.contact * ((mk.ContactDisplacement(X_) - mk.x0) / mk.s_B);
  ProjectOntoSet(was);
  gaps_[static_cast<size_t>(k)] = 0;
  const S v_minus = mk.ContactVelocity(V_);
  const S floor = S(1000 * std::numeric_limits<double>::epsilon()) * mk.shape.cwiseProduct(V_).cwiseAbs().sum();
  std::vector<int> Z = was;
  Z.push_back(k);
  if (!(v_minus < -floor)) {
    Emit(EventKind::kGrazing, v_minus, v_minus, k);
    NotifyReset(ResetKind::kHeldSet, X_, V_);
    return EnterActiveSet(Z, was);
  }
  const auto z = static_cast<Eigen::Index>(Z.size());
  Mat W(z, z);
  Vec q(z);
  for (Eigen::Index a = 0; a < z; ++a) {
    const ModelT<S>& ma = M(Z[static_cast<size_t>(a)]);
    q[a] = (S(1) + ma.r) * ma.ContactVelocity(V_);
    for (Eigen::Index b = 0; b < z; ++b)
      W(a, b) = a == b ? ma.s_B : DelassusOffDiagonal(ma, M(Z[static_cast<size_t>(b)]));
  }
  Vec P;
  if (!SolveLcp<S>(W, q, S(64) * Eps<S>() * (R::abs(q[z - 1]) + S(1e-300)), P))
    return Fail(fmt::format("contact {} hits at t = {:.17g} while {} contacts stick: the impact law "
                            "has no solution (dependent contacts)",
                            k, AbsTime(clock_), was.size()));
  Vb_ = V_;
  for (Eigen::Index a = 0; a < z; ++a) V_ += M(Z[static_cast<size_t>(a)]).contact * P[a];
  for (Eigen::Index a = 0; a + 1 < z; ++a) loads_.AddImpulse(Z[static_cast<size_t>(a)], P[a]);  // held ones
  NotifyReset(ResetKind::kHeldSet, X_, Vb_);
  const S vk = mk.ContactVelocity(V_);
  Emit(EventKind::kImpact, v_minus, vk, k);
  std::vector<int> rest, stay;
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
  if (vk > floor) starts_[static_cast<size_t>(k)] = FlightStart::kAfterImpact;
  else rest.push_back(k);
  const int followed = held_chatter_, contact = held_chatter_contact_;
  const double t = held_chatter_t_;
  const S last = chatter_last_;
  if (!EnterActiveSet(rest, stay)) return false;
  if (vk > floor && mode_ == Mode::kSticking && held_set_ == was) {
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

template <class S>
void Automaton<S>::Checkpointed() {
  if (opt_.observers.empty()) return;
  Checkpoint& cp = checkpoint_;  // assigned in place: its vectors keep their storage
  cp.clock = ToClock(clock_);
  cp.X = X_.template cast<double>();
  cp.V = V_.template cast<double>();
  cp.mode = mode_;
  cp.gap = R::to_double(gap_);
  cp.start_kind = mode_ == Mode::kFree ? static_cast<int>(flight_start_) : static_cast<int>(stick_start_);
  cp.chatter_first_speed = R::to_double(chatter_first_);
  cp.chatter_last_speed = R::to_double(chatter_last_);
  cp.sample_index = sample_index_;
  cp.counts = result_.counts;
  cp.chatter_predicted = result_.chatter.accumulations_predicted;
  cp.chatter_followed = result_.chatter.impacts_followed;
  cp.chatter_max_error = result_.chatter.max_estimated_error;
  cp.contact = active_;
  loads_.Save(cp);
  cp.held = held_set_;
  if (multi()) cp.contact_counts = counts_;
  cp.gaps.resize(gaps_.size());
  cp.start_kinds.resize(starts_.size());
  for (size_t j = 0; j < gaps_.size(); ++j) {
    cp.gaps[j] = R::to_double(gaps_[j]);
    cp.start_kinds[j] = static_cast<int>(starts_[j]);
  }
  for (auto* o : opt_.observers) o->OnCheckpoint(cp);
}

template <class S>
RunResult Automaton<S>::Run() {
  if (opt_.resume_from) {
    const Checkpoint& cp = *opt_.resume_from;
    clock_ = {cp.clock.period, S(cp.clock.offset)};
    X_ = cp.X.cast<S>();
    V_ = cp.V.cast<S>();
    mode_ = cp.mode;
    gap_ = cp.gap;
    if (mode_ == Mode::kFree)
      flight_start_ = static_cast<FlightStart>(cp.start_kind);
    else
      stick_start_ = static_cast<StickStart>(cp.start_kind);
    chatter_first_ = cp.chatter_first_speed;
    chatter_last_ = cp.chatter_last_speed;
    sample_index_ = cp.sample_index;
    result_.counts = cp.counts;
    result_.chatter = {cp.chatter_predicted, cp.chatter_followed, cp.chatter_max_error};
    active_ = cp.contact >= 0 && cp.contact < static_cast<int>(models_.size()) ? cp.contact : 0;
    loads_.Restore(cp);
    if (cp.held.size() > 1) held_set_ = cp.held;
    if (cp.contact_counts.size() == counts_.size()) counts_ = cp.contact_counts;
    else if (counts_.size() == 1) counts_[0] = cp.counts;
    if (multi()) {
      if (cp.gaps.size() == gaps_.size() && cp.start_kinds.size() == starts_.size()) {
        for (size_t j = 0; j < gaps_.size(); ++j) {
          gaps_[j] = S(cp.gaps[j]);
          starts_[j] = static_cast<FlightStart>(cp.start_kinds[j]);
        }
      } else {  // a checkpoint without them: the gaps of its state
        for (size_t j = 0; j < gaps_.size(); ++j)
          gaps_[j] = (mode_ == Mode::kSticking && static_cast<int>(j) == active_)
                         ? S(0) : models_[j]->ContactDisplacement(X_) - models_[j]->x0;
      }
    }
  } else {
    ClassifyInitialState();
    if (!opt_.observers.empty()) {
      const Sample s{ToClock(clock_), t0_, D(X_, dx_), D(V_, dv_),
                     R::to_double(m_.side * m_.ContactDisplacement(X_)), mode_};
      for (auto* o : opt_.observers) o->OnSection(s);
      if (run_.samples_per_period > 0) {
        for (auto* o : opt_.observers) o->OnSample(s);
        sample_index_ = 1;
      }
    } else if (run_.samples_per_period > 0) {
      sample_index_ = 1;
    }
    if (mode_ == Mode::kSticking && held_set_.empty()) Emit(EventKind::kStick, S(0), S(0));
    for (const int j : held_set_) Emit(EventKind::kStick, S(0), S(0), j);
    Checkpointed();
  }

  const S tiny = S(4) * Eps<S>() * period_;
  int stalled = 0;
  while (clock_.period < run_.periods && result_.status == RunStatus::kOk) {
    if (!Guarded()) break;
    if (StopPolled()) {
      result_.status = RunStatus::kInterrupted;
      result_.message = fmt::format(
          "interrupted at t = {:.10g} (period {}); everything so far is kept, continue with "
          "--resume",
          AbsTime(clock_), clock_.period);
      break;
    }
    const S to_boundary = period_ - clock_.offset;
    SetStickingT<S>* set = mode_ == Mode::kSticking && !held_set_.empty() ? SetEngine() : nullptr;
    if (mode_ == Mode::kSticking && !held_set_.empty() && !set) break;  // failed: reason kept
    PropagatorT<S>& p = set ? *set : (mode_ == Mode::kSticking && Resting()) ? *Resting() : *engine_;
    p.Begin({mode_, Phase(clock_), clock_.offset, X_, V_, gap_, flight_start_, stick_start_, active_,
             multi() ? &gaps_ : nullptr, multi() ? &starts_ : nullptr});
    const ClockT<S> from = clock_;
    // Loads of a phase held on one contact or on a set of contacts at once (docs/loads.md).
    const bool loads = mode_ == Mode::kSticking && held_set_.empty() && opt_.loads && !opt_.observers.empty();
    const bool set_loads = mode_ == Mode::kSticking && !held_set_.empty() && opt_.loads && !opt_.observers.empty();
    if (mode_ == Mode::kSticking && !held_set_.empty() && !set_loads) loads_.Invalidate();
    if (loads || set_loads) loads_.SegmentStart(X_, V_);
    stretch_loads_ = loads && cvode_;
    // The callback captures one pointer, so that std::function keeps it inline (no allocation per
    // segment).
    struct {
      Automaton* self;
      const ClockT<S>* from;
      PropagatorT<S>* p;
    } stretch{this, &from, &p};
    const auto seg = p.Advance(to_boundary, true, [ctx = &stretch](const S& lo, const S& hi) {
      ctx->self->EmitStretch(*ctx->from, *ctx->p, lo, hi);
    });
    stretch_loads_ = false;
    if (seg.end == SegmentEnd::kFailure) {
      if (StopPolled()) continue;  // reported as an interruption at the top of the loop
      Fail(fmt::format("{} (t = {:.17g}, mode {})", seg.message, AbsTime(clock_),
                       mode_ == Mode::kFree ? "free flight" : "sticking"),
           seg.undetermined ? RunStatus::kUndetermined : RunStatus::kNumericalFailure);
      break;
    }
    p.Evaluate(seg.sigma, X_, V_);
    if (loads) loads_.Segment(active_, M(active_), p, Phase(from), seg.sigma, X_, V_);
    if (set_loads)
      loads_.SetSegment(held_set_, models_, Phase(from), seg.sigma, X_, V_,
                        [set](int c) { return SetForce<S>{set, c}; });
    if (multi())
      UpdateGaps(p, seg.sigma);
    else if (mode_ == Mode::kFree)
      gap_ = p.Gap(seg.sigma);
    if (!opt_.observers.empty()) {
      for (auto* o : opt_.observers) o->OnStretch({mode_, R::to_double(seg.sigma), active_});
    }
    AdvanceClock(clock_, seg.sigma, to_boundary, seg.exact_offset);
    CheckSegment(from, seg.sigma);
    if (!Guarded()) break;
    stalled = seg.sigma <= tiny ? stalled + 1 : 0;
    if (stalled > 1000) {
      Fail(fmt::format("no progress at t = {:.17g}: 1000 consecutive events without time "
                       "advancing (degenerate contact)",
                       AbsTime(clock_)));
      break;
    }
    if (seg.end == SegmentEnd::kLimit) {
      if (mode_ == Mode::kFree) flight_start_ = FlightStart::kGeneric;
      if (mode_ == Mode::kSticking) stick_start_ = StickStart::kGeneric;
      if (multi()) starts_.assign(models_.size(), FlightStart::kGeneric);
      Checkpointed();
      continue;
    }
    if (seg.end == SegmentEnd::kContact) {
      if (!(multi() ? OnContactMulti(seg.contact) : OnContact())) break;
      if (grazing_streak_ > 1000) {
        Fail(fmt::format("1000 tangential contacts in a row near t = {:.17g}: the contact is "
                         "degenerate (R ≈ 0 within rounding with the body at rest on the stop){}",
                         AbsTime(clock_),
                         cvode_ ? "; tighten run.rtol or use run.engine = \"exact\""
                                : " (e.g. next to a rising bifurcation); move the parameter slightly"));
        break;
      }
      continue;
    }
    if (set) {
      // Release candidate of a held set: contact c's force reached 0 (MODEL (S4) in
      // docs/contacts_reference.md); it leaves with g = g' = g'' = 0, g''' > 0 under the flow of
      // the others, which stay held.
      const int c = seg.contact;
      const JetT<S> jf = set->Force(c, seg.sigma);
      if (jf.g1 < 0 || (jf.g1 == S(0) && jf.g2 < 0)) {
        ProjectOntoSet(held_set_);
        NotifyReset(ResetKind::kHeldSet, X_, V_);
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
      continue;
    }
    // Release candidate: R reached 0 on the stop.
    const S phase = Phase(clock_);
    const ModelT<S>& held = M(active_);
    if (held.ReactionRate(X_, V_, phase) < 0 || Resting()) {
      held.ProjectOntoStop(X_, V_);
      NotifyReset(ResetKind::kRelease, X_, V_);
      Emit(EventKind::kRelease, S(0), S(0));
      Depart(FlightStart::kAfterRelease);
      gap_ = 0;
    } else {
      stick_start_ = StickStart::kTangent;  // R touches 0 without crossing: stay
    }
  }
  Guarded();
  result_.end = ToClock(clock_);
  result_.t_end = AbsTime(clock_);
  result_.X = X_.template cast<double>();
  result_.V = V_.template cast<double>();
  result_.mode = mode_;
  if (multi()) result_.contact_counts = counts_;
  else result_.contact_counts = {result_.counts};
  result_.solver = engine_->stats();
  return result_;
}

}  // namespace vibro::detail
