// The exact engine against the 1-DOF closed forms of docs/model.md §6 (r = 0): release (32), landing (33),
// sticking fraction, the limits f_free-flight (38) and f_sticking (36), clearance, subharmonics.
#include <cmath>

#include <gtest/gtest.h>

#include "support.hpp"

namespace vibro::test {
namespace {

// Time from event a to event b, from the clocks (whole periods kept apart from the offsets).
double Elapsed(const Event& a, const Event& b, double T) {
  return static_cast<double>(b.clock.period - a.clock.period) * T + (b.clock.offset - a.clock.offset);
}

double PhaseMod(double phase, double m) {
  double p = std::fmod(phase, m);
  return p < 0 ? p + m : p;
}

// docs/model.md §6.3: f_free-flight(ω, q), √(f² − 1) = ω tan(qπ/ω) (valid when tan > 0, preload).
double FreeFlightLimit(double w, int q) {
  const double t = std::tan(q * M_PI / w);
  return std::sqrt(1.0 + w * w * t * t);
}

// docs/model.md §6.3 (36): √(f² − 1)/ω = tan(((2q − 1)π/2 − arcsin(1/f))/ω), by bisection on [lo, hi].
double StickingLimit(double w, int q, double lo, double hi) {
  const auto F = [&](double f) {
    return std::sqrt(f * f - 1) / w - std::tan(((2 * q - 1) * M_PI / 2 - std::asin(1 / f)) / w);
  };
  const bool lo_pos = F(lo) > 0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    ((F(mid) > 0) == lo_pos ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(ClosedForms, OraclesReproduceTheSanityValuesOfModelSection63) {
  EXPECT_NEAR(FreeFlightLimit(2.8, 1), 5.899628658, 1e-9);
  EXPECT_NEAR(FreeFlightLimit(10, 1), 3.399600109, 1e-9);
  EXPECT_NEAR(FreeFlightLimit(10, 2), 7.333921495, 1e-9);
  EXPECT_NEAR(StickingLimit(10, 2, 4.5, 5.5), 4.943480948, 1e-9);
  EXPECT_NEAR(StickingLimit(5, 2, 6.0, 7.0), 6.531972647, 1e-9);
}

// One-flight sticking orbit from its closed form: release t1 (32), landing t0 (33), period q and
// sticking fraction SP (§6.2), compared with the engine's events and attractor.
void CheckOneFlightOrbit(double w, double f, double x0) {
  SCOPED_TRACE(testing::Message() << "ω = " << w << ", f = " << f << ", x0 = " << x0);
  const Outcome run = Simulate(OneDof(0.0, w, f, x0, 40));
  ASSERT_EQ(run.result.status, RunStatus::kOk);
  const double T = 2 * M_PI / w;

  const LD t1 = ReleaseTime(w, f, x0);
  const Flight1 flight{w, f, t1, x0, 0};
  const LD t0 = flight.Landing(x0);
  ASSERT_LT(f * std::sin(w * t0), x0) << "the landing must stick: R(t'_0) > 0";
  const LD theta = t0 - t1;
  const int q = static_cast<int>(std::ceil(w * theta / (2 * M_PIl)));
  const double sp = static_cast<double>(1 - w * theta / (2 * M_PIl * q));

  ASSERT_TRUE(run.attractor.period.has_value());
  EXPECT_EQ(run.attractor.kind, "sticking-periodic");
  EXPECT_EQ(*run.attractor.period, q);
  EXPECT_EQ(run.attractor.impacts_per_period, 1);
  EXPECT_NEAR(*run.attractor.sticking_fraction, sp, 1e-12);
  if (x0 < 0) {
    EXPECT_LT(sp, 0.5);  // clearance: SP < 1/2 (§6.2)
    EXPECT_LE(sp, (M_PI + 2 * std::asin(x0 / f)) / (2 * M_PI) + 1e-12);
  }
  ASSERT_EQ(run.attractor.stick_phases.size(), 1u);
  const auto [start, end] = run.attractor.stick_phases[0];
  EXPECT_NEAR(PhaseMod(end, 2 * M_PI), static_cast<double>(w * t1), 1e-12);  // release phase
  EXPECT_NEAR(end - start, 2 * M_PI * q * sp, 1e-11);

  // Every flight of the run: release → impact+stick after Θ.
  const auto releases = run.log.Of(EventKind::kRelease);
  ASSERT_GE(releases.size(), 5u);
  for (const auto& rel : releases)
    EXPECT_NEAR(PhaseMod(w * rel.clock.offset, 2 * M_PI), static_cast<double>(w * t1), 1e-12);
  int flights = 0;
  for (size_t i = 0; i + 1 < run.log.events.size(); ++i) {
    const Event& e = run.log.events[i];
    if (e.kind != EventKind::kRelease) continue;
    const Event& landing = run.log.events[i + 1];
    ASSERT_EQ(landing.kind, EventKind::kImpact);
    EXPECT_NEAR(Elapsed(e, landing, T), static_cast<double>(theta), 1e-12 * T);
    EXPECT_NEAR(landing.v_before, static_cast<double>(flight.v(t0)), 1e-11);
    EXPECT_EQ(landing.v_after, 0.0);
    ++flights;
  }
  EXPECT_GE(flights, 5);
}

TEST(ClosedForms, ReleaseLandingAndStickingFractionPreload) {
  for (double w : {0.5, 1.4, 2.8, 5.0, 10.0})
    for (double f : {1.05, 1.5, 3.0}) CheckOneFlightOrbit(w, f, 1.0);
}

TEST(ClosedForms, SubharmonicOrbitOfFig4) { CheckOneFlightOrbit(10.0, 6.0, 1.0); }

TEST(ClosedForms, ClearanceOrbitOfFig11) {
  CheckOneFlightOrbit(1.4, 10.0, -1.0);
  CheckOneFlightOrbit(1.4, 3.0, -1.0);
}

TEST(ClosedForms, TwoFlightOrbitOfFig10) {
  // (r, ω, f) = (0, 10, 4.8): the landing after a release meets R < 0 and leaves at zero velocity
  // (docs/model.md §4.4); the second flight lands with R > 0 and sticks.
  const double w = 10.0, f = 4.8, T = 2 * M_PI / w;
  const Outcome run = Simulate(OneDof(0.0, w, f, 1.0, 40));
  const LD t1 = ReleaseTime(w, f);
  const LD ta = Flight1{w, f, t1, 1, 0}.Landing(1);
  ASSERT_GT(f * std::sin(w * ta), 1.0L) << "first landing: R < 0";
  const LD tb = Flight1{w, f, ta, 1, 0}.Landing(1, 1e-4L, 1e-5L);
  ASSERT_LT(f * std::sin(w * tb), 1.0L) << "second landing: R > 0";
  const int q = static_cast<int>(std::ceil(w * (tb - t1) / (2 * M_PIl)));
  EXPECT_EQ(q, 2);
  EXPECT_EQ(run.attractor.period, q);
  EXPECT_EQ(run.attractor.impacts_per_period, 2);
  EXPECT_NEAR(*run.attractor.sticking_fraction,
              static_cast<double>(1 - w * (tb - t1) / (2 * M_PIl * q)), 1e-12);
  int checked = 0;
  const auto& ev = run.log.events;
  for (size_t i = 0; i + 3 < ev.size(); ++i) {
    if (ev[i].kind != EventKind::kRelease) continue;
    ASSERT_EQ(ev[i + 1].kind, EventKind::kImpact);
    ASSERT_EQ(ev[i + 2].kind, EventKind::kImpact);
    ASSERT_EQ(ev[i + 3].kind, EventKind::kStick);
    EXPECT_NEAR(Elapsed(ev[i], ev[i + 1], T), static_cast<double>(ta - t1), 1e-12);
    EXPECT_NEAR(Elapsed(ev[i], ev[i + 2], T), static_cast<double>(tb - t1), 1e-12);
    ++checked;
  }
  EXPECT_GE(checked, 5);
}

TEST(ClosedForms, FreeFlightLimitSticksJustInsideNotJustOutside) {
  // docs/model.md §6.3: the period-1 sticking orbits end at f_ff(ω, 1) with SP → 0 linearly.
  for (double w : {2.8, 5.0, 10.0}) {
    SCOPED_TRACE(w);
    const double fff = FreeFlightLimit(w, 1);
    const Outcome inside = Simulate(OneDof(0.0, w, fff * (1 - 1e-9), 1.0, 20));
    EXPECT_EQ(inside.attractor.kind, "sticking-periodic");
    EXPECT_EQ(inside.attractor.period, 1);
    EXPECT_EQ(inside.attractor.impacts_per_period, 1);
    ASSERT_TRUE(inside.attractor.sticking_fraction.has_value());
    EXPECT_GT(*inside.attractor.sticking_fraction, 0.0);
    EXPECT_LT(*inside.attractor.sticking_fraction, 1e-6);
    const Outcome inside2 = Simulate(OneDof(0.0, w, fff * (1 - 2e-9), 1.0, 20));
    EXPECT_NEAR(*inside2.attractor.sticking_fraction / *inside.attractor.sticking_fraction, 2.0,
                0.01);  // linear vanishing
    const Outcome outside = Simulate(OneDof(0.0, w, fff * (1 + 1e-9), 1.0, 20));
    EXPECT_FALSE(outside.attractor.kind == "sticking-periodic" && outside.attractor.period == 1 &&
                 outside.attractor.impacts_per_period == 1)
        << outside.attractor.kind;
  }
}

TEST(ClosedForms, StickingLimitFirstLandingSticksJustAbove) {
  // docs/model.md §6.3 (36): just above f_st the first landing sticks (one impact per period q = 2), just
  // below it lands with R < 0 and sticks after a second flight.
  const double w = 10.0;
  const double fst = StickingLimit(w, 2, 4.5, 5.5);
  const Outcome above = Simulate(OneDof(0.0, w, fst * (1 + 1e-7), 1.0, 20));
  EXPECT_EQ(above.attractor.period, 2);
  EXPECT_EQ(above.attractor.impacts_per_period, 1);
  const Outcome below = Simulate(OneDof(0.0, w, fst * (1 - 1e-7), 1.0, 20));
  EXPECT_EQ(below.attractor.period, 2);
  EXPECT_EQ(below.attractor.impacts_per_period, 2);
  // SP is continuous across f_st (the landing is a degenerate grazing, |f − f_st|^{1/3}).
  EXPECT_NEAR(*above.attractor.sticking_fraction, *below.attractor.sticking_fraction, 1e-2);
}

TEST(ClosedForms, OneDofRunIsExactlyPeriodicOnceItSticks) {
  // docs/model.md §5.5: for n = 1 every trajectory that sticks once is periodic from its first release
  // on, with no transient. With the release phase in closed form this holds to the bit.
  for (double r : {0.0, 0.75}) {
    const Outcome run = Simulate(OneDof(r, 10.0, 1.1, 1.0, 50));
    const auto rel = run.log.Of(EventKind::kRelease);
    const auto stick = run.log.Of(EventKind::kStick);
    ASSERT_GE(rel.size(), 40u);
    for (size_t i = 1; i < rel.size(); ++i) {
      EXPECT_EQ(rel[i].clock.offset, rel[0].clock.offset);
      EXPECT_EQ(rel[i].clock.period, rel[0].clock.period + static_cast<long long>(i));
    }
    for (size_t i = 2; i < stick.size(); ++i) EXPECT_EQ(stick[i].clock.offset, stick[1].clock.offset);
  }
}

TEST(ClosedForms, SameInputsSameBits) {
  const Outcome a = Simulate(OneDof(0.75, 2.8, 1.2, 1.0, 30));
  const Outcome b = Simulate(OneDof(0.75, 2.8, 1.2, 1.0, 30));
  ASSERT_EQ(a.log.events.size(), b.log.events.size());
  for (size_t i = 0; i < a.log.events.size(); ++i) {
    EXPECT_EQ(a.log.events[i].clock.offset, b.log.events[i].clock.offset);
    EXPECT_EQ(a.log.events[i].v_before, b.log.events[i].v_before);
  }
}

}  // namespace
}  // namespace vibro::test
