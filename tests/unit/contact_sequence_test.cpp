// Contact sequences (include/vibro/contact_sequence.hpp): reading them, and comparing two
// sequences of one periodic orbit as cyclic words.
#include "vibro/contact_sequence.hpp"

#include <algorithm>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace vibro {
namespace {

using ::testing::HasSubstr;

std::vector<std::string> Parse(const std::string& text, int contacts = -1) {
  std::string problem;
  const auto s = ParseContactSequence(text, contacts, problem);
  EXPECT_TRUE(s) << problem;
  return s.value_or(std::vector<std::string>{});
}

std::string Problem(const std::string& text, int contacts = -1) {
  std::string problem;
  EXPECT_FALSE(ParseContactSequence(text, contacts, problem)) << text;
  return problem;
}

bool Same(const std::string& a, const std::string& b) { return SameContactSequence(Parse(a), Parse(b)); }

// The canonical text of a sequence given as text.
std::string Canonical(const std::string& text) { return ContactSequenceText(Parse(text)); }

std::vector<std::string> Rotated(std::vector<std::string> w, size_t k) {
  std::rotate(w.begin(), w.begin() + static_cast<std::ptrdiff_t>(k % w.size()), w.end());
  return w;
}

TEST(ContactSequence, ReadsOrbitResultsFormat) {
  EXPECT_EQ(Parse("0:impact 1:impact*3  1+0:impact 0:stick 0:release"),
            (std::vector<std::string>{"0:impact", "1:impact", "1:impact", "1:impact", "0+1:impact", "0:stick",
                                      "0:release"}));
  EXPECT_TRUE(Parse("").empty());
  EXPECT_TRUE(Parse("   ").empty());
  EXPECT_EQ(Parse("2:grazing 0:accumulation", 3).size(), 2u);
}

TEST(ContactSequence, RefusesWhatIsNoSequence) {
  EXPECT_THAT(Problem("0-impact"), HasSubstr("no ':'"));
  EXPECT_THAT(Problem("0:bounce"), HasSubstr("unknown event kind"));
  EXPECT_THAT(Problem("0:impact*0"), HasSubstr("whole number ≥ 1"));
  EXPECT_THAT(Problem("0:impact*x"), HasSubstr("whole number ≥ 1"));
  EXPECT_THAT(Problem("a:impact"), HasSubstr("contact index"));
  EXPECT_THAT(Problem("-1:impact"), HasSubstr("contact index"));
  EXPECT_THAT(Problem("0+0:impact"), HasSubstr("named twice"));
  EXPECT_THAT(Problem("0+1:stick"), HasSubstr("only an impact"));
  EXPECT_THAT(Problem("2:impact", 2), HasSubstr("the scene has 2 contacts"));
  EXPECT_THAT(Problem("0:impact*999999 0:impact*2"), HasSubstr("more than 1000000 events"));
}

TEST(ContactSequence, SameOrbitWhereverItStarts) {
  EXPECT_TRUE(Same("0:impact 1:impact", "0:impact 1:impact"));
  EXPECT_TRUE(Same("0:impact 1:impact", "1:impact 0:impact"));  // from the other stop
  EXPECT_TRUE(Same("0:impact 1:impact", "1:impact 0:impact 1:impact 0:impact"));  // over two periods
  EXPECT_TRUE(Same("0:impact 1:impact*2 0:stick 0:release", "0:stick 0:release 0:impact 1:impact 1:impact"));
  EXPECT_FALSE(Same("0:impact 1:impact", "0:impact 0:impact"));
  EXPECT_FALSE(Same("0:impact 1:impact", "0:impact"));
  EXPECT_FALSE(Same("0:impact 1:impact*2", "0:impact*2 1:impact"));
  EXPECT_FALSE(Same("0:impact 0:impact 1:impact", "0:impact 1:impact 1:impact"));
  EXPECT_FALSE(Same("0:impact*2 1:impact*2", "0:impact 1:impact"));  // not a repetition
  EXPECT_FALSE(Same("0+1:impact", "0:impact 1:impact"));
  EXPECT_TRUE(SameContactSequence({}, {}));
  EXPECT_FALSE(SameContactSequence({}, Parse("0:impact")));
}

TEST(ContactSequence, AChatteringSequenceIsOneWhateverItsCount) {
  // The impacts of a chattering sequence up to its accumulation point count as one entry (where
  // the tail starts is bookkeeping), also when the word starts inside the sequence.
  EXPECT_TRUE(Same("0:impact*16 0:accumulation 0:stick 0:release 1:impact*16 1:accumulation 1:stick 1:release",
                   "0:impact*3 0:accumulation 0:stick 0:release 1:impact*20 1:accumulation 1:stick 1:release"));
  EXPECT_TRUE(Same("0:impact*5 0:accumulation 0:stick 0:release 0:impact*11",
                   "0:impact*16 0:accumulation 0:stick 0:release"));
  // ... but not across contacts, nor without the accumulation point.
  EXPECT_FALSE(Same("1:impact*3 0:accumulation 0:stick 0:release", "0:impact*3 0:accumulation 0:stick 0:release"));
  EXPECT_FALSE(Same("0:impact*16 0:accumulation 0:stick 0:release", "0:impact*16 0:accumulation 0:stick"));
  EXPECT_FALSE(Same("0:impact*3 0:release", "0:impact*4 0:release"));
  // A chattering sequence ended by a plastic impact below a threshold (no accumulation point) is
  // the same landing.
  EXPECT_TRUE(Same("0:impact*3 0:stick 0:release", "0:impact*4 0:stick 0:release"));
  EXPECT_TRUE(Same("0:impact*16 0:accumulation 0:stick 0:release 1:impact*16 1:accumulation 1:stick 1:release",
                   "1:impact*9 1:stick 1:release 0:impact*12 0:stick 0:release"));
  EXPECT_FALSE(Same("0:impact*3 0:stick 0:release", "1:impact*3 0:stick 0:release"));
  EXPECT_FALSE(Same("0:impact*3 0:stick 0:release", "0:impact*3 0:stick 0:release 1:impact"));
}

TEST(ContactSequence, OneCanonicalRotation) {
  // Issue 37, scene E continued in ω: one orbit written from two sections.
  EXPECT_EQ(Canonical("1:impact 0:impact"), "0:impact 1:impact");
  EXPECT_EQ(Canonical("0:impact 1:impact"), "0:impact 1:impact");
  EXPECT_EQ(Canonical("0:impact 1:impact*2 0:impact"), "0:impact*2 1:impact*2");
  EXPECT_EQ(Canonical("1:impact 0:impact*2 1:impact"), "0:impact*2 1:impact*2");
  // Contacts first (ascending lists compared lexicographically: 0 < 0+1 < 1), then the kind.
  EXPECT_EQ(Canonical("1:impact 0+1:impact 2:grazing"), "0+1:impact 2:grazing 1:impact");
  EXPECT_EQ(Canonical("1:impact 0:stick 0:release"), "0:stick 0:release 1:impact");
  EXPECT_EQ(Canonical("2:impact 10:impact"), "2:impact 10:impact");  // contacts as numbers
  // A chattering run is one token, after a lone impact at its contact: it is never cut, also
  // when the word was written from inside it.
  EXPECT_EQ(Canonical("0:impact*2 0:accumulation 0:stick 0:release 1:impact 0:impact*3"),
            "0:impact*5 0:accumulation 0:stick 0:release 1:impact");
  EXPECT_EQ(Canonical("1:impact*9 1:stick 1:release 0:impact*12 0:stick 0:release"),
            "0:impact*12 0:stick 0:release 1:impact*9 1:stick 1:release");
  EXPECT_EQ(Canonical("0:release 0:impact 0:impact*4 0:accumulation 0:stick 1:impact 0:impact"),
            "0:impact 0:release 0:impact*5 0:accumulation 0:stick 1:impact");
  // Where its tail starts does not move the start: the same rotation whatever the counts.
  EXPECT_EQ(Canonical("1:impact*3 1:accumulation 1:stick 1:release 0:impact*20 0:accumulation 0:stick 0:release"),
            "0:impact*20 0:accumulation 0:stick 0:release 1:impact*3 1:accumulation 1:stick 1:release");
  // Over several periods the whole word is kept; repetitions that differ only in a chattering
  // count are ordered by their entries (an impact before an accumulation point).
  EXPECT_EQ(Canonical("1:impact 0:impact 1:impact 0:impact"), "0:impact 1:impact 0:impact 1:impact");
  EXPECT_EQ(Canonical("0:impact*2 0:accumulation 0:stick 0:release 0:impact*3 0:accumulation 0:stick 0:release"),
            "0:impact*3 0:accumulation 0:stick 0:release 0:impact*2 0:accumulation 0:stick 0:release");
  EXPECT_EQ(Canonical(""), "");
  EXPECT_EQ(Canonical("0:impact*4"), "0:impact*4");
}

// The canonical rotation against its definition by brute force, without chattering (every entry a
// token): the least of all rotations under the stated order, computed here independently.
TEST(ContactSequence, CanonicalRotationIsTheLeastRotation) {
  std::mt19937 rng(37);
  const std::vector<std::string> alphabet = {"0:impact", "1:impact", "0+1:impact", "2:impact", "0:release",
                                             "1:grazing", "1:release", "0+2:impact"};
  // Rank of each entry in the order: contacts' lists lexicographically, then kind.
  const std::vector<std::string> order = {"0:impact", "0:release", "0+1:impact", "0+2:impact", "1:impact",
                                          "1:release", "1:grazing", "2:impact"};
  const auto rank = [&](const std::string& e) { return std::find(order.begin(), order.end(), e) - order.begin(); };
  for (int trial = 0; trial < 2000; ++trial) {
    const size_t n = 1 + rng() % 9;
    std::vector<std::string> w(n);
    for (auto& e : w) e = alphabet[rng() % alphabet.size()];
    std::vector<std::string> least = w;
    for (size_t k = 1; k < n; ++k) {
      const auto r = Rotated(w, k);
      if (std::lexicographical_compare(r.begin(), r.end(), least.begin(), least.end(),
                                       [&](const auto& a, const auto& b) { return rank(a) < rank(b); }))
        least = r;
    }
    ASSERT_EQ(CanonicalRotation(w), least) << ContactSequenceText(w);
  }
}

// Every rotation of a word, chattering runs and all, is written the same: a rotation of the word,
// the same cyclic word.
TEST(ContactSequence, EveryRotationIsWrittenTheSame) {
  std::mt19937 rng(11);
  const std::vector<std::vector<std::string>> pieces = {
      {"0:impact"}, {"1:impact"}, {"0+1:impact"}, {"1:grazing"},
      {"0:impact", "0:impact", "0:accumulation", "0:stick", "0:release"},
      {"0:impact", "0:impact", "0:impact", "0:accumulation", "0:stick", "0:release"},
      {"1:impact", "1:impact", "1:stick", "1:release"},
      {"1:impact", "1:impact", "1:impact", "1:accumulation", "1:stick", "1:release"},
      {"0:stick", "0:release"}};
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<std::string> w;
    const size_t parts = 1 + rng() % 5;
    for (size_t i = 0; i < parts; ++i) {
      const auto& p = pieces[rng() % pieces.size()];
      w.insert(w.end(), p.begin(), p.end());
    }
    if (rng() % 3 == 0) {  // over two periods
      const auto once = w;
      w.insert(w.end(), once.begin(), once.end());
    }
    const auto canonical = CanonicalRotation(w);
    ASSERT_EQ(canonical.size(), w.size());
    bool is_rotation = false;
    for (size_t k = 0; k < w.size(); ++k) {
      const auto r = Rotated(w, k);
      is_rotation = is_rotation || r == canonical;
      ASSERT_EQ(CanonicalRotation(r), canonical) << ContactSequenceText(w) << " rotated by " << k;
    }
    ASSERT_TRUE(is_rotation) << ContactSequenceText(w);
    ASSERT_TRUE(SameContactSequence(w, canonical));
  }
}


// Where the canonical rotation starts (an orbit's events are listed from there, docs/orbits.md):
// the word rotated to start there is the canonical rotation, for every rotation of random words;
// issue 37's scene D read from Newton's section, 1:impact*4 0:impact, starts at its entry 4.
TEST(ContactSequence, CanonicalStartIsWhereTheCanonicalRotationBegins) {
  const std::vector<std::string> d = {"1:impact", "1:impact", "1:impact", "1:impact", "0:impact"};
  EXPECT_EQ(CanonicalStart(d), 4u);
  EXPECT_EQ(CanonicalStart(CanonicalRotation(d)), 0u);
  EXPECT_EQ(CanonicalStart(std::vector<std::string>{"0:impact"}), 0u);
  std::mt19937 rng(37);
  const std::vector<std::string> entries = {"0:impact", "1:impact", "0+1:impact", "0:accumulation",
                                            "0:stick", "0:release", "1:stick", "1:release"};
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<std::string> w(1 + rng() % 8);
    for (auto& e : w) e = entries[rng() % entries.size()];
    const size_t s = CanonicalStart(w);
    ASSERT_LT(s, w.size());
    ASSERT_EQ(Rotated(w, s), CanonicalRotation(w)) << ContactSequenceText(w);
  }
}
}  // namespace
}  // namespace vibro
