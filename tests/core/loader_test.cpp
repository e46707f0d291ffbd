// Task files are checked completely before anything runs; errors say where and what.
#include <gtest/gtest.h>

#include <fba/task_config.hpp>

#include "test_components.hpp"

using fba::test::load;

namespace {

std::string errors_of(const std::string& yaml, const fba::LoadOptions& options = {}) {
  try {
    load(yaml, options);
  } catch (const fba::ConfigError& e) {
    return e.what();
  }
  return "";
}

const char* kChain = R"(
components:
  source: { type: examples.counter, params: { count: 5 } }
  pass: { type: examples.passthrough }
  sink: { type: examples.sink }
connections:
  - source.out -> pass.in
  - pass.out -> sink.in
)";

}  // namespace

TEST(Loader, AValidChainLoadsWithDefaultsFilledIn) {
  const auto task = load(kChain);
  ASSERT_EQ(task.components.size(), 3u);
  const auto* sink = task.find("sink");
  ASSERT_NE(sink, nullptr);
  EXPECT_EQ(std::get<std::int64_t>(sink->params.at("expected")), 0);
  ASSERT_EQ(task.connections.size(), 2u);
  EXPECT_EQ(task.connections[1].type->name, "fba.Int");  // resolved through the passthrough
}

TEST(Loader, UnknownTypeSuggestsTheClosestName) {
  const auto e = errors_of("components:\n  a: { type: examples.countr }\n");
  EXPECT_NE(e.find("test.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean examples.counter"), std::string::npos) << e;
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

TEST(Loader, ParameterTypesAreChecked) {
  EXPECT_NE(errors_of("components:\n  a: { type: examples.counter, params: { count: many } }\n").find("expects a whole number; found 'many'"),
            std::string::npos);
  EXPECT_NE(errors_of("components:\n  a: { type: examples.counter, params: { rate: [1] } }\n").find("expects a double; found a list"),
            std::string::npos);
}

TEST(Loader, ChoicesAreChecked) {
  const auto e = errors_of("components:\n  r: { type: test.reader, params: { file: loader_test.cpp, mode: words } }\n");
  EXPECT_NE(e.find("must be one of: bytes, lines; found 'words'"), std::string::npos) << e;
}

TEST(Loader, RequiredParametersMustBeGiven) {
  const auto e = errors_of("components:\n  r: { type: test.reader }\n");
  EXPECT_NE(e.find("needs parameter 'file'"), std::string::npos) << e;
}

TEST(Loader, RelativePathsResolveAgainstTheTaskFile) {
  const auto task = load("components:\n  r: { type: test.reader, params: { file: loader_test.cpp } }\n");
  const std::string path = std::get<std::string>(task.find("r")->params.at("file"));
  EXPECT_EQ(path, (std::filesystem::path(FBA_TEST_SOURCE_DIR) / "loader_test.cpp").string());
  EXPECT_NE(errors_of("components:\n  r: { type: test.reader, params: { file: nowhere.txt } }\n").find("does not exist"), std::string::npos);
}

TEST(Loader, UnknownPortsListTheValidOnes) {
  const auto e = errors_of("components:\n  a: { type: examples.counter }\n  b: { type: examples.sink }\nconnections:\n  - a.output -> b.in\n");
  EXPECT_NE(e.find("test.yaml:5:"), std::string::npos) << e;
  EXPECT_NE(e.find("has no output 'output'; its outputs: out"), std::string::npos) << e;
}

TEST(Loader, ConnectionTypesMustMatch) {
  const auto e = errors_of(R"(
components:
  a: { type: examples.counter }
  l: { type: test.event_log }
  s: { type: examples.sink }
connections:
  - a.out -> l.events
  - l.names -> s.in
)");
  EXPECT_NE(e.find("type mismatch: 'a.out' carries 'fba.Int' but 'l.events' takes 'fba.Event'"), std::string::npos) << e;
}

TEST(Loader, AnInputTakesOneConnection) {
  const auto e = errors_of(R"(
components:
  a: { type: examples.counter }
  b: { type: examples.counter }
  s: { type: examples.sink }
connections:
  - a.out -> s.in
  - b.out -> s.in
)");
  EXPECT_NE(e.find("is connected already (at test.yaml:7:"), std::string::npos) << e;
}

TEST(Loader, CyclesMustBeMarked) {
  const char* cycle = R"(
components:
  src: { type: examples.counter }
  m: { type: test.merge }
  c: { type: test.countdown }
connections:
  - src.out -> m.a
  - m.out -> c.in
  - { from: c.out, to: m.b%s }
)";
  char unmarked[512], marked[512];
  std::snprintf(unmarked, sizeof unmarked, cycle, "");
  std::snprintf(marked, sizeof marked, cycle, ", feedback: true");
  const auto e = errors_of(unmarked);
  EXPECT_NE(e.find("is not marked"), std::string::npos) << e;
  EXPECT_EQ(errors_of(marked), "");
}

TEST(Loader, OverridesReplaceFileValuesAndAreChecked) {
  fba::LoadOptions o;
  o.overrides = {{"source.count=42"}};
  EXPECT_EQ(std::get<std::int64_t>(load(kChain, o).find("source")->params.at("count")), 42);
  o.overrides = {{"source.count=-3"}};
  EXPECT_NE(errors_of(kChain, o).find("--set source.count=-3: error: parameter 'count' must be in"), std::string::npos);
  o.overrides = {{"nobody.count=3"}};
  EXPECT_NE(errors_of(kChain, o).find("no component 'nobody'"), std::string::npos);
}

TEST(Loader, CompositesFlattenWithPrefixedNames) {
  const auto task = load(R"(
components:
  src: { type: examples.counter }
  relay: { type: examples.relay }
  sink: { type: examples.sink }
connections:
  - src.out -> relay.in
  - relay.out -> sink.in
)");
  EXPECT_NE(task.find("relay/first"), nullptr);
  EXPECT_NE(task.find("relay/second"), nullptr);
  bool into_first = false, out_of_second = false;
  for (const auto& c : task.connections) {
    into_first |= c.from == "src" && c.to == "relay/first";
    out_of_second |= c.from == "relay/second" && c.to == "sink";
  }
  EXPECT_TRUE(into_first);
  EXPECT_TRUE(out_of_second);
}

TEST(Loader, IncludesAreResolvedAgainstTheTaskFile) {
  const auto e = errors_of("include: [missing.yaml]\ncomponents: {}\n");
  EXPECT_NE(e.find("test.yaml:1:11: error: included file 'missing.yaml' does not exist"), std::string::npos) << e;
}

TEST(Loader, YamlSyntaxErrorsPointAtTheirPlace) {
  const auto e = errors_of("components:\n  a: { type: examples.counter\n");
  EXPECT_NE(e.find("test.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("YAML syntax"), std::string::npos) << e;
}

TEST(Loader, EventRulesNameDeclaredEvents) {
  const auto e = errors_of(std::string(kChain) + "on:\n  sink.finishd: stop_success\n");
  EXPECT_NE(e.find("emits no event 'finishd'; its events: done, gap, safe_state, error, finished"), std::string::npos) << e;
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
