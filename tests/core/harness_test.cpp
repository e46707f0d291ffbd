// The component harness drives one component by hand, as a plugin author's test would.
#include <gtest/gtest.h>

#include <fba/testing.hpp>

#include "test_components.hpp"

using fba::testing::ComponentHarness;

TEST(Harness, CounterEmitsItsRangeThenFinishes) {
  ComponentHarness h(fba::test::registry(), "examples.counter", {{"count", "3"}, {"start", "7"}});
  EXPECT_EQ(h.run(), 3);
  EXPECT_EQ(h.values<std::int64_t>("out"), (std::vector<std::int64_t>{7, 8, 9}));
  EXPECT_TRUE(h.finished());
}

TEST(Harness, PassthroughForwardsAnyTypeUntouched) {
  ComponentHarness h(fba::test::registry(), "examples.passthrough");
  h.push<std::string>("in", "hello", 42);
  h.push<std::string>("in", "world", 43);
  EXPECT_EQ(h.run(), 2);
  const auto& out = h.packets("out");
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].get<std::string>(), "hello");
  EXPECT_EQ(out[1].header().stamp_ns, 43);
}

TEST(Harness, EndOfStreamFinishesAFilter) {
  ComponentHarness h(fba::test::registry(), "examples.passthrough");
  h.push<std::int64_t>("in", 1);
  h.run();
  EXPECT_FALSE(h.finished());
  h.close("in");
  h.run();
  EXPECT_TRUE(h.finished());
}

TEST(Harness, SinkReportsAGapAndFails) {
  ComponentHarness h(fba::test::registry(), "examples.sink", {{"expected", "5"}});
  h.push_packet("in", fba::Packet::make<std::int64_t>(std::make_shared<const std::int64_t>(0), {0, 0, nullptr}));
  h.push_packet("in", fba::Packet::make<std::int64_t>(std::make_shared<const std::int64_t>(2), {2, 0, nullptr}));
  h.run();
  const auto events = h.events();
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.front().name, "gap");
  EXPECT_EQ(events.front().payload, "from ?: expected sample 1, got 2");
  EXPECT_NE(h.failure().find("sequence gap"), std::string::npos);
}

TEST(Harness, SinkEmitsDoneAtTheExpectedCount) {
  ComponentHarness h(fba::test::registry(), "examples.sink", {{"expected", "2"}});
  h.push<std::int64_t>("in", 10);
  h.push<std::int64_t>("in", 11);
  h.run();
  const auto events = h.events();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].name, "done");
  EXPECT_EQ(events[0].payload, "2");
  h.safe_state();
  EXPECT_EQ(h.events().back().name, "safe_state");
}

TEST(Harness, WrongInputTypeIsRefused) {
  ComponentHarness h(fba::test::registry(), "test.countdown");
  EXPECT_THROW(h.push<std::string>("in", "x"), std::invalid_argument);
}

TEST(Harness, ParametersAreCheckedAsInATaskFile) {
  EXPECT_THROW(ComponentHarness(fba::test::registry(), "examples.counter", {{"count", "-1"}}), fba::ConfigError);
}

TEST(Harness, AnIllegalStageTransitionIsAFailure) {
  ComponentHarness h(fba::test::registry(), "test.staged");
  EXPECT_EQ(h.stage(), "idle");
  h.push<std::int64_t>("in", 1);
  h.run();
  EXPECT_EQ(h.stage(), "working");
  h.push<std::int64_t>("in", 3);  // working -> idle is not declared
  h.run();
  EXPECT_NE(h.failure().find("allows no transition from stage 'working' to 'idle'"), std::string::npos) << h.failure();
}
