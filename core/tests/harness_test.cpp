// The component harness drives one component by hand, as a plugin author's test would.
#include <gtest/gtest.h>

#include <fba/testing.hpp>

#include "fixture_components.hpp"

using fba::testing::ComponentHarness;

TEST(Harness, CounterEmitsItsRangeThenFinishes) {
  ComponentHarness h(fba::test::registry(), "examples.counter", {{"count", 3}, {"start", 7}});
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
  ComponentHarness h(fba::test::registry(), "examples.sink", {{"expected", 5}});
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
  ComponentHarness h(fba::test::registry(), "examples.sink", {{"expected", 2}});
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
  EXPECT_THROW(ComponentHarness(fba::test::registry(), "examples.counter", {{"count", -1}}), fba::ConfigError);
  EXPECT_THROW(ComponentHarness(fba::test::registry(), "examples.counter", {{"count", 2.5}}), fba::ConfigError);
  EXPECT_THROW(ComponentHarness(fba::test::registry(), "examples.counter", {{"count", "5"}}), fba::ConfigError);
  EXPECT_THROW(ComponentHarness(fba::test::registry(), "examples.counter", {{"cuont", 5}}), fba::ConfigError);
  EXPECT_THROW(ComponentHarness(fba::test::registry(), "test.reader", {{"file", "harness_test.cpp"}, {"mode", "words"}}),
               fba::ConfigError);
}

TEST(Harness, AnIntIsTakenForADoubleParameter) {
  ComponentHarness h(fba::test::registry(), "examples.sink", {{"delay", 0}});
  h.push<std::int64_t>("in", 1);
  EXPECT_EQ(h.run(), 1);
}

TEST(Harness, TextParametersNeedNoQuoting) {
  ComponentHarness h(fba::test::registry(), "examples.faulty", {{"fail_after", 0}, {"message", "a: b, [c] # d"}});
  h.push<std::int64_t>("in", 1);
  h.run();
  EXPECT_NE(h.failure().find("a: b, [c] # d"), std::string::npos) << h.failure();
}

TEST(Harness, PushesAreStampedWithTheHarnessClock) {
  ComponentHarness h(fba::test::registry(), "examples.passthrough");
  h.push<std::int64_t>("in", 1);
  h.advance(250);
  h.push<std::int64_t>("in", 2);
  h.set_time(1000);
  h.push<std::int64_t>("in", 3, 700);
  h.run();
  const auto& out = h.packets("out");
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].header().stamp_ns, 0);
  EXPECT_EQ(out[1].header().stamp_ns, 250);
  EXPECT_EQ(out[2].header().stamp_ns, 700);
  EXPECT_THROW(h.set_time(999), std::invalid_argument);
}

TEST(Harness, ASensorStampsWithTheClockAndAPeriodicTickAdvancesIt) {
  ComponentHarness h(fba::test::registry(), "examples.counter", {{"count", 3}, {"rate", 10.0}});
  h.set_time(5'000);
  EXPECT_EQ(h.run(), 0);  // periodic: nothing before a tick
  h.tick();
  h.tick();
  EXPECT_EQ(h.run(), 1);  // two ticks pending are one
  h.tick();
  EXPECT_EQ(h.run(), 1);
  const auto& out = h.packets("out");
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].header().stamp_ns, 5'000 + 200'000'000);
  EXPECT_EQ(out[1].header().stamp_ns, 5'000 + 300'000'000);
}

TEST(Harness, TypedHandlesPushAndRead) {
  constexpr fba::In<std::int64_t> kIn{"in", ""};
  constexpr fba::Out<std::int64_t> kOut{"out", ""};
  ComponentHarness h(fba::test::registry(), "test.countdown");
  h.push(kIn, std::int64_t{5});
  h.push(kIn, std::int64_t{0});
  h.run();
  EXPECT_EQ(h.values(kOut), (std::vector<std::int64_t>{4}));
}

TEST(PluginBug, AnUndeclaredParameterIsReportedAtThePluginNotTheTaskFile) {
  try {
    ComponentHarness h(fba::test::registry(), "test.forgetful");
    FAIL() << "constructed";
  } catch (const fba::ConfigError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    const auto& d = e.diagnostics()[0];
    EXPECT_EQ(d.where.file, "the test program");
    EXPECT_EQ(d.where.line, 0);
    EXPECT_EQ(d.message,
              "plugin bug in the test program (type 'test.forgetful'): reads parameter 'undeclared', which its spec does not declare");
  }
}

TEST(PluginBug, AParameterReadWithAnotherTypeIsAPluginBug) {
  try {
    ComponentHarness h(fba::test::registry(), "test.mistyped");
    FAIL() << "constructed";
  } catch (const fba::ConfigError& e) {
    EXPECT_EQ(e.diagnostics().at(0).message,
              "plugin bug in the test program (type 'test.mistyped'): reads parameter 'factor' as int; its spec declares double");
  }
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
