// Task files are checked completely before anything runs; errors say where and what.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <fba/task.hpp>
#include <fba/task_config.hpp>

#include "test_components.hpp"
#include "support/build_paths.hpp"

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

namespace fs = std::filesystem;

// A folder of its own for each test, removed at the end.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::path(testing::TempDir()) / "fba_loader_XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  fs::path write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name, std::ios::binary) << text;
    return path_ / name;
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::vector<fba::Diagnostic> diagnostics_of_file(const fs::path& file, const fba::LoadOptions& options = {}) {
  try {
    fba::load_task(file, fba::test::registry(), options);
  } catch (const fba::ConfigError& e) {
    return e.diagnostics();
  }
  return {};
}

std::string errors_of_file(const fs::path& file) {
  std::string s;
  for (const auto& d : diagnostics_of_file(file)) s += d.str() + "\n";
  return s;
}

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

// An alias is its anchor's node, tags and both styles are read, and a value's error names the line
// and column it was written at, also through an alias.
TEST(Loader, AnchorsTagsAndPlacesAreKeptThroughAliases) {
  const auto task = load(R"(
components:
  a: { type: examples.counter, params: &five { count: !!int 5 } }
  b:
    type: examples.counter
    params: *five
  sink: { type: examples.sink }
connections: [ a.out -> sink.in ]
)");
  EXPECT_EQ(std::get<std::int64_t>(task.find("b")->params.at("count")), 5);
  const auto e = errors_of(R"(
components:
  a: { type: examples.counter, params: &bad { count: -1 } }
  b:
    type: examples.counter
    params: *bad
)");
  EXPECT_NE(e.find("test.yaml:3:54: error: parameter 'count' must be in"), std::string::npos) << e;
  EXPECT_EQ(e.find("test.yaml:6:"), std::string::npos) << e;
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
  EXPECT_EQ(path, (std::filesystem::path(fba::test::source_dir() + "/tests/core") / "loader_test.cpp").string());
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

TEST(Loader, ATaskFileMustBeARegularFileAndSaysWhatItIsInstead) {
  TempDir dir;
  EXPECT_NE(errors_of_file(dir.path()).find("the task file is a directory; expected a regular file"), std::string::npos);
  EXPECT_NE(errors_of_file("/dev/zero").find("/dev/zero: error: the task file is a character device"), std::string::npos);
  const fs::path fifo = dir.path() / "task.fifo";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  // Opening a FIFO for reading would wait for a writer forever: the check comes first.
  EXPECT_NE(errors_of_file(fifo).find("the task file is a FIFO (a pipe)"), std::string::npos);
  EXPECT_NE(errors_of_file(dir.path() / "missing.yaml").find("the task file does not exist"), std::string::npos);
}

TEST(Loader, ATaskFileOverFourMebibytesIsRefusedBeforeItIsRead) {
  TempDir dir;
  const fs::path big = dir.write("big.yaml", "components:\n");
  fs::resize_file(big, (4u << 20) + 1);  // sparse: no disk or memory spent
  EXPECT_NE(errors_of_file(big).find("is 4194305 bytes; task and composite files are limited to 4 MiB (4194304 bytes)"), std::string::npos);
}

TEST(Loader, AnIncludedFifoOrDeviceSaysWhatItIs) {
  TempDir dir;
  ASSERT_EQ(mkfifo((dir.path() / "c.fifo").c_str(), 0600), 0);
  const auto task = dir.write("t.yaml", "include: [c.fifo, /dev/zero]\ncomponents:\n  a: { type: examples.counter }\n");
  const std::string e = errors_of_file(task);
  EXPECT_NE(e.find("t.yaml:1:11: error: included file 'c.fifo' is a FIFO (a pipe)"), std::string::npos) << e;
  EXPECT_NE(e.find("t.yaml:1:19: error: included file '/dev/zero' is a character device"), std::string::npos) << e;
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

TEST(Loader, OverridesGoThroughTheSameChecksWithSetAsTheirPlace) {
  fba::LoadOptions o;
  o.overrides = {{"source.count=3"}, {"source.count=4"}};
  EXPECT_NE(errors_of(kChain, o).find("--set source.count=4: error: 'source.count' is set twice on the command line (also by --set source.count=3)"),
            std::string::npos)
      << errors_of(kChain, o);
  o.overrides = {{"source.count={a: 1, a: 2}"}};
  EXPECT_NE(errors_of(kChain, o).find("--set source.count={a: 1, a: 2}: error: key 'a' is given twice in one mapping"), std::string::npos)
      << errors_of(kChain, o);
  o.overrides = {{"source.rate=1000001"}};
  EXPECT_NE(errors_of(kChain, o).find("--set source.rate=1000001: error: parameter 'rate' must be in [0, 1000000]; found 1000001"),
            std::string::npos)
      << errors_of(kChain, o);
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
  fba::RunOptions o;
  o.executor = fba::ExecutorKind::Deterministic;
  o.timeout_s = 60;
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 3 } }
  pass: { type: examples.passthrough }
on:
  src.finished: { deliver: pass.in }
)"),
                 o);
  const auto r = task.run();
  EXPECT_EQ(r.exit_code(), 0) << r.reason;
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

TEST(Loader, AnEmptyIncludeNameIsRefusedAtItsPlace) {
  for (const std::string include : {"include: ''", "include: [composites/none.yaml, \"\"]"}) {
    const auto e = errors_of(include + kChain);
    EXPECT_NE(e.find("an include names a composite file, relative to this file's folder; found an empty name"), std::string::npos)
        << include << "\n" << e;
  }
  const auto e = errors_of(std::string("include: ''") + kChain);
  EXPECT_NE(e.find("test.yaml:1:10: error: an include names"), std::string::npos) << e;
}

// A bound on a string, bool or path was ignored: the declaration seemed to limit what it did not.
TEST(Loader, MinAndMaxApplyToNumbersAndListsOnly) {
  const auto e = errors_of(R"(
params:
  on: { type: bool, default: true, max: 1 }
  where: { type: path, default: ., min: 0 }
  n: { type: int, default: 3, min: 1, max: 5 }
  gains: { type: list, default: [1, 2], max: 5 }
components:
  source: { type: examples.counter, params: { count: "${n}" } }
  sink: { type: examples.sink }
connections: [ source.out -> sink.in ]
)");
  EXPECT_NE(e.find("test.yaml:3:41: error: max applies to int and double parameters (and to every number of a list); 'on' is a bool parameter"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("test.yaml:4:41: error: min applies to int and double parameters (and to every number of a list); 'where' is a path parameter"),
            std::string::npos)
      << e;
  EXPECT_EQ(e.find("'n'"), std::string::npos) << e;
  EXPECT_EQ(e.find("'gains'"), std::string::npos) << e;
}
