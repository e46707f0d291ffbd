// Graph checking (core/src/graph_checking.cpp): connections, triggers and rules as they are read,
// then the whole graph: one producer per input, required inputs, marked cycles, matching types;
// through the loader, and check_graph called on a TaskConfig made without a task file.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <utility>

#include <fba/task.hpp>
#include <fba/task_config.hpp>

#include "graph_checking.hpp"
#include "fixture_components.hpp"

using fba::test::errors_of;
using fba::test::kChain;
using fba::test::load;
using fba::test::with;

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

TEST(Loader, AConnectionsByteBudgetIsReadAndRangeChecked) {
  const auto config = load(R"(
components:
  a: { type: examples.counter }
  s: { type: examples.sink }
connections:
  - { from: a.out, to: s.in, buffer: lossless, capacity: 4, max_bytes: 4096 }
)");
  ASSERT_EQ(config.connections.size(), 1u);
  EXPECT_EQ(config.connections[0].max_bytes, 4096u);
  EXPECT_EQ(config.connections[0].capacity, 4u);
  const auto e = errors_of(R"(
components:
  a: { type: examples.counter }
  s: { type: examples.sink }
connections:
  - { from: a.out, to: s.in, max_bytes: -1 }
)");
  EXPECT_NE(e.find("max_bytes"), std::string::npos) << e;
  EXPECT_NE(e.find("found -1"), std::string::npos) << e;
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

TEST(Loader, EventRulesNameDeclaredEvents) {
  const auto e = errors_of(std::string(kChain) + "on:\n  sink.finishd: stop_success\n");
  EXPECT_NE(e.find("emits no event 'finishd'; its events: done, gap, safe_state, error, finished"), std::string::npos) << e;
}

TEST(Loader, DeliveredEventsAreTypedAtCheckTime) {
  // Typed like its input, a passthrough that receives events sends fba.Event.
  const auto e = errors_of(R"(
components:
  src: { type: examples.counter }
  pass: { type: examples.passthrough }
  c: { type: test.countdown }
connections:
  - pass.out -> c.in
on:
  src.finished: { deliver: pass.in }
)");
  EXPECT_NE(e.find("test.yaml:7:5: error: type mismatch: 'pass.out' carries 'fba.Event' but 'c.in' takes 'fba.Int'"), std::string::npos) << e;
  const auto task = load(R"(
components:
  src: { type: examples.counter, params: { count: 3 } }
  pass: { type: examples.passthrough }
on:
  src.finished: { deliver: pass.in }
)");
  EXPECT_EQ(task.find("pass")->output_types.at("out")->name, "fba.Event");
}

TEST(Loader, ATaskThatPassesTheCheckRunsWithEventsDeliveredToAnAnyInput) {
  // The check passed and the run failed: the unconnected output was typed 'any' at run time.
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 3 } }
  pass: { type: examples.passthrough }
on:
  src.finished: { deliver: pass.in }
)"),
                 with(fba::ExecutorKind::Deterministic));
  const auto r = task.run();
  EXPECT_EQ(r.exit_code(), 0) << r.reason;
}

// The stage alone: components, connections and rules as the loader would leave them.
TEST(GraphChecking, ChecksATaskConfigMadeWithoutAFile) {
  fba::TaskConfig task;
  for (const auto& [name, type] : {std::pair{"src", "examples.counter"}, {"pass", "examples.passthrough"}, {"sink", "examples.sink"}}) {
    fba::ComponentConfig c;
    c.name = name;
    c.type = fba::test::registry().find(type);
    c.where = fba::Location{"t.yaml", static_cast<int>(task.components.size()) + 2, 3};
    task.components.push_back(std::move(c));
  }
  auto connect = [&](const char* from, const char* from_port, const char* to, const char* to_port, int line) {
    fba::ConnectionConfig c;
    c.from = from, c.from_port = from_port, c.to = to, c.to_port = to_port;
    c.where = fba::Location{"t.yaml", line, 5};
    task.connections.push_back(std::move(c));
  };
  connect("src", "out", "pass", "in", 6);
  connect("pass", "out", "sink", "in", 7);
  EXPECT_TRUE(fba::loader::check_graph(task, true).empty());
  EXPECT_EQ(task.connections[1].type->name, "fba.Int");  // the passthrough's output follows its input
  connect("src", "out", "sink", "in", 8);
  const auto twice = fba::loader::check_graph(task, true);
  ASSERT_EQ(twice.size(), 1u);
  EXPECT_EQ(twice[0].str(), "t.yaml:8:5: error: input 'sink.in' is connected already (at t.yaml:7:5); an input takes one connection");
  task.connections.pop_back();
  task.connections.erase(task.connections.begin());
  const auto unfed = fba::loader::check_graph(task, true);
  ASSERT_EQ(unfed.size(), 2u);
  EXPECT_NE(unfed[0].str().find("t.yaml:3:3: error: input 'in' of 'pass' (examples.passthrough, any) is required but not connected"),
            std::string::npos)
      << unfed[0].str();
  EXPECT_EQ(unfed[1].str(), "t.yaml:7:5: error: the type of 'pass.out' cannot be resolved: it follows an input that is not connected, or "
                            "only through a cycle");
  // The component harness feeds inputs itself: only the type is left unresolved.
  const auto harness = fba::loader::check_graph(task, false);
  ASSERT_EQ(harness.size(), 1u);
  EXPECT_EQ(harness[0].str(), unfed[1].str());
}
