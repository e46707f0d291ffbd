// Include and composite expansion (core/src/expansion.cpp): included composites become types,
// instances flatten into components named instance/inner, composite parameters are substituted and
// checked where they are used, and include mistakes are said once, at the include.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include <fba/task_config.hpp>

#include "support/temp_dir.hpp"
#include "fixture_components.hpp"

using fba::test::diagnostics_of_file;
using fba::test::errors_of;
using fba::test::errors_of_file;
using fba::test::kChain;
using fba::test::load;
using fba::test::TempDir;

TEST(Loader, UnknownTypeSuggestsTheClosestName) {
  const auto e = errors_of("components:\n  a: { type: examples.countr }\n");
  EXPECT_NE(e.find("test.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean examples.counter"), std::string::npos) << e;
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

TEST(Loader, AnIncludeCycleIsOneErrorWithoutFollowOnErrors) {
  TempDir dir;
  const char* composite = "composite: x.%s\ninclude: %s.yaml\ninputs:\n  in: inner.in\noutputs:\n  out: inner.out\ncomponents:\n  inner: { type: x.%s }\n";
  char a[256], b[256];
  std::snprintf(a, sizeof a, composite, "a", "b", "b");
  std::snprintf(b, sizeof b, composite, "b", "a", "a");
  dir.write("a.yaml", a);
  dir.write("b.yaml", b);
  const auto task = dir.write("t.yaml", R"(include: a.yaml
components:
  src: { type: examples.counter }
  r: { type: x.a }
  sink: { type: examples.sink }
connections:
  - src.out -> r.in
  - r.out -> sink.in
)");
  const auto d = diagnostics_of_file(task);
  ASSERT_EQ(d.size(), 1u) << errors_of_file(task);
  EXPECT_NE(d[0].message.find("include cycle: 'a.yaml' includes itself"), std::string::npos) << d[0].str();
  const auto itself = dir.write("self.yaml", "include: self.yaml\ncomponents:\n  a: { type: examples.counter }\n");
  EXPECT_NE(errors_of_file(itself).find("include cycle: 'self.yaml' includes itself"), std::string::npos) << errors_of_file(itself);
}

TEST(Loader, CompositeParametersAreRangeCheckedWhereverTheyAreSubstituted) {
  TempDir dir;
  dir.write("ticker.yaml", R"(composite: x.ticker
params:
  period: { type: double, default: 1 }
  restarts: { type: int, default: 1 }
  capacity: { type: int, default: 1 }
outputs:
  out: pass.out
components:
  src: { type: examples.counter, trigger: { policy: periodic, period: "${period}" }, on_error: { policy: restart, max_restarts: "${restarts}" } }
  pass: { type: examples.passthrough }
connections:
  - { from: src.out, to: pass.in, capacity: "${capacity}" }
)");
  const auto task = dir.write("t.yaml", R"(include: ticker.yaml
components:
  t: { type: x.ticker, params: { period: 1e10, restarts: 1000001, capacity: 4294967296 } }
)");
  const std::string e = errors_of_file(task);
  EXPECT_NE(e.find("ticker.yaml:9:71: error: period must be in (0, 1000000000] seconds; found 10000000000"), std::string::npos) << e;
  EXPECT_NE(e.find("ticker.yaml:9:129: error: max_restarts must be in [0, 1000000]; found 1000001"), std::string::npos) << e;
  EXPECT_NE(e.find("ticker.yaml:12:45: error: capacity must be in [1, 1000000]; found 4294967296"), std::string::npos) << e;
}

// A composite's parameters are set as instance.parameter: a dotted name there would read as
// another component's, so only a task's and a profile's parameters may be grouped with dots.
TEST(Loader, ACompositesParameterNameHasNoDot) {
  TempDir dir;
  dir.write("ticker.yaml", R"(composite: x.ticker
params:
  src.count: { type: int, default: 1 }
outputs:
  out: src.out
components:
  src: { type: examples.counter }
)");
  const auto task = dir.write("t.yaml", "include: ticker.yaml\ncomponents:\n  t: { type: x.ticker }\n");
  const std::string e = errors_of_file(task);
  EXPECT_NE(e.find("ticker.yaml:3:3: error: parameter name 'src.count' must be letters, digits and '_'"), std::string::npos) << e;
  EXPECT_EQ(e.find("make a group"), std::string::npos) << e;
}

TEST(Loader, AnEmptyIncludeNameIsRefusedAtItsPlace) {
  for (const std::string include : {"include: ''", "include: [composites/none.yaml, \"\"]"}) {
    const auto e = errors_of(include + kChain);
    EXPECT_NE(e.find("an include names a composite file, relative to this file's folder; found an empty name"), std::string::npos)
        << include << "\n" << e;
  }
  const auto e = errors_of(std::string("include: ''") + kChain);
  EXPECT_NE(e.find("test.yaml:1:10: error: an include names"), std::string::npos) << e;
}
