// The example tasks run headless and do what their files say, under both executors.
#include <gtest/gtest.h>

#include <fba/registry.hpp>

#include "support/built_plugins.hpp"
#include <fba/task.hpp>
#include "support/build_paths.hpp"

namespace {

using fba::test::built_plugins;

fba::TaskConfig example(const std::string& name, const fba::LoadOptions& o = {}) {
  return fba::load_task(fba::test::tasks_dir() + "/examples/" + name, built_plugins(), o);
}

class ExampleTasks : public ::testing::TestWithParam<fba::ExecutorKind> {
 protected:
  fba::RunOptions options() const {
    fba::RunOptions o;
    o.executor = GetParam();
    o.timeout_s = 120;
    return o;
  }
};

}  // namespace

INSTANTIATE_TEST_SUITE_P(Executors, ExampleTasks, ::testing::Values(fba::ExecutorKind::Threaded, fba::ExecutorKind::Deterministic),
                         [](const auto& info) { return std::string(fba::to_string(info.param)); });

TEST_P(ExampleTasks, ChainDeliversEverySampleAndStopsOnDone) {
  fba::Task task(example("chain.yaml"), options());
  const auto& arriving = task.tap("third.out");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  ASSERT_TRUE(r.final_event);
  EXPECT_EQ(r.final_event->source, "sink");
  EXPECT_EQ(r.final_event->name, "done");
  EXPECT_EQ(r.final_event->payload, "100000");
  ASSERT_EQ(arriving.size(), 100000u);
  EXPECT_EQ(arriving.back().get<std::int64_t>(), 99999);
}

TEST_P(ExampleTasks, CompositeTaskRunsThroughNestedComposites) {
  const auto cfg = example("composite.yaml");
  EXPECT_NE(cfg.find("pair/front/first"), nullptr);  // examples.relay_pair > examples.relay > passthrough
  fba::Task task(cfg, options());
  const auto& out = task.tap("pair/back/second.out");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  EXPECT_EQ(out.size(), 1000u);
  for (const auto& c : r.connections)
    if (c.from == "pair/front/second.out") EXPECT_EQ(c.delivered, 1000u);
}

TEST_P(ExampleTasks, OverridesChangeTheRun) {
  fba::LoadOptions o;
  o.overrides = {{"source.count=500"}, {"sink.expected=500"}};
  fba::Task task(example("chain.yaml", o), options());
  const auto r = task.run();
  ASSERT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  EXPECT_EQ(r.final_event->payload, "500");
}
