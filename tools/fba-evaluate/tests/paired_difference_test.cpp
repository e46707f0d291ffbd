// fba-evaluate's paired comparison of two variants on the same runs, on differences whose median
// and spread are known.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "paired_difference.hpp"

namespace {

using fba::evaluate::mcnemar_p;
using fba::evaluate::paired_difference;

TEST(PairedDifference, TheSameShiftOnEveryRunIsThatShiftWithNoSpread) {
  const std::vector<double> a = {0.02, 0.05, 0.11, 0.07};
  std::vector<double> b = a;
  for (auto& x : b) x += 0.01;
  const auto d = paired_difference(a, b, 2000, 1);
  EXPECT_EQ(d.pairs, 4u);
  EXPECT_NEAR(d.median, 0.01, 1e-12);
  EXPECT_NEAR(d.low, 0.01, 1e-12);
  EXPECT_NEAR(d.high, 0.01, 1e-12);
  EXPECT_EQ(d.b_higher, 4u);
  EXPECT_EQ(d.a_higher, 0u);
}

TEST(PairedDifference, TheMedianIsOfTheDifferencesNotTheDifferenceOfTheMedians) {
  // Differences -1, 0, 2, 3, 10: their median 2; the medians' difference would be 4 - 3 = 1.
  const std::vector<double> a = {5, 3, 1, 4, 2};
  const std::vector<double> b = {4, 3, 3, 7, 12};
  const auto d = paired_difference(a, b, 5000, 7);
  EXPECT_DOUBLE_EQ(d.median, 2);
  EXPECT_EQ(d.b_higher, 3u);
  EXPECT_EQ(d.a_higher, 1u);
  // A resampled median is one of the differences (an odd count): the interval's ends lie in [-1, 10].
  EXPECT_GE(d.low, -1);
  EXPECT_LE(d.low, 2);
  EXPECT_GE(d.high, 2);
  EXPECT_LE(d.high, 10);
}

TEST(PairedDifference, ItsIntervalIsAsWideAsTheMediansSpreadAndHoldsTheTrueMedian) {
  // 400 differences from a normal law (mean 1, sd 1): the sample median's standard error is
  // sqrt(pi / 2) / sqrt(400) = 0.063, so a 95% interval is about 0.25 wide.
  std::mt19937_64 rng(42);
  std::normal_distribution<double> law(1.0, 1.0);
  std::vector<double> a(400, 0.0), b(400);
  for (auto& x : b) x = law(rng);
  const auto d = paired_difference(a, b, 4000, 3);
  EXPECT_LT(d.low, 1.0);
  EXPECT_GT(d.high, 1.0);
  EXPECT_GT(d.high - d.low, 0.15);
  EXPECT_LT(d.high - d.low, 0.40);
}

TEST(PairedDifference, TheSameSeedGivesTheSameIntervalAndNoPairsGiveZeros) {
  const std::vector<double> a = {0.1, 0.4, 0.2, 0.9, 0.3, 0.5};
  const std::vector<double> b = {0.2, 0.1, 0.6, 0.8, 0.3, 0.9};
  const auto d1 = paired_difference(a, b, 1000, 11), d2 = paired_difference(a, b, 1000, 11);
  EXPECT_EQ(d1.low, d2.low);
  EXPECT_EQ(d1.high, d2.high);
  const auto none = paired_difference({}, {}, 1000, 11);
  EXPECT_EQ(none.pairs, 0u);
  EXPECT_EQ(none.median, 0);
  EXPECT_EQ(none.low, 0);
  EXPECT_EQ(none.high, 0);
}

TEST(PairedDifference, FiguresForDifferentRunsAreRefused) {
  try {
    paired_difference({0.1, 0.2}, {0.1}, 100, 1);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("found 2 and 1"), std::string::npos) << e.what();
  }
}

TEST(McNemar, TheExactTestOnTheRunsOnlyOneVariantSelectedOnGivesTheBinomialTail) {
  // 1 against 5 of 6: 2 * (1 + 6) / 64.
  EXPECT_NEAR(mcnemar_p(1, 5), 14.0 / 64, 1e-12);
  EXPECT_NEAR(mcnemar_p(5, 1), 14.0 / 64, 1e-12);
  // 0 against 6: 2 / 64, the smallest p six runs can give.
  EXPECT_NEAR(mcnemar_p(0, 6), 2.0 / 64, 1e-12);
  // An even split, or no run telling them apart: nothing against "as likely".
  EXPECT_EQ(mcnemar_p(3, 3), 1.0);
  EXPECT_EQ(mcnemar_p(0, 0), 1.0);
  // Large counts stay finite: 400 against 600 is far from even.
  EXPECT_LT(mcnemar_p(400, 600), 1e-9);
  EXPECT_GT(mcnemar_p(400, 600), 0.0);
}

}  // namespace
