// The numbers the views write by hand (libs/types/src/view_json.hpp): rounded, short, valid JSON.
#include <gtest/gtest.h>

#include <limits>

#include "view_json.hpp"

namespace {

std::string text(double v, double scale) {
  std::string out;
  fba::views::append_number(out, v, scale);
  return out;
}

}  // namespace

TEST(ViewNumbers, AreRoundedToTheirScaleWithoutTrailingZeros) {
  EXPECT_EQ(text(0.0123456, 1e5), "0.01235");
  EXPECT_EQ(text(-0.0123456, 1e5), "-0.01235");
  EXPECT_EQ(text(-0.000004, 1e5), "0") << "no negative zero";
  EXPECT_EQ(text(1.5, 1e5), "1.5");
  EXPECT_EQ(text(-2, 1e5), "-2");
  EXPECT_EQ(text(0.04, 1e5), "0.04");
  EXPECT_EQ(text(123.45678, 10), "123.5");
  EXPECT_EQ(text(std::numeric_limits<double>::quiet_NaN(), 1e5), "null");
  EXPECT_EQ(text(-std::numeric_limits<double>::infinity(), 1e5), "null");
  EXPECT_EQ(nlohmann::json::parse(text(3e300, 1e5)).get<double>(), 3e300);
}
