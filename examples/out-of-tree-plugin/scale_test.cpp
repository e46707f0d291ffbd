// Unit test of demo.scale: ComponentHarness drives the component by hand, loaded from the
// plugin this folder builds, with typed parameters checked exactly as in a task file.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include <fba/registry.hpp>
#include <fba/testing.hpp>

using fba::testing::ComponentHarness;

namespace {

const fba::Registry& registry() {
  static const fba::Registry r = [] {
    fba::Registry reg;
    reg.load_plugin(DEMO_PLUGIN);  // throws fba::PluginError naming the file and the reason
    return reg;
  }();
  return r;
}

}  // namespace

TEST(Scale, MultipliesEachSampleAndKeepsItsStamp) {
  ComponentHarness h(registry(), "demo.scale", {{"factor", 3}});
  h.push<std::int64_t>("in", 1, 100);
  h.push<std::int64_t>("in", -4, 200);
  EXPECT_EQ(h.run(), 2);
  EXPECT_EQ(h.values<std::int64_t>("out"), (std::vector<std::int64_t>{3, -12}));
  EXPECT_EQ(h.packets("out")[1].header().stamp_ns, 200);
}

TEST(Scale, StampsFollowTheInputNotTheClock) {
  ComponentHarness h(registry(), "demo.scale");
  h.push<std::int64_t>("in", 1);  // stamped with the harness clock: 0
  h.advance(1'000);
  h.push<std::int64_t>("in", 2);  // 1000
  h.advance(5'000);
  h.run();
  const auto& out = h.packets("out");
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].header().stamp_ns, 0);
  EXPECT_EQ(out[1].header().stamp_ns, 1'000);
}

TEST(Scale, FactorDefaultsToTwo) {
  ComponentHarness h(registry(), "demo.scale");
  h.push<std::int64_t>("in", 21);
  h.run();
  EXPECT_EQ(h.values<std::int64_t>("out"), (std::vector<std::int64_t>{42}));
}

TEST(Scale, FactorOutsideItsRangeIsAConfigurationError) {
  EXPECT_THROW(ComponentHarness(registry(), "demo.scale", {{"factor", 5000}}), fba::ConfigError);
  EXPECT_THROW(ComponentHarness(registry(), "demo.scale", {{"factor", "two"}}), fba::ConfigError);
}

TEST(Scale, OverflowIsAnEventAndTheSampleIsDropped) {
  ComponentHarness h(registry(), "demo.scale", {{"factor", 10}});
  h.push<std::int64_t>("in", std::numeric_limits<std::int64_t>::max());
  h.push<std::int64_t>("in", 5);
  h.run();
  EXPECT_EQ(h.values<std::int64_t>("out"), (std::vector<std::int64_t>{50}));
  const auto events = h.events();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].name, "overflow");
  EXPECT_EQ(events[0].payload, std::to_string(std::numeric_limits<std::int64_t>::max()));
}

TEST(Scale, TakesOnlyIntegers) {
  ComponentHarness h(registry(), "demo.scale");
  EXPECT_THROW(h.push<std::string>("in", "x"), std::invalid_argument);
}

TEST(Scale, FinishesAtTheEndOfItsInput) {
  ComponentHarness h(registry(), "demo.scale");
  h.push<std::int64_t>("in", 1);
  h.close("in");
  h.run();
  EXPECT_TRUE(h.finished());
  EXPECT_EQ(h.events().back().name, "finished");
}
