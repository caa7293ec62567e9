// The hybrid automaton (see the pseudocode in include/vibro/simulator.hpp).
#include "vibro/simulator.hpp"

#include <cmath>
#include <limits>
#include <memory>

#include <fmt/format.h>

#include "dynamics/engine_factory.hpp"
#include "dynamics/propagator.hpp"

namespace vibro {
namespace {

using detail::FlightStart;
using detail::Propagator;
using detail::SegmentEnd;
using detail::SegmentStart;
using detail::StickStart;

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kTwoPi = 2.0 * M_PI;

// One DOF (no constrained mode): the stuck body rests at x0 and R depends on the phase only, so
// the release phase is closed form (MODEL §4.4, §6.1) and no sticking flow is integrated.
class RestingStick final : public Propagator {
 public:
  explicit RestingStick(const System& sys) : sys_(sys) {}
  void Begin(const SegmentStart& s) override {
    phase_ = s.phase;
    offset_ = s.offset;
    X_ = sys_.stop() * sys_.static_shape();
    V_ = Eigen::VectorXd::Zero(sys_.dof());
  }
  detail::SegmentResult Advance(double sigma_max, bool detect,
                                const detail::StretchCallback& cb) override {
    const double target = detect ? ReleaseOffset() : std::numeric_limits<double>::infinity();
    const bool released = target - offset_ <= sigma_max;
    const double end = released ? target - offset_ : sigma_max;
    if (cb) cb(0.0, end);
    if (!released) return {SegmentEnd::kLimit, end, {}};
    return {SegmentEnd::kRelease, end, {}, target};
  }
  void Evaluate(double, Eigen::VectorXd& X, Eigen::VectorXd& V) const override {
    X = X_;
    V = V_;
  }
  double Gap(double) const override { return 0.0; }

 private:
  // R ∝ ω_1² x0 − F sin φ with F = s_A f: release where F sin φ rises through ω_1² x0, i.e.
  // sin φ_1 = β = ω_1² x0 / F with F cos φ_1 > 0. Never when |β| ≥ 1 (permanent sticking).
  // Returned as the clock offset of the next release (possibly ≥ T, then beyond this period).
  double ReleaseOffset() const {
    const double F = sys_.s_A() * sys_.amplitude();
    const double k = sys_.omega()[0] * sys_.omega()[0] * sys_.stop();
    if (F == 0.0 || std::abs(k) >= std::abs(F)) return std::numeric_limits<double>::infinity();
    const double beta = k / F;
    const double phi1 = std::atan2(beta, std::copysign(std::sqrt(1.0 - beta * beta), F));
    // Offsets o with phase0 + ω o ≡ φ_1 (mod 2π): o_m = (φ_1 − phase0 + 2πm)/ω, the first > now.
    const double w = sys_.frequency();
    const double base = phi1 - (phase_ - w * offset_);
    double m = std::floor((w * offset_ - base) / kTwoPi);
    double o = (base + kTwoPi * m) / w;
    while (o <= offset_) o = (base + kTwoPi * ++m) / w;
    return o;
  }

  const System& sys_;
  double phase_ = 0, offset_ = 0;
  Eigen::VectorXd X_, V_;
};

class Automaton {
 public:
  Automaton(const System& sys, const Scene& scene, const SimulationOptions& opt)
      : sys_(sys),
        run_(scene.run),
        opt_(opt),
        engine_(detail::MakeEngine(sys, scene.run)),
        period_(sys.period()),
        t0_(scene.initial_time),
        phase0_(std::fmod(sys.frequency() * scene.initial_time, kTwoPi)),
        // CVODE resolves impact velocities only to about √rtol of the sequence's first one: below
        // that the accumulation prediction (error O(v²) ~ rtol) is the more accurate treatment.
        switch_ratio_(scene.run.engine == Engine::kCvode
                          ? std::max(scene.run.chatter_switch, std::sqrt(scene.run.rtol))
                          : scene.run.chatter_switch) {
    if (sys.constrained().frequencies.size() == 0) resting_ = std::make_unique<RestingStick>(sys);
    if (opt.initial) {
      t0_ = opt.initial->time;
      phase0_ = std::fmod(sys.frequency() * t0_, kTwoPi);
      X_ = opt.initial->X;
      V_ = opt.initial->V;
    } else {
      const auto init = sys.Initial(scene);
      X_ = init.X;
      V_ = init.V;
    }
  }

  RunResult Run();

 private:
  double Phase(const Clock& c) const { return phase0_ + sys_.frequency() * c.offset; }
  double AbsTime(const Clock& c) const {
    return t0_ + static_cast<double>(c.period) * period_ + c.offset;
  }
  double ContactSpeedFloor() const {
    // Rounding floor of ẋ_B = Σ c_i Ẋ_i (MODEL §5.4).
    return 1e3 * kEps * sys_.contact_shape().cwiseProduct(V_).cwiseAbs().sum();
  }

  void Emit(EventKind kind, double v_before, double v_after);
  void NotifyReset(ResetKind kind, const Eigen::VectorXd& Xb, const Eigen::VectorXd& Vb,
                   double delta = 0.0, double reaction = 0.0) {
    const Reset r{kind, Phase(clock_), Xb, Vb, X_, V_, delta, reaction};
    for (auto* o : opt_.observers) o->OnReset(r);
  }
  void EmitStretch(const Clock& start, Propagator& p, double lo, double hi);
  void AdvanceClock(Clock& c, double sigma, double sigma_to_boundary,
                    double exact_offset = -1.0) const;
  void ClassifyInitialState();
  void EnterSticking(StickStart how);
  void Depart(FlightStart how);
  bool OnContact();
  bool TryAccumulation(double v_minus, double reaction);
  void Checkpointed();
  bool Fail(std::string message);

  const System& sys_;
  const RunSpec& run_;
  const SimulationOptions& opt_;
  std::unique_ptr<Propagator> engine_;
  std::unique_ptr<Propagator> resting_;
  double period_, t0_, phase0_;
  double switch_ratio_;       // chatter switch velocity / first impact speed
  int grazing_streak_ = 0;    // consecutive grazings (a degenerate contact loops on them)

  Clock clock_;
  Eigen::VectorXd X_, V_, Xs_, Vs_;
  Mode mode_ = Mode::kFree;
  double gap_ = 0;
  FlightStart flight_start_ = FlightStart::kGeneric;
  StickStart stick_start_ = StickStart::kGeneric;
  double chatter_first_ = 0, chatter_last_ = 0;
  long long sample_index_ = 0;
  RunResult result_;
};

void Automaton::Emit(EventKind kind, double v_before, double v_after) {
  grazing_streak_ = kind == EventKind::kGrazing ? grazing_streak_ + 1 : 0;
  Event e{kind, clock_, AbsTime(clock_), sys_.ContactDisplacement(X_), v_before, v_after};
  if (kind != EventKind::kImpact && kind != EventKind::kGrazing) e.x_B = sys_.stop();
  auto& c = result_.counts;
  switch (kind) {
    case EventKind::kImpact: ++c.impacts; break;
    case EventKind::kAccumulation: ++c.accumulations; break;
    case EventKind::kStick: ++c.sticks; break;
    case EventKind::kRelease: ++c.releases; break;
    case EventKind::kGrazing: ++c.grazings; break;
  }
  for (auto* o : opt_.observers) o->OnEvent(e);
}

// Dense samples and section points whose times fall in (lo, hi] of a segment started at `start`.
void Automaton::EmitStretch(const Clock& start, Propagator& p, double lo, double hi) {
  const int spp = run_.samples_per_period;
  // Section points: period boundaries t0 + kT.
  for (long long k = start.period + 1;; ++k) {
    const double sigma = static_cast<double>(k - start.period) * period_ - start.offset;
    if (sigma > hi || k > run_.periods) break;
    if (sigma <= lo) continue;
    p.Evaluate(sigma, Xs_, Vs_);
    const Sample s{{k, 0.0}, t0_ + static_cast<double>(k) * period_, Xs_, Vs_,
                   sys_.ContactDisplacement(Xs_), mode_};
    for (auto* o : opt_.observers) o->OnSection(s);
  }
  if (spp <= 0) return;
  const double dt = period_ / spp;
  for (;; ++sample_index_) {
    const long long k = sample_index_ / spp;
    const double off = static_cast<double>(sample_index_ % spp) * dt;
    const double sigma = static_cast<double>(k - start.period) * period_ + off - start.offset;
    if (sigma > hi) break;
    if (sigma < lo) continue;
    if (k >= run_.periods) break;  // the end state is section row `periods`, not a sample
    p.Evaluate(sigma, Xs_, Vs_);
    const Sample s{{k, off}, t0_ + static_cast<double>(k) * period_ + off, Xs_, Vs_,
                   sys_.ContactDisplacement(Xs_), mode_};
    for (auto* o : opt_.observers) o->OnSample(s);
  }
}

void Automaton::AdvanceClock(Clock& c, double sigma, double sigma_to_boundary,
                             double exact_offset) const {
  if (exact_offset >= 0.0 && exact_offset < period_) {
    c.offset = exact_offset;
  } else if (sigma >= sigma_to_boundary) {
    // Exactly at (or, after an accumulation jump, past) the boundary.
    double rest = sigma - sigma_to_boundary;
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

void Automaton::EnterSticking(StickStart how) {
  sys_.ProjectOntoStop(X_, V_);
  gap_ = 0.0;
  mode_ = Mode::kSticking;
  stick_start_ = how;
  chatter_first_ = chatter_last_ = 0.0;
}

void Automaton::Depart(FlightStart how) {
  mode_ = Mode::kFree;
  flight_start_ = how;
}

// A state on the stop at rest (or the start of a run): stick, leave, or decide with Ṙ.
void Automaton::ClassifyInitialState() {
  // Any positive gap is a free flight; a state at (or, by the rounding of a physical-to-modal
  // conversion, within validation tolerance inside) the stop is on it.
  const double xB = sys_.ContactDisplacement(X_);
  if (xB - sys_.stop() > 0) {
    gap_ = xB - sys_.stop();
    Depart(FlightStart::kGeneric);
    return;
  }
  gap_ = 0.0;
  const double vB = sys_.ContactVelocity(V_);
  if (vB > 0) {  // leaving the stop: the gap has a simple zero at σ = 0
    X_ -= sys_.contact() * ((xB - sys_.stop()) / sys_.s_B());
    Depart(FlightStart::kAfterImpact);
    return;
  }
  const double phase = Phase(clock_);
  const double R = sys_.Reaction(X_, V_, phase);
  if (R > 0) {
    EnterSticking(StickStart::kGeneric);
  } else if (R < 0) {
    sys_.ProjectOntoStop(X_, V_);
    Depart(FlightStart::kDeparture);
  } else if (sys_.ReactionRate(X_, V_, phase) >= 0) {
    EnterSticking(StickStart::kRising);
  } else {
    sys_.ProjectOntoStop(X_, V_);
    Depart(FlightStart::kAfterRelease);
  }
}

bool Automaton::Fail(std::string message) {
  result_.status = RunStatus::kNumericalFailure;
  result_.message = std::move(message);
  return false;
}

// MODEL §5.4: predict the accumulation point of a chattering sequence from impact k.
bool Automaton::TryAccumulation(double v_minus, double reaction) {
  const double r = sys_.restitution();
  const double delta = 2.0 * r * std::abs(v_minus) / ((1.0 - r) * sys_.s_B() * reaction);
  const SegmentStart start{Mode::kFree, Phase(clock_), clock_.offset, X_, V_, 0.0,
                           FlightStart::kAfterImpact, StickStart::kGeneric};
  // First pass without output: the jump is taken only if R(t∞) > 0 after the projection.
  engine_->Begin(start);
  const auto probe = engine_->Advance(delta, false, {});
  if (probe.end == SegmentEnd::kFailure) return false;
  Eigen::VectorXd X, V;
  engine_->Evaluate(delta, X, V);
  sys_.ProjectOntoStop(X, V);
  Clock end = clock_;
  AdvanceClock(end, delta, period_ - clock_.offset);
  if (!(sys_.Reaction(X, V, Phase(end)) > 0)) return false;  // incomplete chatter: continue
  // Commit: the same flow with dense output, then the state at t∞.
  const Eigen::VectorXd X_k = X_, V_k = V_;
  engine_->Begin({Mode::kFree, Phase(clock_), clock_.offset, X_k, V_k, 0.0,
                  FlightStart::kAfterImpact, StickStart::kGeneric});
  const Clock from = clock_;
  engine_->Advance(delta, false, [&](double lo, double hi) { EmitStretch(from, *engine_, lo, hi); });
  const double phase_k = Phase(clock_);
  clock_ = end;
  X_ = X;
  V_ = V;
  gap_ = 0.0;
  {
    const Reset jump{ResetKind::kAccumulation, phase_k, X_k, V_k, X_, V_, delta, reaction};
    for (auto* o : opt_.observers) o->OnReset(jump);
  }
  // ẋ_B → 0 at the accumulation point: the remaining impacts are summed into one impulse.
  Emit(EventKind::kAccumulation, 0.0, 0.0);
  mode_ = Mode::kSticking;
  stick_start_ = StickStart::kGeneric;
  chatter_first_ = chatter_last_ = 0.0;
  Emit(EventKind::kStick, 0.0, 0.0);
  return true;
}

// Free flight reached g = 0 at the current state.
bool Automaton::OnContact() {
  // Snap the contact coordinate onto the stop (MODEL §8.12).
  X_ -= sys_.contact() * ((sys_.ContactDisplacement(X_) - sys_.stop()) / sys_.s_B());
  gap_ = 0.0;
  const double phase = Phase(clock_);
  const double v_minus = sys_.ContactVelocity(V_);
  const double floor = ContactSpeedFloor();
  const double r = sys_.restitution();

  if (!(v_minus < -floor)) {
    // Tangential touch (MODEL §2.1): no impact.
    const double R = sys_.Reaction(X_, V_, phase);
    const Eigen::VectorXd Xb = X_, Vb = V_;
    Emit(EventKind::kGrazing, v_minus, v_minus);
    if (R > 0) {
      EnterSticking(StickStart::kGeneric);
      NotifyReset(ResetKind::kPlasticStick, Xb, Vb);
      Emit(EventKind::kStick, 0.0, 0.0);
    } else {
      sys_.ProjectOntoStop(X_, V_);
      const double rate = sys_.ReactionRate(X_, V_, phase);
      if (R < 0) {
        Depart(FlightStart::kDeparture);
        NotifyReset(ResetKind::kGrazing, Xb, Vb);
      } else if (rate < 0) {
        Depart(FlightStart::kAfterRelease);
        NotifyReset(ResetKind::kGrazing, Xb, Vb);
      } else {
        EnterSticking(StickStart::kRising);
        NotifyReset(ResetKind::kPlasticStick, Xb, Vb);
        Emit(EventKind::kStick, 0.0, 0.0);
      }
    }
    return true;
  }

  // Chattering sequence bookkeeping: a sequence is a run of impacts of decreasing speed.
  const double speed = -v_minus;
  if (chatter_last_ == 0.0 || speed > chatter_last_) chatter_first_ = speed;
  chatter_last_ = speed;
  const double v_switch = std::max(switch_ratio_ * chatter_first_, floor);
  const bool in_switch = speed < v_switch && chatter_first_ > speed;

  const bool plastic =
      r == 0.0 || (run_.chatter == ChatterTreatment::kThreshold && in_switch);
  if (plastic) {
    // MODEL §4.4: plastic impact; stick if R > 0, leave at zero velocity if R < 0, decide with Ṙ
    // if R = 0.
    const Eigen::VectorXd Xb = X_, Vb = V_;
    sys_.ProjectOntoStop(X_, V_);
    Emit(EventKind::kImpact, v_minus, 0.0);
    const double R = sys_.Reaction(X_, V_, phase);
    if (R > 0) {
      EnterSticking(StickStart::kGeneric);
      NotifyReset(ResetKind::kPlasticStick, Xb, Vb);
      Emit(EventKind::kStick, 0.0, 0.0);
    } else if (R < 0) {
      chatter_first_ = chatter_last_ = 0.0;
      Depart(FlightStart::kDeparture);
      NotifyReset(ResetKind::kPlasticLeave, Xb, Vb);
    } else if (sys_.ReactionRate(X_, V_, phase) > 0) {
      EnterSticking(StickStart::kRising);
      NotifyReset(ResetKind::kPlasticStick, Xb, Vb);
      Emit(EventKind::kStick, 0.0, 0.0);
    } else {
      chatter_first_ = chatter_last_ = 0.0;
      Depart(FlightStart::kAfterRelease);
      NotifyReset(ResetKind::kPlasticLeave, Xb, Vb);
    }
    return true;
  }

  // Restitution (MODEL eq. 12). R is that of the post-impact state (with damping it depends on
  // Ẋ; the difference is O(v), within the O(v²) of the accumulation prediction).
  const Eigen::VectorXd Vb = V_;
  sys_.ApplyImpact(V_, r);
  const double R = sys_.Reaction(X_, V_, phase);
  NotifyReset(ResetKind::kImpact, X_, Vb);
  Emit(EventKind::kImpact, v_minus, sys_.ContactVelocity(V_));
  if (run_.chatter == ChatterTreatment::kAccumulation && r < 1.0 && in_switch && R > 0) {
    if (TryAccumulation(v_minus, R)) return true;
  }
  if (run_.chatter == ChatterTreatment::kNone && R > 0) {
    // Impacts followed one by one: stop once the next flight is below the resolution.
    const double next_flight = 2.0 * r * speed / (sys_.s_B() * R);
    if (r * speed <= floor || next_flight <= 4.0 * kEps * period_)
      return Fail(fmt::format(
          "chattering: impacts accumulate near t = {:.17g} and cannot be followed one by one "
          "(contact speed {:.3g}, next flight {:.3g}; run.chatter = \"none\"). Use run.chatter = "
          "\"accumulation\" (or \"threshold\")",
          AbsTime(clock_), r * speed, next_flight));
  }
  Depart(FlightStart::kAfterImpact);
  return true;
}

void Automaton::Checkpointed() {
  const Checkpoint cp{clock_,
                      X_,
                      V_,
                      mode_,
                      gap_,
                      static_cast<int>(mode_ == Mode::kFree ? static_cast<int>(flight_start_)
                                                            : static_cast<int>(stick_start_)),
                      chatter_first_,
                      chatter_last_,
                      sample_index_,
                      result_.counts};
  for (auto* o : opt_.observers) o->OnCheckpoint(cp);
}

RunResult Automaton::Run() {
  if (opt_.resume_from) {
    const Checkpoint& cp = *opt_.resume_from;
    clock_ = cp.clock;
    X_ = cp.X;
    V_ = cp.V;
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
  } else {
    ClassifyInitialState();
    const Sample s{clock_, t0_, X_, V_, sys_.ContactDisplacement(X_), mode_};
    for (auto* o : opt_.observers) o->OnSection(s);
    if (run_.samples_per_period > 0) {
      for (auto* o : opt_.observers) o->OnSample(s);
      sample_index_ = 1;
    }
    if (mode_ == Mode::kSticking) Emit(EventKind::kStick, 0.0, 0.0);
    Checkpointed();
  }

  int stalled = 0;
  while (clock_.period < run_.periods) {
    if (opt_.stop_requested && opt_.stop_requested->load(std::memory_order_relaxed)) {
      result_.status = RunStatus::kInterrupted;
      result_.message = fmt::format(
          "interrupted at t = {:.10g} (period {}); everything so far is kept, continue with "
          "--resume",
          AbsTime(clock_), clock_.period);
      break;
    }
    const double to_boundary = period_ - clock_.offset;
    Propagator& p = (mode_ == Mode::kSticking && resting_) ? *resting_ : *engine_;
    p.Begin({mode_, Phase(clock_), clock_.offset, X_, V_, gap_, flight_start_, stick_start_});
    const Clock from = clock_;
    const auto seg = p.Advance(to_boundary, true,
                               [&](double lo, double hi) { EmitStretch(from, p, lo, hi); });
    if (seg.end == SegmentEnd::kFailure) {
      Fail(fmt::format("{} (t = {:.17g}, mode {})", seg.message, AbsTime(clock_),
                       mode_ == Mode::kFree ? "free flight" : "sticking"));
      break;
    }
    p.Evaluate(seg.sigma, X_, V_);
    if (mode_ == Mode::kFree) gap_ = p.Gap(seg.sigma);
    for (auto* o : opt_.observers) o->OnStretch({mode_, seg.sigma});
    AdvanceClock(clock_, seg.sigma, to_boundary, seg.exact_offset);
    stalled = seg.sigma <= 4.0 * kEps * period_ ? stalled + 1 : 0;
    if (stalled > 1000) {
      Fail(fmt::format("no progress at t = {:.17g}: 1000 consecutive events without time "
                       "advancing (degenerate contact)",
                       AbsTime(clock_)));
      break;
    }
    if (seg.end == SegmentEnd::kLimit) {
      if (mode_ == Mode::kFree) flight_start_ = FlightStart::kGeneric;
      if (mode_ == Mode::kSticking) stick_start_ = StickStart::kGeneric;
      Checkpointed();
      continue;
    }
    if (seg.end == SegmentEnd::kContact) {
      if (!OnContact()) break;
      if (grazing_streak_ > 1000) {
        Fail(fmt::format("1000 tangential contacts in a row near t = {:.17g}: the contact is "
                         "degenerate (R ≈ 0 within rounding with the body at rest on the stop){}",
                         AbsTime(clock_),
                         run_.engine == Engine::kCvode
                             ? "; tighten run.rtol or use run.engine = \"exact\""
                             : " (e.g. next to a rising bifurcation); move the parameter slightly"));
        break;
      }
      continue;
    }
    // Release candidate: R reached 0 on the stop.
    const double phase = Phase(clock_);
    if (sys_.ReactionRate(X_, V_, phase) < 0 || resting_) {
      sys_.ProjectOntoStop(X_, V_);
      NotifyReset(ResetKind::kRelease, X_, V_);
      Emit(EventKind::kRelease, 0.0, 0.0);
      Depart(FlightStart::kAfterRelease);
      gap_ = 0.0;
    } else {
      stick_start_ = StickStart::kTangent;  // R touches 0 without crossing: stay
    }
  }
  result_.end = clock_;
  result_.t_end = AbsTime(clock_);
  result_.X = X_;
  result_.V = V_;
  result_.mode = mode_;
  result_.solver = engine_->stats();
  return result_;
}

}  // namespace

const char* ToString(RunStatus s) {
  switch (s) {
    case RunStatus::kOk: return "ok";
    case RunStatus::kNumericalFailure: return "numerical-failure";
    case RunStatus::kInterrupted: return "interrupted";
  }
  return "?";
}

const char* ToString(EventKind k) {
  switch (k) {
    case EventKind::kImpact: return "impact";
    case EventKind::kAccumulation: return "accumulation";
    case EventKind::kStick: return "stick";
    case EventKind::kRelease: return "release";
    case EventKind::kGrazing: return "grazing";
  }
  return "?";
}

RunResult Simulate(const System& system, const Scene& scene, const SimulationOptions& options) {
  Automaton a(system, scene, options);
  return a.Run();
}

}  // namespace vibro
