// vibro score's matching (src/analysis/score.cpp) on event lists made by hand: a divergence is
// looked for in both lists, chattering tails excused on both sides, accumulation points of vibro
// not asked of a simulator that reports none, and the table's checks before any run.
#include <gtest/gtest.h>

#include "vibro/score.hpp"

namespace vibro {
namespace {

constexpr double kT = 2.0;

Event Ours(EventKind kind, double t) {
  Event e{};
  e.kind = kind;
  e.t = t;
  e.v_before = kind == EventKind::kImpact ? -1.0 : 0.0;
  return e;
}

TheirEvent Theirs(EventKind kind, double t, int line = 0) {
  TheirEvent e;
  e.kind = kind;
  e.t = t;
  e.line = line;
  return e;
}

const KindScore& Kind(const ScoreReport& r, EventKind k) {
  for (const auto& s : r.kinds)
    if (s.kind == k) return s;
  throw std::runtime_error("kind not in the report");
}

TEST(Score, AnEventTheyMissedIsTheFirstDivergence) {
  const std::vector<Event> ours = {Ours(EventKind::kImpact, 1.0), Ours(EventKind::kImpact, 2.0),
                                   Ours(EventKind::kImpact, 3.0)};
  const std::vector<TheirEvent> theirs = {Theirs(EventKind::kImpact, 1.0), Theirs(EventKind::kImpact, 3.0)};
  const ScoreReport r = ScoreEvents(ours, theirs, kT, {});
  ASSERT_TRUE(r.divergence);
  EXPECT_EQ(r.divergence->side, "vibro");
  EXPECT_EQ(r.divergence->t, 2.0);
  EXPECT_FALSE(r.agrees());
  const KindScore& s = Kind(r, EventKind::kImpact);
  EXPECT_EQ(s.matched, 2);
  EXPECT_EQ(s.unmatched_ours, 1);
  EXPECT_DOUBLE_EQ(*s.matched_fraction, 2.0 / 3.0);
  EXPECT_EQ(r.max_time_error, 0.0);  // over the matches: the verdict comes from the divergence
}

TEST(Score, TheEarlierOfBothListsDiverges) {
  // Their extra event at 0.5 comes before vibro's missed one at 2.
  const std::vector<Event> ours = {Ours(EventKind::kImpact, 1.0), Ours(EventKind::kImpact, 2.0)};
  const std::vector<TheirEvent> theirs = {Theirs(EventKind::kStick, 0.5), Theirs(EventKind::kImpact, 1.0)};
  const ScoreReport r = ScoreEvents(ours, theirs, kT, {});
  ASSERT_TRUE(r.divergence);
  EXPECT_EQ(r.divergence->side, "theirs");
  EXPECT_EQ(r.divergence->t, 0.5);
  EXPECT_EQ(r.unmatched, 2);
}

TEST(Score, TailsAreExcusedOnBothSides) {
  // They sum up a sequence earlier than vibro (accumulation at 1.8 after their impact at 1.5):
  // vibro's impacts at 1.6 and 1.7 lie in their tail. vibro sums up another one earlier than
  // they do: their impact at 3.6 lies in vibro's tail (3.5, 3.8].
  const std::vector<Event> ours = {
      Ours(EventKind::kImpact, 1.0), Ours(EventKind::kImpact, 1.5),       Ours(EventKind::kImpact, 1.6),
      Ours(EventKind::kImpact, 1.7), Ours(EventKind::kAccumulation, 1.8), Ours(EventKind::kStick, 1.8),
      Ours(EventKind::kImpact, 3.5), Ours(EventKind::kAccumulation, 3.8), Ours(EventKind::kStick, 3.8)};
  const std::vector<TheirEvent> theirs = {
      Theirs(EventKind::kImpact, 1.0),       Theirs(EventKind::kImpact, 1.5),
      Theirs(EventKind::kAccumulation, 1.8), Theirs(EventKind::kStick, 1.8),
      Theirs(EventKind::kImpact, 3.5),       Theirs(EventKind::kImpact, 3.6),
      Theirs(EventKind::kAccumulation, 3.8), Theirs(EventKind::kStick, 3.8)};
  const ScoreReport r = ScoreEvents(ours, theirs, kT, {});
  EXPECT_TRUE(r.agrees()) << r.divergence->why;
  const KindScore& s = Kind(r, EventKind::kImpact);
  EXPECT_EQ(s.ours_in_accumulation, 2);
  EXPECT_EQ(s.in_accumulation, 1);
  EXPECT_EQ(*s.matched_fraction, 1.0);
}

TEST(Score, AccumulationsNotAskedOfASimulatorThatReportsNone) {
  const std::vector<Event> ours = {Ours(EventKind::kImpact, 1.0), Ours(EventKind::kAccumulation, 1.2),
                                   Ours(EventKind::kStick, 1.2)};
  const std::vector<TheirEvent> theirs = {Theirs(EventKind::kImpact, 1.0), Theirs(EventKind::kStick, 1.2)};
  const ScoreReport r = ScoreEvents(ours, theirs, kT, {});
  EXPECT_TRUE(r.agrees());
  EXPECT_FALSE(Kind(r, EventKind::kAccumulation).scored);
  EXPECT_FALSE(Kind(r, EventKind::kAccumulation).matched_fraction);
  // A stick missing too is a divergence.
  const ScoreReport r2 = ScoreEvents(ours, {Theirs(EventKind::kImpact, 1.0)}, kT, {});
  ASSERT_TRUE(r2.divergence);
  EXPECT_EQ(r2.divergence->kind, EventKind::kStick);
}

TEST(Score, AnEventAtTheEndOfTheRunMayLackItsPartner) {
  ScoreOptions opt;
  opt.t_end = 10.0;
  const std::vector<Event> ours = {Ours(EventKind::kImpact, 1.0), Ours(EventKind::kImpact, 10.0 - 1e-7 * kT)};
  const std::vector<TheirEvent> theirs = {Theirs(EventKind::kImpact, 1.0)};
  EXPECT_TRUE(ScoreEvents(ours, theirs, kT, opt).agrees());
  const std::vector<Event> earlier = {Ours(EventKind::kImpact, 1.0), Ours(EventKind::kImpact, 10.0 - 1e-5 * kT)};
  EXPECT_FALSE(ScoreEvents(earlier, theirs, kT, opt).agrees());
}

TEST(Score, TableProblemsNameTheirRows) {
  const auto where = [](const TheirEvent& e) { return "row " + std::to_string(e.line); };
  const std::vector<TheirEvent> good = {Theirs(EventKind::kImpact, 1.0, 1), Theirs(EventKind::kAccumulation, 2.0, 2),
                                        Theirs(EventKind::kStick, 2.0, 3)};
  EXPECT_TRUE(EventTableProblems(good, 0.0, 10.0, kT, 0.05, where).empty());
  const std::vector<TheirEvent> bad = {Theirs(EventKind::kImpact, 2.0, 1), Theirs(EventKind::kImpact, 1.0, 2),
                                       Theirs(EventKind::kImpact, 1.0, 3), Theirs(EventKind::kImpact, 1e9, 4),
                                       Theirs(EventKind::kImpact, std::nan(""), 5)};
  const auto p = EventTableProblems(bad, 0.0, 10.0, kT, 0.05, where);
  ASSERT_EQ(p.size(), 4u);
  EXPECT_NE(p[0].find("row 2: time 1 is earlier"), std::string::npos) << p[0];
  EXPECT_NE(p[1].find("row 3: the same time and kind"), std::string::npos) << p[1];
  EXPECT_NE(p[2].find("row 4: time 1000000000 is after the end"), std::string::npos) << p[2];
  EXPECT_NE(p[3].find("row 5: time nan is not a finite number"), std::string::npos) << p[3];
}

}  // namespace
}  // namespace vibro
