// grasp.start through the component harness: one sample when it first runs, then the stream ends.
#include <gtest/gtest.h>

#include <cstdint>

#include <fba/testing.hpp>

#include "support/built_plugins.hpp"

TEST(SearchStart, SendsOneSampleWhenItFirstRunsAndFinishes) {
  fba::testing::ComponentHarness h(fba::test::built_plugins(), "grasp.start");
  h.run();
  h.run();
  EXPECT_EQ(h.values<std::int64_t>("out"), std::vector<std::int64_t>{0});
  EXPECT_TRUE(h.finished());
}
