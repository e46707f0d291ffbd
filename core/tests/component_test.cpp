// Rules of the component API that hold across the runtime: blocking types implement
// interrupt(), time stamps follow the data, plugin bugs are reported at the plugin.
#include <gtest/gtest.h>

#include <fba/component.hpp>
#include <fba/registry.hpp>
#include <fba/task.hpp>
#include <fba/testing.hpp>

#include "fixture_components.hpp"

namespace {

class Waits final : public fba::Component {
 public:
  static constexpr fba::AnyIn kIn{"in", ""};
  static fba::Spec spec() { return fba::Spec::actuator("t.waits", "").add(kIn).blocking(); }
  explicit Waits(fba::Context&) {}
  void process() override {}
};

class WaitsInterruptibly final : public fba::Component {
 public:
  void process() override {}
  void interrupt() override {}
};

std::unique_ptr<fba::Component> make_waits(fba::Context& ctx) { return std::make_unique<Waits>(ctx); }

}  // namespace

TEST(Blocking, ATypeRecordsWhetherItImplementsInterrupt) {
  EXPECT_FALSE(fba::detail::overrides_interrupt<Waits>());
  EXPECT_TRUE(fba::detail::overrides_interrupt<WaitsInterruptibly>());
}

TEST(Blocking, ABlockingTypeWithoutInterruptIsRefusedWhenItRegisters) {
  fba::Registry r;
  try {
    r.add(Waits::spec(), &make_waits, "waits.so", {}, false);
    FAIL() << "registered";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("type 't.waits' is declared blocking() but does not implement interrupt()"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(r.find("t.waits"));
  r.add(Waits::spec(), &make_waits, "waits.so", {}, true);
  EXPECT_TRUE(r.find("t.waits"));
}

// counter -> passthrough -> countdown -> countdown: the counter's capture stamps reach the end,
// whatever the clock says when the filters run.
TEST(TimeStamps, AFilterOutputCarriesItsInputsStampThroughAChain) {
  const auto config = fba::test::load(R"(
components:
  src: { type: examples.counter, params: { count: 4, start: 10, rate: 100 } }
  hop: { type: examples.passthrough }
  a: { type: test.countdown }
  b: { type: test.countdown }
connections:
  - src.out -> hop.in
  - hop.out -> a.in
  - a.out -> b.in
)");
  fba::RunOptions options;
  options.executor = fba::ExecutorKind::Deterministic;
  fba::Task task(config, options);
  const auto& src = task.tap("src.out");
  const auto& out = task.tap("b.out");
  task.run();
  ASSERT_EQ(src.size(), 4u);
  ASSERT_EQ(out.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(out[i].get<std::int64_t>(), 8 + static_cast<std::int64_t>(i));
    EXPECT_EQ(out[i].header().stamp_ns, src[i].header().stamp_ns) << i;
  }
  EXPECT_GT(src[3].header().stamp_ns, src[0].header().stamp_ns);  // the stamps are distinct times
}

TEST(TimeStamps, AnOutputMadeFromSeveralInputsCarriesTheNewestStamp) {
  fba::testing::ComponentHarness h(fba::test::registry(), "test.pair");
  h.push<std::int64_t>("a", 1, 300);
  h.push<std::int64_t>("b", 2, 300);
  h.run();
  ASSERT_EQ(h.packets("sum").size(), 1u);
  EXPECT_EQ(h.packets("sum")[0].header().stamp_ns, 300);
}

TEST(PluginBug, TaskConstructionReportsItAtThePlugin) {
  const auto config = fba::test::load("components:\n  f: { type: test.forgetful }\n");
  try {
    fba::Task task(config, {});
    FAIL() << "constructed";
  } catch (const fba::ConfigError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    EXPECT_EQ(e.diagnostics()[0].where.str(), "the test program");
    EXPECT_EQ(e.diagnostics()[0].message.rfind("plugin bug in the test program (type 'test.forgetful'): ", 0), 0u);
  }
}
