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
#include "dynamics/compliant_contact.hpp"
#include "dynamics/cvode_engine.hpp"
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
    // One DOF: the closed-form resting flow (a single harmonic; a sum's release is searched by the
    // engine, docs/harmonics.md).
    if (model.stick_frequencies.size() == 0 && model.harmonics.empty())
      for (const ModelT<S>* k : models_) resting_all_.push_back(std::make_unique<RestingStick<S>>(*k));
    counts_.resize(models_.size());
    loads_.Resize(models_.size());
    BuildCompliant();
    if (multi()) {
      gaps_.assign(models_.size(), S(0));
      starts_.assign(models_.size(), FlightStart::kGeneric);
      last_impact_t_.assign(models_.size(), -std::numeric_limits<double>::infinity());
      last_event_t_.assign(models_.size(), -std::numeric_limits<double>::infinity());
      pair_first_speed_.assign(models_.size(), -1.0);
      const std::vector<ContactSpec> specs = Contacts(scene);
      for (size_t j = 0; j < models_.size(); ++j) {
        if (j >= specs.size()) {
          labels_.push_back(fmt::format("contact {}", j));
          continue;
        }
        // As `vibro simulate` prints it (modal form: the contact's coordinate a_jᵀX).
        const ContactSpec& k = specs[j];
        labels_.push_back(fmt::format("{} {} {}",
                                      scene.modal         ? fmt::format("a{}·X", j)
                                      : k.partner >= 0 ? fmt::format("q{} - q{}", k.dof, k.partner)
                                                       : fmt::format("q{}", k.dof),
                                      k.side == Side::kBelow ? ">=" : "<=", k.position));
      }
    }
    const auto poll = [this] { return StopPolled(); };
    engine_->SetStopPoll(poll);
    if (opt.initial) {
      t0_ = opt.initial->time;
      X_ = opt.initial->X.cast<S>();
      V_ = opt.initial->V.cast<S>();
      if (opt.section_origin) {  // periods counted from the origin: the start is inside one
        t0_ = *opt.section_origin;
        start_offset_ = S(opt.initial->time) - S(t0_);
      }
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
  bool PairChatter(int k);
  bool DecidableBesideHeld(int k);
  bool ImpactWhileHeld(int k);
  // Sticking on two or more contacts at once (docs/contacts.md): the held set's propagator, a
  // contact closing while the set is held, and the acceleration LCP that decides which contacts
  // at zero gap and zero gap velocity stick.
  bool Held(int j) const { return std::find(held_set_.begin(), held_set_.end(), j) != held_set_.end(); }
  SetStickingT<S>* SetEngine();
  SetStickingT<S>* SetEngineFor(const std::vector<int>& set, std::string& why);
  // `resting`: free contacts at zero gap, at rest or closing, that the impact at k reaches (they
  // join its LCP); `was`: the held contacts (the set, or the single held contact).
  bool ImpactWhileSetHeld(int k, const std::vector<int>& was, const std::vector<int>& resting = {});
  std::vector<int> RestingBeside(int k) const;
  bool EnterActiveSet(std::vector<int> Z0, const std::vector<int>& was_held, bool emit_sticks = true);
  void ProjectOntoSet(const std::vector<int>& Z);
  int HeldChatter(int k, const S& speed, const S& floor);
  int TryHeldAccumulation(int k);
  bool SimultaneousImpact(const std::vector<int>& Z);
  S Phase(const ClockT<S>& c) const { return phase0_ + m_.w * c.offset; }
  // sin φ, cos φ of a phase (Real<S>::sin and cos, the same values), kept for the last phase asked:
  // an impact's reaction, its tail prediction and the next flight's start share them.
  const S* SinCos(const S& phase) {
    if (!sincos_valid_ || !(phase == sincos_phase_)) {
      sincos_[0] = R::sin(phase);
      sincos_[1] = R::cos(phase);
      sincos_phase_ = phase;
      sincos_valid_ = true;
    }
    return sincos_;
  }
  double AbsTime(const ClockT<S>& c) const {
    return R::to_double(S(t0_) + S(static_cast<double>(c.period)) * period_ + c.offset);
  }
  Clock ToClock(const ClockT<S>& c) const { return {c.period, R::to_double(c.offset)}; }
  // What may resolve an undetermined sequence: quad precision where it is not already in use (it
  // runs every scene the double engine runs, damped sticking of several modes included).
  // Several contacts: " at contact j (its constraint)", and the held ones; one contact: "".
  std::string AtContact() const {
    if (!multi()) return "";
    std::string s = fmt::format(" at contact {} ({})", active_, labels_[static_cast<size_t>(active_)]);
    if (held_set_.size() > 1) {
      std::string who;
      for (const int j : held_set_) who += (who.empty() ? "" : ", ") + std::to_string(j);
      s += fmt::format(", contacts {} held", who);
    }
    return s;
  }
  std::string UndeterminedHint() const {
    if (std::is_same_v<S, double>)
      return fmt::format("Use run.precision = \"quad\"{}, or move the parameter.",
                         cvode_ ? " with run.engine = \"exact\"" : "");
    return "Move the parameter.";
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
                   bool simultaneous = false, HeldSetCause cause = HeldSetCause::kEntry);
  void EmitStretch(const ClockT<S>& start, PropagatorT<S>& p, const S& lo, const S& hi);
  void AdvanceClock(ClockT<S>& c, const S& sigma, const S& sigma_to_boundary,
                    const S& exact_offset = S(-1)) const;
  void ClassifyInitialState();
  void ClassifyInitialContacts();
  void ReleaseFromSet(const SetStickingT<S>& set, int c, const S& sigma);
  void EnterSticking(StickStart how);
  void Depart(FlightStart how);
  bool OnContact();
  // Compliant stops (docs/compliant.md; dynamics/compliant_contact.hpp, the transitions in
  // dynamics/compliant_transitions.hpp): the contact phase is the mode `sticking` on a compliant
  // contact, its propagator the contact's closed form (CVODE's integration with run.engine =
  // "cvode"); a force-rule exit leaves a relaxing flight.
  void BuildCompliant();
  bool Compliant(int j) const { return M(j).compliant; }
  bool InCompliantPhase() const { return mode_ == Mode::kSticking && held_set_.empty() && Compliant(active_); }
  PropagatorT<S>* CompliantPropagatorNow();
  bool EnterContactPhase(int k);
  bool AfterCompliantSegment(const SegmentResultT<S>& seg, const ClockT<S>& from);
  bool ClassifyInitialCompliant();
  void CompliantEventLoads(Event& e, int contact);
  // The tangent map's notice of a compliant entry or exit (ResetKind::kCompliantEntry/Exit): the
  // state now, `rate` the rate of the surface crossed (entry: ḋ; exit: ġ), the surface's offset.
  void NotifyCompliant(ResetKind kind, int contact, const S& rate, const S& surface, bool relaxing);
  bool TryAccumulation(const S& reaction);
  bool TailClearOfOtherContacts(const S& delta);
  void Checkpointed();
  // A compliant stop's open contact phase and relaxing flight into and out of a checkpoint
  // (dynamics/compliant_transitions.hpp).
  void SaveCompliant(Checkpoint& cp) const;
  void RestoreCompliant(const Checkpoint& cp);
  bool Fail(std::string message, RunStatus status = RunStatus::kNumericalFailure);

  // Physics invariants, checked where they arise (docs/reliability.md): a state below the stop
  // beyond tolerance after a flight or in a sample of one, a sticking state off the stop, a
  // non-finite state, a clock that goes backwards. The first violation is kept and ends the run
  // as a numerical failure naming it (Guarded()); the run is never reported ok.
  S GapTolerance(const Vec& X) const;
  // contact: the contact whose gap it is (several contacts: named in the message), −1 the [stop].
  void CheckFreeGap(const S& gap, const Vec& X, double t, const char* where, int contact = -1);
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
  std::vector<std::string> labels_;  // several contacts: each one's constraint, "q0 - q2 >= -1"
  // Several contacts: impacts alternating between two contacts (PairChatter): the last one's
  // contact and time, how many alternations in a row.
  int pair_last_ = -1, pair_cascade_ = 0;
  double pair_t_ = 0;
  std::vector<double> pair_first_speed_;  // each contact's first closing speed in the cascade (−1: none yet)
  // Several contacts: the impacts (contact, time) since the last event of another kind, the last
  // few (ChatteringTogether).
  std::vector<std::pair<int, double>> recent_impacts_;
  bool ChatteringTogether(int j, int k) const;
  // Several contacts: the runs of impacts (contact, first closing speed) of two coupled contacts
  // whose chattering sequences interleave, each slower than the one before at its contact, with
  // short flights between them (InterleavedChatter); the time of the last impact of the runs.
  struct ChatterRun {
    int contact;
    double speed;
  };
  std::vector<ChatterRun> runs_;
  double runs_t_ = 0;
  static constexpr int kInterleavedRuns = 4;
  static constexpr double kInterleavedResolution = 30;
  std::vector<double> last_event_t_;  // several contacts: each contact's last event time
  bool InterleavedChatter(int k);
  // Whether the predicted accumulation point of contact j's run (the state X, Ẋ there, `held` held
  // after it) is ordered against the next arrival of the contact it interleaves with; false (the
  // run ended undetermined) when that arrival is within the timing resolution (contact_laws.hpp).
  bool AccumulationOrdered(int j, const std::vector<int>& held, const Vec& X, const Vec& V, const S& phase,
                           double t_inf);
  // How many contacts are held (Sample::held).
  int HeldCount() const {
    if (mode_ != Mode::kSticking) return 0;
    return held_set_.empty() ? 1 : static_cast<int>(held_set_.size());
  }
  // Several contacts: each contact's last impact time (a tail beside a recent impact of another
  // contact is not one contact's chattering tail, RecentOtherImpact).
  std::vector<double> last_impact_t_;
  bool RecentOtherImpact(int k, const S& delta) const;
  std::vector<EventCounts> counts_;  // per contact
  S period_;
  double t0_;
  S start_offset_{0};  // SimulationOptions::section_origin: where the start is in period 0
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
  S sincos_[2] = {S(0), S(1)}, sincos_phase_{0};  // SinCos's memory
  bool sincos_valid_ = false;
  Vec tail_w_;  // PredictTail's scratch (no allocation per impact)
  // TryAccumulation's states (no allocation per accepted prediction): at t∞, free at t∞⁻, and the
  // post-impact state the tail starts from (the last two for the resets only).
  Vec jump_X_, jump_V_, jump_X_end_, jump_V_end_, jump_X_k_, jump_V_k_;
  ContactLoadsT<S> loads_;  // impulses, energies, sticking phases (docs/loads.md)
  // Compliant stops: each compliant contact's propagator, its closed form or, with run.engine =
  // "cvode", CVODE's integration of the same law (double only: quad refuses them,
  // docs/compliant.md), the relaxing flight after a force-rule exit (its contact and surface
  // offset), and the open contact phase's account beyond the sticking one.
  using CompliantP = std::conditional_t<std::is_same_v<S, double>, CompliantPhase, PropagatorT<S>>;
  std::vector<std::unique_ptr<CompliantP>> compliant_;
  bool relaxing_ = false;
  int relax_contact_ = -1;
  S relax_y_{0};
  struct CompliantAccount {
    double peak = -std::numeric_limits<double>::infinity(), peak_time = 0, penetration = 0, dissipated = 0;
  };
  std::vector<CompliantAccount> compliant_account_;
  bool stretch_loads_ = false;  // the sticking segment under way searches max R per stretch
  // Some observer reads the resets (Observer::WantsResets): else none is built.
  const bool resets_wanted_ = std::any_of(opt_.observers.begin(), opt_.observers.end(),
                                          [](const Observer* o) { return o->WantsResets(); });
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
  if (m.compliant && (kind == EventKind::kStick || kind == EventKind::kRelease)) CompliantEventLoads(e, contact);
  Count(result_.counts, kind, simultaneous);
  // One contact: its counts are the run's (RunResult::contact_counts is filled at the end).
  if (multi()) Count(counts_[static_cast<size_t>(contact)], kind, simultaneous);
  if (multi() && kind == EventKind::kImpact) last_impact_t_[static_cast<size_t>(contact)] = e.t;
  if (multi() && contact >= 0) last_event_t_[static_cast<size_t>(contact)] = e.t;
  if (multi()) {
    if (kind != EventKind::kImpact) {
      recent_impacts_.clear();
    } else {
      if (recent_impacts_.size() >= 16) recent_impacts_.erase(recent_impacts_.begin());
      recent_impacts_.emplace_back(contact, e.t);
    }
  }
  for (auto* o : opt_.observers) o->OnEvent(e);
}

template <class S>
void Automaton<S>::NotifyReset(ResetKind kind, const Vec& Xb, const Vec& Vb, int contact,
                               bool simultaneous, HeldSetCause cause) {
  if (!resets_wanted_) return;
  if (contact < 0) contact = active_;
  const Reset r{kind, R::to_double(Phase(clock_)), D(Xb, dx_), D(Vb, dv_), D(X_, dx2_), D(V_, dv2_),
                0.0, 0.0, nullptr, nullptr, nullptr, R::to_double(M(contact).ContactVelocity(Vb)),
                contact, simultaneous, cause};
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
      for (size_t j = 0; j < models_.size(); ++j)
        if (!(relaxing_ && static_cast<int>(j) == relax_contact_))
        CheckFreeGap(models_[j]->ContactDisplacement(Xs_) - models_[j]->x0, Xs_,
                     R::to_double(S(t0_) + S(static_cast<double>(k)) * period_), "a section point of a flight",
                     multi() ? static_cast<int>(j) : -1);
    const Sample s{{k, 0.0},
                   R::to_double(S(t0_) + S(static_cast<double>(k)) * period_),
                   D(Xs_, dx_),
                   D(Vs_, dv_),
                   R::to_double(m_.side * m_.ContactDisplacement(Xs_)),
                   mode_,
                   HeldCount()};
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
      for (size_t j = 0; j < models_.size(); ++j)
        if (!(relaxing_ && static_cast<int>(j) == relax_contact_))
        CheckFreeGap(models_[j]->ContactDisplacement(Xs_) - models_[j]->x0, Xs_,
                     R::to_double(S(t0_) + S(static_cast<double>(k)) * period_ + off), "a sample of a flight",
                     multi() ? static_cast<int>(j) : -1);
    const Sample s{{k, R::to_double(off)},
                   R::to_double(S(t0_) + S(static_cast<double>(k)) * period_ + off),
                   D(Xs_, dx_),
                   D(Vs_, dv_),
                   R::to_double(m_.side * m_.ContactDisplacement(Xs_)),
                   mode_,
                   HeldCount()};
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
      if (static_cast<int>(j) != active_ && !(gaps_[j] == S(0) && starts_[j] != FlightStart::kGeneric))
        gaps_[j] = models_[j]->ContactDisplacement(X_) - models_[j]->x0;
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
  if (ClassifyInitialCompliant()) return;
  if (multi()) {
    ClassifyInitialContacts();
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
void Automaton<S>::CheckFreeGap(const S& gap, const Vec& X, double t, const char* where, int contact) {
  if (!violation_.empty() || gap >= -GapTolerance(X)) return;
  if (!R::isfinite(gap)) return;  // a non-finite state is reported by CheckSegment
  const std::string hint = cvode_ ? ": tighten run.rtol and run.atol, or use run.engine = \"exact\"" : "";
  if (contact < 0) {
    violation_ = fmt::format(
        "state below the stop: x_B − x0 = {:.3g} in {} at t = {:.17g} (tolerance {:.3g}); the {} "
        "engine crossed the stop without detecting the contact{}",
        R::to_double(gap), where, t, R::to_double(GapTolerance(X)), cvode_ ? "CVODE" : "exact", hint);
    return;
  }
  violation_ = fmt::format(
      "contact {} ({}) violated: its gap is {:.3g} in {} at t = {:.17g} (tolerance {:.3g}); the {} "
      "engine crossed it without detecting the contact{}",
      contact, labels_[static_cast<size_t>(contact)], R::to_double(gap), where, t,
      R::to_double(GapTolerance(X)), cvode_ ? "CVODE" : "exact", hint);
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
    if (multi()) {
      for (size_t j = 0; j < gaps_.size(); ++j)
        CheckFreeGap(gaps_[j], X_, AbsTime(clock_), "the state at the end of a flight", static_cast<int>(j));
    } else {
      CheckFreeGap(gap_, X_, AbsTime(clock_), "the state at the end of a flight");
    }
  } else if (InCompliantPhase()) {
    // In a compliant stop: the gap is ≤ 0 (within rounding) over the whole contact phase.
    const S off = M(active_).ContactDisplacement(X_) - M(active_).x0;
    if (off > GapTolerance(X_))
      violation_ = fmt::format("contact phase of a compliant stop with the gap open: {:.3g} at t = {:.17g}{}",
                               R::to_double(off), AbsTime(clock_), AtContact());
  } else {
    const S off = M(active_).ContactDisplacement(X_) - M(active_).x0;
    if (R::abs(off) > GapTolerance(X_))
      violation_ = multi()
                       ? fmt::format("sticking state off contact {} ({}): its gap is {:.3g} at t = {:.17g} "
                                     "(tolerance {:.3g})",
                                     active_, labels_[static_cast<size_t>(active_)], R::to_double(off),
                                     AbsTime(clock_), R::to_double(GapTolerance(X_)))
                       : fmt::format("sticking state off the stop: x_B − x0 = {:.3g} at t = {:.17g} "
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
  const S* sc = SinCos(phase_k);
  const TailPrediction<S> tail = PredictTail<S>(m, X_, V_, sc[0], sc[1], chatter_tol_, tail_w_, &phase_k);
  last_tail_ = tail;
  last_jump_failure_.clear();
  if (!tail.accepted) {
    ++result_.chatter.impacts_followed;
    return false;
  }
  const S delta = tail.delta;
  const SegmentStartT<S> start{Mode::kFree, phase_k, clock_.offset, X_, V_, S(0),
                               FlightStart::kAfterImpact, StickStart::kGeneric, active_,
                               nullptr, nullptr, -1, sc};
  // First pass without output: the jump is taken only if R(t∞) > 0 after the projection.
  engine_->Begin(start);
  const auto probe = engine_->Advance(delta, false, {});
  if (probe.end == SegmentEnd::kFailure) {  // a stop request is seen again by the next segment
    if (!probe.stopped) last_jump_failure_ = probe.message;
    return false;
  }
  // The state at t∞ (the engine's scratch: no allocation per prediction), and the free state there
  // before the projection, kept only for the resets.
  Vec& X = jump_X_;
  Vec& V = jump_V_;
  engine_->Evaluate(delta, X, V);
  if (resets_wanted_) {
    jump_X_end_ = X;
    jump_V_end_ = V;
  }
  m.ProjectOntoStop(X, V);
  ClockT<S> end = clock_;
  AdvanceClock(end, delta, period_ - clock_.offset);
  if (!(m.Reaction(X, V, Phase(end)) > 0)) {  // the sequence would not complete: follow it
    ++result_.chatter.impacts_followed;
    return false;
  }
  // Several contacts (MODEL §11.6): the tail holds only if every other gap stays open over it,
  // and no other contact took part in the sequence.
  if (multi() && (RecentOtherImpact(active_, delta) || !TailClearOfOtherContacts(delta))) {
    ++result_.chatter.impacts_followed;
    return false;
  }
  if (multi() && !AccumulationOrdered(active_, {active_}, X, V, Phase(end), AbsTime(end))) return false;
  // Commit: the same flow with dense output, then the state at t∞.
  // (Begin copies the post-impact state; the reset below needs it after X_ has moved to t∞.)
  if (resets_wanted_) {
    jump_X_k_ = X_;
    jump_V_k_ = V_;
  }
  engine_->Begin({Mode::kFree, phase_k, clock_.offset, X_, V_, S(0), FlightStart::kAfterImpact,
                  StickStart::kGeneric, active_, nullptr, nullptr, -1, sc});
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
  if (resets_wanted_) {
    Eigen::VectorXd a, b, c, d, xe, ve;
    const Vec& X_k = jump_X_k_;
    const Vec& V_k = jump_V_k_;
    const Eigen::VectorXd grad = DeltaGradient<S>(m, X_k, V_k, phase_k, tail);
    const Reset jump{ResetKind::kAccumulation, R::to_double(phase_k), D(X_k, a), D(V_k, b),
                     D(X_, c), D(V_, d), R::to_double(delta), R::to_double(reaction),
                     &grad, &D(jump_X_end_, xe), &D(jump_V_end_, ve),
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
  if (Compliant(active_)) return EnterContactPhase(active_);
  const ModelT<S>& m = multi() ? M(active_) : m_;
  // Snap the contact coordinate onto the stop (docs/model.md §8).
  X_ -= m.contact * ((m.ContactDisplacement(X_) - m.x0) / m.s_B);
  gap_ = 0;
  const S phase = Phase(clock_);
  const S* sc = SinCos(phase);  // shared with the tail's prediction and the next flight's Begin
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
    const S Rc = m.ReactionSin(X_, V_, sc[0], &phase);
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
    const S Rc = m.ReactionSin(X_, V_, sc[0], &phase);
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
      const S rate = m.ReactionRateTrig(X_, V_, sc[0], sc[1], &phase);
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
    const S Rc = m.ReactionSin(X_, V_, sc[0], &phase);
    if (Rc > 0) {
      EnterSticking(StickStart::kGeneric);
      NotifyReset(ResetKind::kPlasticStick, Xb, Vb);
      Emit(EventKind::kStick, S(0), S(0));
    } else if (Rc < 0) {
      chatter_first_ = chatter_last_ = 0;
      Depart(FlightStart::kDeparture);
      NotifyReset(ResetKind::kPlasticLeave, Xb, Vb);
    } else if (m.ReactionRateTrig(X_, V_, sc[0], sc[1], &phase) > 0) {
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
  const S Rc = m.ReactionSin(X_, V_, sc[0], &phase);
  NotifyReset(ResetKind::kImpact, X_, Vb);
  Emit(EventKind::kImpact, v_minus, m.ContactVelocity(V_));
  if (accumulating && Rc > 0) {
    if (TryAccumulation(Rc)) return true;
    if (result_.status != RunStatus::kOk) return false;  // its accumulation point is not ordered
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
  SaveCompliant(cp);
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
    RestoreCompliant(cp);
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
    clock_ = {0, start_offset_};
    ClassifyInitialState();
    if (start_offset_ > 0) {
      sample_index_ = 0;  // the start is no section point; samples from the first one after it
    } else if (!opt_.observers.empty()) {
      const Sample s{ToClock(clock_), t0_, D(X_, dx_), D(V_, dv_),
                     R::to_double(m_.side * m_.ContactDisplacement(X_)), mode_, HeldCount()};
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
  long long segments = 0;
  while (clock_.period < run_.periods && result_.status == RunStatus::kOk) {
    if (!Guarded()) break;
    if (opt_.max_segments > 0 && ++segments > opt_.max_segments) {
      Fail(fmt::format("segment budget exhausted at t = {:.17g} (period {}): more than {} flights and held "
                       "phases",
                       AbsTime(clock_), clock_.period, opt_.max_segments));
      break;
    }
    if (StopPolled()) {
      result_.status = RunStatus::kInterrupted;
      // Where what was computed is kept, and how to go on, is the caller's to say
      // (frontend::NoteInterruption): a run without an output file has nothing to resume.
      result_.message = fmt::format("interrupted at t = {:.10g} (period {})", AbsTime(clock_), clock_.period);
      break;
    }
    const S to_boundary = period_ - clock_.offset;
    SetStickingT<S>* set = mode_ == Mode::kSticking && !held_set_.empty() ? SetEngine() : nullptr;
    if (mode_ == Mode::kSticking && !held_set_.empty() && !set) break;  // failed: reason kept
    PropagatorT<S>* compliant = CompliantPropagatorNow();
    PropagatorT<S>& p = set         ? *set
                        : compliant ? *compliant
                        : (mode_ == Mode::kSticking && Resting()) ? *Resting()
                                                                   : *engine_;
    const S phase_now = Phase(clock_);
    p.Begin({mode_, phase_now, clock_.offset, X_, V_, gap_, flight_start_, stick_start_, active_,
             multi() ? &gaps_ : nullptr, multi() ? &starts_ : nullptr, -1, SinCos(phase_now)});
    const ClockT<S> from = clock_;
    // Loads of a phase held on one contact or on a set of contacts at once (docs/loads.md).
    const bool loads = mode_ == Mode::kSticking && held_set_.empty() && !compliant && opt_.loads &&
                       !opt_.observers.empty();
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
      Fail(fmt::format("{} (t = {:.17g}, mode {}{})", seg.message, AbsTime(clock_),
                       mode_ == Mode::kFree ? "free flight" : "sticking", AtContact()),
           seg.undetermined ? RunStatus::kUndetermined : RunStatus::kNumericalFailure);
      break;
    }
    // One contact in free flight: the state and the gap from one pass over the modes.
    const bool free_gap = !multi() && mode_ == Mode::kFree;
    if (free_gap) gap_ = p.EvaluateWithGap(seg.sigma, X_, V_);
    else p.Evaluate(seg.sigma, X_, V_);
    if (loads) loads_.Segment(active_, M(active_), p, Phase(from), seg.sigma, X_, V_);
    if (set_loads)
      loads_.SetSegment(held_set_, models_, Phase(from), seg.sigma, X_, V_,
                        [set](int c) { return SetForce<S>{set, c}; });
    if (multi()) UpdateGaps(p, seg.sigma);
    if (!opt_.observers.empty()) {
      for (auto* o : opt_.observers) o->OnStretch({mode_, R::to_double(seg.sigma), active_, &held_set_});
    }
    AdvanceClock(clock_, seg.sigma, to_boundary, seg.exact_offset);
    if (compliant && mode_ == Mode::kFree && multi())  // a relaxing flight: its contact's gap is to the surface
      gaps_[static_cast<size_t>(relax_contact_)] = p.GapOf(relax_contact_, seg.sigma);
    CheckSegment(from, seg.sigma);
    if (!Guarded()) break;
    stalled = seg.sigma <= tiny ? stalled + 1 : 0;
    if (stalled > 1000) {
      Fail(fmt::format("no progress at t = {:.17g}{}: 1000 consecutive events without time "
                       "advancing (degenerate contact)",
                       AbsTime(clock_), AtContact()));
      break;
    }
    if (compliant) {
      // The compliant contact's own transitions (dynamics/compliant_transitions.hpp).
      if (!AfterCompliantSegment(seg, from)) break;
      // A period boundary (not the end of a relaxing flight inside the period): a checkpoint.
      if (seg.end == SegmentEnd::kLimit && !(seg.sigma < to_boundary)) Checkpointed();
      continue;
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
        Fail(fmt::format("1000 tangential contacts in a row near t = {:.17g}{}: the contact is "
                         "degenerate (R ≈ 0 within rounding with the body at rest on the stop){}.",
                         AbsTime(clock_), AtContact(),
                         cvode_ ? "; tighten run.rtol or use run.engine = \"exact\""
                                : " (e.g. next to a rising bifurcation); move the parameter slightly"));
        break;
      }
      continue;
    }
    if (set) {
      ReleaseFromSet(*set, seg.contact, seg.sigma);
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
  if constexpr (std::is_same_v<S, double>)
    for (const auto& c : compliant_) {  // CVODE's work in the compliant contacts
      if (!c) continue;
      const SolverStats w = c->stats();
      result_.solver.steps += w.steps;
      result_.solver.rhs_evals += w.rhs_evals;
      result_.solver.root_evals += w.root_evals;
      result_.solver.jac_evals += w.jac_evals;
      result_.solver.error_test_failures += w.error_test_failures;
      result_.solver.reinits += w.reinits;
    }
  return result_;
}

}  // namespace vibro::detail

// The contact laws of several contacts and the automaton's transitions that use them.
#include "dynamics/contact_laws.hpp"  // IWYU pragma: export
// The compliant stops' transitions (docs/compliant.md).
#include "dynamics/compliant_transitions.hpp"  // IWYU pragma: export
