// The loader's pipeline (core/src/task_loader.cpp): a task file is checked completely before
// anything runs, every error is reported with its place, and what it says is escaped. Each stage
// has its own tests: yaml_reading_test, expansion_test, param_checking_test, graph_checking_test,
// task_params_test, overrides_test, profile_interfaces_test.
#include <gtest/gtest.h>

#include <string>

#include <fba/task.hpp>
#include <fba/task_config.hpp>

#include "fixture_components.hpp"

using fba::test::errors_of;
using fba::test::kChain;
using fba::test::load;

TEST(Loader, AValidChainLoadsWithDefaultsFilledIn) {
  const auto task = load(kChain);
  ASSERT_EQ(task.components.size(), 3u);
  const auto* sink = task.find("sink");
  ASSERT_NE(sink, nullptr);
  EXPECT_EQ(std::get<std::int64_t>(sink->params.at("expected")), 0);
  ASSERT_EQ(task.connections.size(), 2u);
  EXPECT_EQ(task.connections[1].type->name, "fba.Int");  // resolved through the passthrough
}

TEST(Loader, EveryErrorIsReportedNotJustTheFirst) {
  const auto e = errors_of(R"(
components:
  a: { type: examples.counter, params: { count: -1 } }
  b: { type: examples.sink, params: { expectd: 3 } }
)");
  EXPECT_NE(e.find("test.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("must be in [0, inf]"), std::string::npos) << e;
  EXPECT_NE(e.find("test.yaml:4:"), std::string::npos) << e;
  EXPECT_NE(e.find("no parameter 'expectd'"), std::string::npos) << e;
}

TEST(Loader, DotShowsCompositesFeedbackAndRules) {
  const auto task = load(R"(
components:
  src: { type: examples.counter }
  relay: { type: examples.relay }
  m: { type: test.merge }
  c: { type: test.countdown }
connections:
  - src.out -> relay.in
  - relay.out -> m.a
  - m.out -> c.in
  - { from: c.out, to: m.b, feedback: true }
on:
  src.finished: stop_success
)");
  const std::string dot = fba::to_dot(task);
  EXPECT_NE(dot.find("subgraph \"cluster_relay\""), std::string::npos) << dot;
  EXPECT_NE(dot.find("style=dashed"), std::string::npos) << dot;
  EXPECT_NE(dot.find("\"stop: success\""), std::string::npos) << dot;
}

TEST(Loader, RawControlBytesAreEscapedInMessages) {
  const auto e = errors_of("components:\n  a: { type: \"ex\\0am\\x1bple\" }\n");
  EXPECT_NE(e.find("unknown component type 'ex\\x00am\\x1bple'"), std::string::npos) << e;
}

// A newline in a name is shown as \n, so that the name printed is the name given.
TEST(Loader, NewlinesTabsAndReturnsAreEscapedAsInC) {
  const auto e = errors_of("components:\n  a: { type: \"ex\\nam\\tp\\rle\" }\n");
  EXPECT_NE(e.find("unknown component type 'ex\\nam\\tp\\rle'"), std::string::npos) << e;
}
