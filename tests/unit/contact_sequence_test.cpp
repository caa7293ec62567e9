// Contact sequences (include/vibro/contact_sequence.hpp): reading them, and comparing two
// sequences of one periodic orbit as cyclic words.
#include "vibro/contact_sequence.hpp"

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

}  // namespace
}  // namespace vibro
