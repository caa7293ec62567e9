// Hardening (docs/reliability.md): classification that does not invent periods, CVODE starts on
// the stop that must not tunnel, and stop requests seen inside a CVODE segment.
#include <atomic>
#include <cmath>

#include <gtest/gtest.h>

#include "dynamics/automaton.hpp"
#include "dynamics/cvode_engine.hpp"
#include "dynamics/engine_factory.hpp"
#include "dynamics/exact_engine.hpp"
#include "dynamics/exact_engine_quad.hpp"
#include "support.hpp"
#include "vibro/attractor.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/simulator.hpp"
#include "vibro/studies.hpp"

namespace vibro {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;

// A 2-DOF modal structure; the recorder only needs its forcing period and the tolerances.
Scene TwoDof(double w) {
  Scene s;
  s.modal = ModalStructureSpec{Eigen::Vector2d(1.0, 2.7), Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(1.0, 1.0)};
  s.damping_ratios = Eigen::Vector2d(0.01, 0.01);
  s.stop_position = -100.0;  // never reached: no contact
  s.frequency = w;
  s.amplitude = 0.1;
  return s;
}

void Section(AttractorRecorder& rec, const System& sys, long long k, const Eigen::VectorXd& z, Mode mode) {
  const Eigen::VectorXd X = z.head(2), V = z.tail(2);
  rec.OnSection({{k, 0.0}, static_cast<double>(k) * sys.period(), X, V, sys.ContactDisplacement(X), mode,
                 mode == Mode::kSticking ? 1 : 0});
}

// Section points of a forced damped response: a period-1 steady state z_p plus a free transient
// that decays by 0.96 per period and turns by θ = 2π/3 + 1e-9 per period, so that every 3 periods
// it comes back nearly in phase (aliasing). With the amplitude a_k = A·0.96^k:
//   |z_k − z_{k−3}| ≈ a_k |0.96³ − 1| ≈ 0.115 a_k,  |z_k − z_{k−1}| ≈ a_k |0.96 e^{iθ} − 1| ≈ 1.68 a_k.
// At a_K = 3e-7 the 3-period repeat is within period_tolerance = 1e-7 but the 1-period one is not:
// a repeat test alone says "period 3". The motion is the steady state (period 1) plus a transient
// that has not decayed: not periodic yet; once a_K < 1e-12 it is period 1.
Eigen::VectorXd Aliased(long long k, double amplitude_at_K, long long K) {
  const double theta = kTwoPi / 3 + 1e-9;
  const double a = amplitude_at_K * std::pow(0.96, static_cast<double>(k - K));
  Eigen::VectorXd z(4);
  z << 0.5 + a * std::cos(theta * static_cast<double>(k)), 0.2 + a * std::sin(theta * static_cast<double>(k)),
      -0.3 + 0.5 * a * std::cos(theta * static_cast<double>(k) + 1.0), 0.1 - 0.7 * a * std::sin(theta * static_cast<double>(k));
  return z;
}

TEST(Hardening, DecayingFreeTransientIsNeverPeriodic) {
  const Scene scene = TwoDof(1.3);
  const System sys(scene);
  AttractorRecorder rec(sys, scene);
  const long long K = 400;
  for (long long k = 0; k <= K; ++k) Section(rec, sys, k, Aliased(k, 3e-7, K), Mode::kFree);
  // Precondition: the aliasing is there (the last 3 section points repeat within the tolerance).
  double d3 = 0;
  for (long long j = 0; j < 3; ++j) {
    const Eigen::VectorXd a = Aliased(K - j, 3e-7, K), b = Aliased(K - j - 3, 3e-7, K);
    d3 = std::max(d3, (a - b).cwiseAbs().maxCoeff() / (1 + std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff())));
  }
  ASSERT_LT(d3, scene.run.period_tolerance);
  const Attractor a = rec.Classify();
  EXPECT_EQ(a.kind, "not-periodic");
  EXPECT_FALSE(a.period.has_value());

  // The same response 500 periods later: the transient (3e-7 · 0.96^500 ≈ 4e-16) has decayed.
  AttractorRecorder later(sys, scene);
  for (long long k = 0; k <= K + 500; ++k) Section(later, sys, k, Aliased(k, 3e-7, K), Mode::kFree);
  const Attractor b = later.Classify();
  EXPECT_EQ(b.kind, "no-contact-periodic");
  ASSERT_TRUE(b.period.has_value());
  EXPECT_EQ(*b.period, 1);
}

// The same aliasing on short records (a study cell that ends after fewer periods than the
// 4·max_period + 2 = 130 section points a full record holds): never periodic while the transient
// is there, whatever the length of the record.
TEST(Hardening, DecayingFreeTransientOnAShortRecordIsNeverPeriodic) {
  const Scene scene = TwoDof(1.3);
  const System sys(scene);
  for (long long K : {12LL, 20LL, 40LL, 100LL}) {
    AttractorRecorder rec(sys, scene);
    for (long long k = 0; k <= K; ++k) Section(rec, sys, k, Aliased(k, 3e-7, K), Mode::kFree);
    double d3 = 0;
    for (long long j = 0; j < 3; ++j) {
      const Eigen::VectorXd a = Aliased(K - j, 3e-7, K), b = Aliased(K - j - 3, 3e-7, K);
      d3 = std::max(d3, (a - b).cwiseAbs().maxCoeff() / (1 + std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff())));
    }
    ASSERT_LT(d3, scene.run.period_tolerance) << "K = " << K;
    const Attractor a = rec.Classify();
    EXPECT_EQ(a.kind, "not-periodic") << "K = " << K;
    EXPECT_FALSE(a.period.has_value()) << "K = " << K;
  }
}

// Identical section points every period (what a contracting orbit shows between its sticking
// phases), one impact at mid-period, and a sticking phase [0.1 T, 0.3 T] every 7th period: the
// motion has period 7 and sticking fraction 0.2/7, whether the record ends just after a sticking
// period or not (the last two periods alike must not make it "period 1").
TEST(Hardening, EventLogOfTheWholeWindowMustRepeat) {
  const Scene scene = TwoDof(1.3);
  const System sys(scene);
  const double T = sys.period();
  const Eigen::VectorXd z = (Eigen::VectorXd(4) << 0.4, 0.1, -0.2, 0.3).finished();
  for (long long K : {300LL, 301LL, 302LL, 306LL}) {
    AttractorRecorder rec(sys, scene);
    for (long long k = 0; k <= K; ++k) {
      Section(rec, sys, k, z, Mode::kFree);
      if (k == K) break;
      if (k % 7 == 3) {
        rec.OnEvent({EventKind::kStick, {k, 0.1 * T}, (static_cast<double>(k) + 0.1) * T, 1.0, 0.0, 0.0});
        rec.OnEvent({EventKind::kRelease, {k, 0.3 * T}, (static_cast<double>(k) + 0.3) * T, 1.0, 0.0, 0.0});
      }
      rec.OnEvent({EventKind::kImpact, {k, 0.5 * T}, (static_cast<double>(k) + 0.5) * T, 1.0, -0.2, 0.15});
    }
    const Attractor a = rec.Classify();
    ASSERT_TRUE(a.period.has_value()) << "K = " << K;
    EXPECT_EQ(*a.period, 7) << "K = " << K;
    EXPECT_EQ(a.kind, "sticking-periodic") << "K = " << K;
    ASSERT_TRUE(a.sticking_fraction.has_value());
    EXPECT_NEAR(*a.sticking_fraction, 0.2 / 7, 1e-12) << "K = " << K;
  }
}

// The event log is bounded (issue 38: a tiny clearance gives 10⁹ impacts per time unit): the
// motion that sticks every 7 periods, now with 200 impacts a period. With room for 40 periods of
// events the oldest are dropped and the classification is that of the whole record (period 7,
// sticking fraction 0.2/7); with room for only 15 periods (fewer than the three windows of 7 a
// period needs) or less than one period, no period is claimed: the kept record is too short,
// and never a wrong one (period 1 from two alike periods).
TEST(Hardening, BoundedEventLogClassifiesOnlyWholePeriods) {
  const Scene scene = TwoDof(1.3);
  const System sys(scene);
  const double T = sys.period();
  const Eigen::VectorXd z = (Eigen::VectorXd(4) << 0.4, 0.1, -0.2, 0.3).finished();
  constexpr int kImpacts = 200;
  const auto run = [&](size_t max_events, long long K, AttractorRecorder& rec) {
    rec.set_max_events(max_events);
    for (long long k = 0; k <= K; ++k) {
      Section(rec, sys, k, z, Mode::kFree);
      if (k == K) break;
      const auto kd = static_cast<double>(k);
      if (k % 7 == 3) {
        rec.OnEvent({EventKind::kStick, {k, 0.1 * T}, (kd + 0.1) * T, 1.0, 0.0, 0.0});
        rec.OnEvent({EventKind::kRelease, {k, 0.3 * T}, (kd + 0.3) * T, 1.0, 0.0, 0.0});
      }
      for (int i = 0; i < kImpacts; ++i) {
        const double s = (0.4 + 0.5 * i / kImpacts) * T;
        rec.OnEvent({EventKind::kImpact, {k, s}, kd * T + s, 1.0, -0.2, 0.15});
      }
    }
  };
  for (long long K : {300LL, 301LL, 306LL}) {
    AttractorRecorder rec(sys, scene);
    run(40 * kImpacts, K, rec);
    EXPECT_GT(rec.events_dropped(), 0) << "K = " << K;
    const Attractor a = rec.Classify();
    ASSERT_TRUE(a.period.has_value()) << "K = " << K;
    EXPECT_EQ(*a.period, 7) << "K = " << K;
    EXPECT_EQ(a.kind, "sticking-periodic") << "K = " << K;
    ASSERT_TRUE(a.sticking_fraction.has_value());
    EXPECT_NEAR(*a.sticking_fraction, 0.2 / 7, 1e-12) << "K = " << K;
  }
  for (size_t room : {size_t{15 * kImpacts}, size_t{kImpacts / 2}, size_t{1}}) {
    AttractorRecorder rec(sys, scene);
    run(room, 301, rec);
    const Attractor a = rec.Classify();
    EXPECT_FALSE(a.period.has_value()) << "room " << room << ", period " << a.period.value_or(0);
    EXPECT_EQ(a.kind, "not-periodic") << "room " << room;
  }
  // Unbounded by default for every record that fits in 256 MB.
  EXPECT_GE(AttractorRecorder::kDefaultMaxEvents * sizeof(Event), size_t{250} << 20);
}

// Studies classify short records (a cell stopped early, fewer than the 4·max_period + 1 = 129
// periods the recorder can hold): the motion that sticks every 7 periods is never "period 1"
// there either: it is period 7 once the record holds three windows of 7 periods (22 section
// points), and not periodic before.
TEST(Hardening, ShortRecordsDoNotInventPeriods) {
  const Scene scene = TwoDof(1.3);
  const System sys(scene);
  const double T = sys.period();
  const Eigen::VectorXd z = (Eigen::VectorXd(4) << 0.4, 0.1, -0.2, 0.3).finished();
  for (long long K = 8; K <= 40; ++K) {
    AttractorRecorder rec(sys, scene);
    for (long long k = 0; k <= K; ++k) {
      Section(rec, sys, k, z, Mode::kFree);
      if (k == K) break;
      if (k % 7 == 3) {
        rec.OnEvent({EventKind::kStick, {k, 0.1 * T}, (static_cast<double>(k) + 0.1) * T, 1.0, 0.0, 0.0});
        rec.OnEvent({EventKind::kRelease, {k, 0.3 * T}, (static_cast<double>(k) + 0.3) * T, 1.0, 0.0, 0.0});
      }
      rec.OnEvent({EventKind::kImpact, {k, 0.5 * T}, (static_cast<double>(k) + 0.5) * T, 1.0, -0.2, 0.15});
    }
    const Attractor a = rec.Classify();
    if (K + 1 > 21) {
      ASSERT_TRUE(a.period.has_value()) << "K = " << K;
      EXPECT_EQ(*a.period, 7) << "K = " << K;
      EXPECT_NEAR(*a.sticking_fraction, 0.2 / 7, 1e-12) << "K = " << K;
    } else {
      EXPECT_FALSE(a.period.has_value()) << "K = " << K << ", period " << a.period.value_or(0);
      EXPECT_GE(*a.sticking_fraction, 0.0);
      EXPECT_LE(*a.sticking_fraction, 1.0);
    }
  }
}

// A sweep's runs hold a full record whatever run.periods says (the decay test needs it): a sweep
// of the free 2-DOF structure with run.periods = 10 classifies each value from 4·max_period + 1
// periods, which the section points it keeps show (record = 200 > 129 points asked, 129 + 1 given).
TEST(Hardening, SweepRunsHoldAFullRecord) {
  Scene scene = TwoDof(1.3);
  scene.run.periods = 10;
  SweepRequest req;
  req.scene_at = [&](double f) {
    Scene s = scene;
    s.amplitude = f;
    return s;
  };
  req.from = 0.1;
  req.to = 0.2;
  req.steps = 1;
  req.record = 200;
  req.both_ways = false;
  const auto points = Sweep(req);
  ASSERT_EQ(points.size(), 2u);
  for (const auto& p : points) {
    EXPECT_EQ(p.x_B.size(), static_cast<size_t>(4 * scene.run.max_period + 2));
    EXPECT_EQ(p.status, "ok");
  }
}

// A motion that never repeats, stuck from period 70.5 to 199.5 (a phase begun before the
// analysed record of 4·max_period + 1 = 129 periods, 71..200): the time on the stop inside the
// record is 199.5 − 71 = 128.5 periods, a fraction 128.5/129 (not 129 periods over a window of
// the last max_period periods, > 1).
TEST(Hardening, StickingFractionOfNonPeriodicMotionIsAWholeWindowAverage) {
  const Scene scene = TwoDof(1.3);
  const System sys(scene);
  const double T = sys.period();
  AttractorRecorder rec(sys, scene);
  const long long K = 200;
  for (long long k = 0; k <= K; ++k) {
    Eigen::VectorXd z(4);
    z << 0.3 * std::sin(1.7 * static_cast<double>(k)), 0.2 * std::cos(2.3 * static_cast<double>(k)),
        0.1 * std::sin(0.9 * static_cast<double>(k)), 0.05;
    Section(rec, sys, k, z, k > 70 && k < 200 ? Mode::kSticking : Mode::kFree);
    if (k == 70) rec.OnEvent({EventKind::kStick, {k, 0.5 * T}, (static_cast<double>(k) + 0.5) * T, 1.0, 0.0, 0.0});
    if (k == 199) rec.OnEvent({EventKind::kRelease, {k, 0.5 * T}, (static_cast<double>(k) + 0.5) * T, 1.0, 0.0, 0.0});
  }
  const Attractor a = rec.Classify();
  EXPECT_EQ(a.kind, "not-periodic");
  ASSERT_TRUE(a.sticking_fraction.has_value());
  const long long record = 4 * scene.run.max_period + 1;  // periods between the sections kept
  EXPECT_NEAR(*a.sticking_fraction, (199.5 - static_cast<double>(K - record)) / static_cast<double>(record), 1e-12);
  EXPECT_LE(*a.sticking_fraction, 1.0);
}

// CVODE: a stop request ends a segment that would otherwise run on (the flag is polled at every
// step), with `stopped` set; without it the same flight ends at the stop.
TEST(Hardening, CvodeSegmentSeesTheStopFlag) {
  Scene s = test::OneDof(0.75, 2.8, 1.2);
  s.run.engine = Engine::kCvode;
  const System sys(s);
  detail::CvodeEngine engine(sys, s.run);
  const Eigen::VectorXd X = Eigen::VectorXd::Constant(1, 2.0), V = Eigen::VectorXd::Zero(1);
  std::atomic<bool> stop{true};
  engine.SetStopPoll([&stop] { return stop.load(); });
  engine.Begin({Mode::kFree, 0.0, 0.0, X, V, 1.0, detail::FlightStart::kGeneric, detail::StickStart::kGeneric});
  const auto stopped = engine.Advance(1e6, true, {});
  EXPECT_EQ(stopped.end, detail::SegmentEnd::kFailure);
  EXPECT_TRUE(stopped.stopped);
  stop = false;
  engine.Begin({Mode::kFree, 0.0, 0.0, X, V, 1.0, detail::FlightStart::kGeneric, detail::StickStart::kGeneric});
  const auto flew = engine.Advance(1e6, true, {});
  EXPECT_EQ(flew.end, detail::SegmentEnd::kContact);
  EXPECT_FALSE(flew.stopped);
  EXPECT_NEAR(engine.Gap(flew.sigma), 0.0, 1e-8);
}

// Leaving the stop at ẋ_B = 5e-324 (or 1e-300) with the body pushed into it: the flight lasts
// about 2ẋ_B/|ẍ_B|, far below the clock's resolution, so the state touches the stop at once and
// sticks. CVODE used to miss the crossing (g(t_lo)·g(t_hi) underflowed to −0) and let the body fall
// through the stop with status ok. The exact engine is the reference: same attractor, and no
// sample of the CVODE run below the stop.
TEST(Hardening, CvodeStartLeavingTheStopByAHairDoesNotTunnel) {
  for (double v0 : {5e-324, 1e-300, 1e-20}) {
    Scene s = test::OneDof(0.75, 2.8, 1.2, 1.0, 30);
    s.initial_displacement = Eigen::VectorXd::Constant(1, 1.0);
    s.initial_velocity = Eigen::VectorXd::Constant(1, v0);
    s.run.samples_per_period = 64;
    const System sys(s);
    test::Log exact_log, cvode_log;
    AttractorRecorder exact_rec(sys, s), cvode_rec(sys, s);
    SimulationOptions eo, co;
    eo.observers = {&exact_log, &exact_rec};
    co.observers = {&cvode_log, &cvode_rec};
    const RunResult exact = Simulate(sys, s, eo);
    Scene c = s;
    c.run.engine = Engine::kCvode;
    c.run.rtol = 1e-11;
    const RunResult cvode = Simulate(sys, c, co);
    ASSERT_EQ(exact.status, RunStatus::kOk) << exact.message;
    ASSERT_EQ(cvode.status, RunStatus::kOk) << cvode.message;
    double lowest = INFINITY;
    for (const auto& row : cvode_log.samples) lowest = std::min(lowest, row.x_B);
    EXPECT_GE(lowest, s.stop_position - 1e-9) << "v0 = " << v0;
    const Attractor ae = exact_rec.Classify(), ac = cvode_rec.Classify();
    EXPECT_EQ(ac.kind, ae.kind) << "v0 = " << v0;
    EXPECT_EQ(ac.period, ae.period) << "v0 = " << v0;
    ASSERT_TRUE(ae.sticking_fraction && ac.sticking_fraction);
    EXPECT_NEAR(*ac.sticking_fraction, *ae.sticking_fraction, 1e-6) << "v0 = " << v0;
  }
}


// ---- physics invariants guarded in the automaton (a test seam: a broken engine) ----

enum class Fault { kNone, kBelowStop, kOffTheStop, kBackwards, kNotFinite };

// A real engine whose results are corrupted from its `after`-th segment on: the flight state
// pushed 0.5 below the stop, the sticking state lifted 0.5 off it, a segment that ends before it
// began, or a non-finite state. What a faulty engine (or a bug in one) would hand the automaton.
template <class S>
class BrokenEngine final : public detail::PropagatorT<S> {
 public:
  using Vec = typename detail::PropagatorT<S>::Vec;
  BrokenEngine(std::unique_ptr<detail::PropagatorT<S>> inner, const detail::ModelT<S>& m, Fault fault, int after)
      : inner_(std::move(inner)), m_(m), fault_(fault), after_(after) {}
  void Begin(const detail::SegmentStartT<S>& s) override {
    ++segments_;
    mode_ = s.mode;
    inner_->Begin(s);
  }
  detail::SegmentResultT<S> Advance(S sigma_max, bool detect, const detail::StretchCallbackT<S>& cb) override {
    auto r = inner_->Advance(sigma_max, detect, cb);
    if (Broken() && fault_ == Fault::kBackwards) r.sigma = -S(0.25) * m_.period;
    return r;
  }
  void Evaluate(S sigma, Vec& X, Vec& V) const override {
    inner_->Evaluate(sigma, X, V);
    if (!Broken()) return;
    if (fault_ == Fault::kBelowStop && mode_ == Mode::kFree) X -= m_.contact * (S(0.5) / m_.s_B);
    if (fault_ == Fault::kOffTheStop && mode_ == Mode::kSticking) X += m_.contact * (S(0.5) / m_.s_B);
    if (fault_ == Fault::kNotFinite) X[0] = S(std::numeric_limits<double>::quiet_NaN());
  }
  S Gap(S sigma) const override {
    const S g = inner_->Gap(sigma);
    return Broken() && fault_ == Fault::kBelowStop ? S(g - S(0.5)) : g;
  }

 private:
  bool Broken() const { return fault_ != Fault::kNone && segments_ > after_; }
  std::unique_ptr<detail::PropagatorT<S>> inner_;
  const detail::ModelT<S>& m_;
  Fault fault_;
  int after_;
  int segments_ = 0;
  Mode mode_ = Mode::kFree;
};

// The 2-DOF chain (free flights, chattering, and sticking phases integrated by the engine: mass 1
// moves while mass 2 is stuck) with the exact engine in double or quad, or CVODE, its engine
// broken after `after` segments.
template <class S>
RunResult RunBroken(Fault fault, int after, Engine engine, std::vector<Observer*> observers = {}) {
  Scene s = LoadScene(std::string(VIBRO_SCENES_DIR) + "/chain2.toml", {"run.periods=30", "run.samples_per_period=16"}).scene;
  s.run.engine = engine;
  const System sys(s);
  const detail::ModelT<S> model(sys);
  std::unique_ptr<detail::PropagatorT<S>> inner;
  if constexpr (std::is_same_v<S, double>)
    inner = detail::MakeEngine(sys, model, s.run);
  else
    inner = std::make_unique<detail::ExactEngineT<S>>(sys, model);
  SimulationOptions opt;
  opt.observers = std::move(observers);
  detail::Automaton<S> a(sys, model, s, opt, std::make_unique<BrokenEngine<S>>(std::move(inner), model, fault, after));
  return a.Run();
}

template <class S>
void ExpectInvariantsGuarded(Engine engine) {
  test::Log log;
  const RunResult healthy = RunBroken<S>(Fault::kNone, 0, engine, {&log});
  ASSERT_EQ(healthy.status, RunStatus::kOk) << healthy.message;  // the seam itself changes nothing
  ASSERT_GT(healthy.counts.sticks, 5);
  ASSERT_FALSE(log.samples.empty());
  const struct {
    Fault fault;
    const char* cause;
  } cases[] = {{Fault::kBelowStop, "state below the stop"},
               {Fault::kOffTheStop, "sticking state off the stop"},
               {Fault::kBackwards, "non-monotone clock"},
               {Fault::kNotFinite, "state not finite"}};
  for (const auto& c : cases) {
    for (const bool observed : {false, true}) {  // samples checked too, or segment ends only
      test::Log seen;
      const RunResult r = RunBroken<S>(c.fault, 12, engine, observed ? std::vector<Observer*>{&seen}
                                                                     : std::vector<Observer*>{});
      EXPECT_EQ(r.status, RunStatus::kNumericalFailure) << c.cause << ", observed " << observed;
      EXPECT_NE(r.message.find(c.cause), std::string::npos) << r.message;
      EXPECT_NE(r.message.find("physics invariant broken"), std::string::npos) << r.message;
      EXPECT_LT(r.end.period, 30) << c.cause;  // caught where it arose, not at the end
    }
  }
}

TEST(Hardening, InvariantsGuardedExactDouble) { ExpectInvariantsGuarded<double>(Engine::kExact); }
TEST(Hardening, InvariantsGuardedCvode) { ExpectInvariantsGuarded<double>(Engine::kCvode); }
TEST(Hardening, InvariantsGuardedExactQuad) { ExpectInvariantsGuarded<detail::Quad>(Engine::kExact); }

// The case: chain2 at f = 0.681 over 600 periods used to report a sticking fraction of
// 1.016. Whatever the motion, the fraction is the time on the stop inside the analysed window
// (the stick/release events of the run, cut at its edges) over the window's length: compared here
// with that time summed independently from the full event log and the section modes.
TEST(Hardening, Chain2StickingFractionIsAWindowAverage) {
  auto loaded = LoadScene(std::string(VIBRO_SCENES_DIR) + "/chain2.toml",
                          {"excitation.frequency=0.681", "run.periods=600"});
  const Scene& s = loaded.scene;
  const System sys(s);
  AttractorRecorder rec(sys, s);
  test::Log log;
  SimulationOptions opt;
  opt.observers = {&rec, &log};
  const RunResult r = Simulate(sys, s, opt);
  ASSERT_EQ(r.status, RunStatus::kOk) << r.message;
  const Attractor a = rec.Classify();
  ASSERT_TRUE(a.sticking_fraction.has_value());
  EXPECT_GE(*a.sticking_fraction, 0.0);
  EXPECT_LE(*a.sticking_fraction, 1.0);
  // Independent truth: the window is the last p periods (p = the period, or the record).
  const double T = sys.period();
  const long long K = s.run.periods;
  const long long p = a.period ? *a.period : 4LL * s.run.max_period + 1;
  const double lo = static_cast<double>(K - p) * T, hi = static_cast<double>(K) * T;
  double stuck = 0, since = -1;
  bool on = false;
  for (const auto& e : log.events) {
    const double t = static_cast<double>(e.clock.period) * T + e.clock.offset;
    if (e.kind == EventKind::kStick && !on) {
      on = true;
      since = t;
    } else if (e.kind == EventKind::kRelease && on) {
      on = false;
      stuck += std::max(0.0, std::min(t, hi) - std::max(since, lo));
    }
  }
  if (on) stuck += hi - std::max(since, lo);
  EXPECT_NEAR(*a.sticking_fraction, stuck / (hi - lo), 1e-9) << a.kind << " period " << a.period.value_or(0);
}


TEST(Hardening, LongPeriodIsFoundByRecurrenceNotCalledChaos) {
  // Issue 24 item 2: the damped 3-DOF clearance chain at f = 0.5, ω = 0.7 settles, within 10⁵
  // periods, on an orbit of period 136, beyond run.max_period = 32. The classification must say
  // how far it searched and find the period by recurrence of the section; the kind stays
  // "not-periodic". Independent truth: the logged section points themselves (no shorter return)
  // and the full classification with run.max_period = 136.
  auto loaded = LoadScene(std::string(VIBRO_TEST_SCENES_DIR) + "/damped3_clearance.toml",
                          {"excitation.amplitude=0.5", "excitation.frequency=0.7", "run.periods=100000",
                           "run.samples_per_period=0"});
  const Scene& scene = loaded.scene;
  const System sys(scene);
  const test::Outcome run = test::Simulate(scene);
  ASSERT_EQ(run.result.status, RunStatus::kOk);
  const Attractor& a = run.attractor;
  EXPECT_EQ(a.kind, "not-periodic");
  EXPECT_EQ(a.searched_period.value_or(0), 32);
  ASSERT_TRUE(a.recurrence_period.has_value());
  EXPECT_EQ(*a.recurrence_period, 136);
  EXPECT_LT(a.recurrence_distance.value_or(1), 1e-10);
  // The section points: the last one returns after 136 periods to 1e-10 and after no fewer.
  const auto& z = run.log.sections;
  const auto dist = [&](size_t i, size_t j) {
    return std::max((z[i].X - z[j].X).cwiseAbs().maxCoeff(), (z[i].V - z[j].V).cwiseAbs().maxCoeff());
  };
  const size_t N = z.size() - 1;
  for (size_t p = 1; p < 136; ++p) EXPECT_GT(dist(N, N - p), 1e-6) << p;
  EXPECT_LT(dist(N, N - 136), 1e-10);
  // With the search reaching 136 the classification describes the orbit.
  Scene longer = scene;
  longer.run.max_period = 136;
  const test::Outcome full = test::Simulate(longer);
  EXPECT_EQ(full.attractor.kind, "sticking-periodic");
  EXPECT_EQ(full.attractor.period.value_or(0), 136);
  EXPECT_FALSE(full.attractor.searched_period.has_value());
}

}  // namespace
}  // namespace vibro
