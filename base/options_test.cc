#include "base/options.h"

#include <gtest/gtest.h>

#include "testing/testing.h"

namespace ms {

enum class Colour { kRed, kGreen };
const std::vector<std::pair<const char*, Colour>>& OptionChoices(Colour) {
  static const std::vector<std::pair<const char*, Colour>> choices = {{"red", Colour::kRed},
                                                                      {"green", Colour::kGreen}};
  return choices;
}

namespace {

using testing::ExpectInputError;

// A group as the real ones are written, with its list inline.
#define TEST_OPTIONS(X)                                                   \
  X(int, count, 3, "count", "how many", InRange(1, 10))                   \
  X(double, weight, 0.5, "weight", "a weight", InRangeOpenLow(0, 1))      \
  X(double, step, 0, "step", "0 = auto", AtLeast(0))                      \
  X(double, rate, 2, "rate", "strictly positive", Above(0))               \
  X(Colour, colour, Colour::kGreen, "colour", "red or green", AnyValue()) \
  X(bool, verbose, false, "verbose", "say more", AnyValue())

struct TestOptions {
  static constexpr const char* kOptionGroup = "test";
  TEST_OPTIONS(MS_OPTION_FIELD)
  template <typename Self, typename Visitor>
  static void ForEachOption(Self&& self, Visitor&& visit) {
    TEST_OPTIONS(MS_OPTION_VISIT)
  }
  void Check() const { CheckOptionGroup(*this); }
};

TEST(Options, DefaultsComeFromTheDeclaration) {
  const TestOptions o;
  EXPECT_EQ(o.count, 3);
  EXPECT_EQ(o.weight, 0.5);
  EXPECT_EQ(o.colour, Colour::kGreen);
  EXPECT_FALSE(o.verbose);
  EXPECT_NO_THROW(o.Check());
}

TEST(Options, ChecksNameTheFlagTheRuleAndTheValue) {
  TestOptions o;
  o.count = 0;
  ExpectInputError([&] { o.Check(); }, {"--test.count must be in [1, 10], got 0"});
  o = {};
  o.weight = 0;
  ExpectInputError([&] { o.Check(); }, {"--test.weight must be in (0, 1], got 0"});
  o = {};
  o.step = -1;
  ExpectInputError([&] { o.Check(); }, {"--test.step must be >= 0, got -1"});
  o = {};
  o.rate = 0;
  ExpectInputError([&] { o.Check(); }, {"--test.rate must be > 0, got 0"});
  o = {};
  o.step = std::numeric_limits<double>::quiet_NaN();
  ExpectInputError([&] { o.Check(); }, {"--test.step must be >= 0, got nan"});
  o = {};
  o.rate = std::numeric_limits<double>::infinity();
  ExpectInputError([&] { o.Check(); }, {"--test.rate must be > 0, got inf"});
  o = {};
  o.colour = static_cast<Colour>(7);
  ExpectInputError([&] { o.Check(); }, {"--test.colour must be one of red, green, got #7"});
}

TEST(Options, TheFirstBrokenOptionIsReported) {
  TestOptions o;
  o.weight = 2;
  o.rate = -1;
  ExpectInputError([&] { o.Check(); }, {"--test.weight"});
}

TEST(Options, GroupTextListsEveryOptionByItsKey) {
  TestOptions o;
  o.colour = Colour::kRed;
  EXPECT_EQ(OptionGroupText(o),
            "test.count=3 test.weight=0.5 test.step=0 test.rate=2 test.colour=red "
            "test.verbose=false");
}

TEST(Options, TopLevelGroupsHaveNoPrefix) {
  const OptionSpec spec{"", "lease_s", "lease", "seconds", Above(0)};
  EXPECT_EQ(spec.Flag(), "--lease");
  EXPECT_EQ(spec.Key(), "lease");
  const OptionSpec grouped{"sweep", "ncc_threshold", "ncc-threshold", "", InRange(-1, 1)};
  EXPECT_EQ(grouped.Flag(), "--sweep.ncc-threshold");
}

TEST(Options, BoundsDescribeThemselves) {
  EXPECT_EQ(AnyValue().Describe(), "");
  EXPECT_EQ(InRangeOpenHigh(0, 1).Describe(), "in [0, 1)");
  EXPECT_TRUE(InRangeOpenHigh(0, 1).Contains(0));
  EXPECT_FALSE(InRangeOpenHigh(0, 1).Contains(1));
  EXPECT_FALSE(InRangeOpenLow(0, 1).Contains(0));
  EXPECT_TRUE(AnyValue().Contains(-1e300));
  EXPECT_FALSE(AnyValue().Contains(std::numeric_limits<double>::infinity()));
}

}  // namespace
}  // namespace ms
