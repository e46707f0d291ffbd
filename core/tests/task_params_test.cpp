// Task-level parameters (`params:` of a task, `--set name=value`) and profiles that bind a task's
// device slots to component types: substituted and checked like literals, every mistake reported
// with its place.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>

#include <fba/task.hpp>
#include <fba/task_config.hpp>
#include <nlohmann/json.hpp>

#include "support/slotted_task.hpp"
#include "support/temp_dir.hpp"
#include "fixture_components.hpp"

namespace {

namespace fs = std::filesystem;
using fba::test::errors_of;
using fba::test::kPassProfile;
using fba::test::kSlottedTask;
using fba::test::load;
using fba::test::TempDir;

fba::LoadOptions with_sets(std::vector<std::string> sets, std::string profile = "") {
  fba::LoadOptions o;
  for (auto& s : sets) o.overrides.push_back({std::move(s)});
  o.profile = std::move(profile);
  return o;
}

std::string load_errors(const fs::path& file, const fba::LoadOptions& options = {}) {
  try {
    fba::load_task(file, fba::test::registry(), options);
  } catch (const fba::ConfigError& e) {
    return e.what();
  }
  return "";
}

const char* kParamTask = R"(
params:
  n: { type: int, default: 5, min: 1, doc: how many samples }
  cap: { type: int, default: 4, doc: queue length }
components:
  source: { type: examples.counter, params: { count: "${n}" } }
  sink: { type: examples.sink, params: { expected: "${n}" } }
connections:
  - { from: source.out, to: sink.in, capacity: "${cap}" }
)";

}  // namespace

TEST(TaskParams, AreSubstitutedIntoComponentParamsAndCapacities) {
  const auto task = load(kParamTask);
  EXPECT_EQ(std::get<std::int64_t>(task.find("source")->params.at("count")), 5);
  EXPECT_EQ(std::get<std::int64_t>(task.find("sink")->params.at("expected")), 5);
  EXPECT_EQ(task.connections.at(0).capacity, 4u);
  ASSERT_EQ(task.params.size(), 2u);
  EXPECT_EQ(task.params[0].name, "n");
  EXPECT_EQ(task.params[0].source, "default");
}

TEST(TaskParams, SetByNameWithoutADot) {
  const auto task = load(kParamTask, with_sets({"n=7", "cap=2"}));
  EXPECT_EQ(std::get<std::int64_t>(task.find("source")->params.at("count")), 7);
  EXPECT_EQ(std::get<std::int64_t>(task.find("sink")->params.at("expected")), 7);
  EXPECT_EQ(task.connections.at(0).capacity, 2u);
  EXPECT_EQ(task.params[0].source, "--set");
}

TEST(TaskParams, ValuesAreCheckedByTheRulesOfALiteral) {
  // The parameter's own range, at the --set.
  EXPECT_NE(errors_of(kParamTask, with_sets({"n=0"})).find("--set n=0: error: parameter 'n' must be in [1, inf]; found 0 (declared at test.yaml:3:3)"),
            std::string::npos);
  // The capacity's range, checked where the parameter is used, said at the --set that gave the value.
  const std::string e = errors_of(kParamTask, with_sets({"cap=0"}));
  EXPECT_NE(e.find("--set cap=0: error: capacity must be in [1, 1000000]; found 0 (capacity is ${cap} at test.yaml:9:48)"), std::string::npos)
      << e;
  // The type of the component parameter it is substituted into.
  const std::string t = errors_of(R"(
params: { label: { type: string, default: many } }
components:
  source: { type: examples.counter, params: { count: "${label}" } }
  sink: { type: examples.sink }
connections: [ source.out -> sink.in ]
)");
  EXPECT_NE(t.find("test.yaml:4:54: error: parameter 'count' expects a int; found 'many' (from a parameter)"), std::string::npos) << t;
}

TEST(TaskParams, AnUnknownNameListsTheDeclaredOnes) {
  const std::string e = errors_of(kParamTask, with_sets({"m=3"}));
  EXPECT_NE(e.find("--set m=3: error: --set m: the task has no parameter 'm'; its parameters: cap, n"), std::string::npos) << e;
  const std::string r = errors_of(R"(
params: { n: { type: int, default: 1 } }
components:
  source: { type: examples.counter, params: { count: "${m}" } }
  sink: { type: examples.sink }
connections: [ source.out -> sink.in ]
)");
  EXPECT_NE(r.find("test.yaml:4:54: error: unknown task parameter '${m}'; the parameters here: n"), std::string::npos) << r;
}

TEST(TaskParams, OneWithoutADefaultMustBeSet) {
  const char* yaml = R"(
params:
  n: { type: int, doc: how many }
components:
  source: { type: examples.counter, params: { count: "${n}" } }
  sink: { type: examples.sink }
connections: [ source.out -> sink.in ]
)";
  const std::string e = errors_of(yaml);
  EXPECT_NE(e.find("test.yaml:3:3: error: task parameter 'n' has no default; set it with --set n=VALUE"), std::string::npos) << e;
  EXPECT_EQ(e.find("unknown parameter"), std::string::npos) << e;  // said once, not at every use
  EXPECT_EQ(std::get<std::int64_t>(load(yaml, with_sets({"n=2"})).find("source")->params.at("count")), 2);
}

TEST(TaskParams, SettingOneUserOfASharedParameterIsRefused) {
  const std::string e = errors_of(kParamTask, with_sets({"sink.expected=9"}));
  EXPECT_NE(e.find("--set sink.expected=9: error: sink.expected comes from the task parameter 'n' (also source.count); "
                   "set it with --set n=..."),
            std::string::npos)
      << e;
  // A parameter with one user can be set either way.
  const auto task = load(R"(
params: { n: { type: int, default: 5 } }
components:
  source: { type: examples.counter, params: { count: "${n}" } }
  sink: { type: examples.sink }
connections: [ source.out -> sink.in ]
)", with_sets({"source.count=9"}));
  EXPECT_EQ(std::get<std::int64_t>(task.find("source")->params.at("count")), 9);
}

// Through its only use, the --set sets the task parameter: --check and summary.json show the value
// that runs, and the parameter's own declaration still holds.
TEST(TaskParams, SettingTheOnlyUseOfATaskParameterSetsTheParameter) {
  const char* yaml = R"(
params: { n: { type: int, default: 5, min: 1 } }
components:
  source: { type: examples.counter, params: { count: "${n}" } }
  sink: { type: examples.sink }
connections: [ source.out -> sink.in ]
)";
  const auto task = load(yaml, with_sets({"source.count=9"}));
  ASSERT_EQ(task.params.size(), 1u);
  EXPECT_EQ(std::get<std::int64_t>(task.params[0].value), 9);
  EXPECT_EQ(task.params[0].source, "--set source.count");
  const auto summary = nlohmann::json::parse(fba::summary_json(fba::RunResult{}, task));
  EXPECT_EQ(summary["params"]["n"]["value"], 9);
  EXPECT_EQ(summary["params"]["n"]["source"], "--set source.count");
  const std::string e = errors_of(yaml, with_sets({"source.count=0"}));
  EXPECT_NE(e.find("--set source.count=0: error: parameter 'n' must be in [1, inf]; found 0 (source.count is ${n}, declared at test.yaml:2:11)"),
            std::string::npos)
      << e;
}

// --set depth=3 --set carver.max_depth=8 ran the carver at 8 while --check and summary.json said 3.
TEST(TaskParams, ASetOfATaskParameterAndOneOfAComponentParameterItFeedsConflict) {
  const std::string sole = errors_of(R"(
params: { n: { type: int, default: 5 } }
components:
  source: { type: examples.counter, params: { count: "${n}" } }
  sink: { type: examples.sink }
connections: [ source.out -> sink.in ]
)", with_sets({"n=3", "source.count=8"}));
  EXPECT_NE(sole.find("--set source.count=8: error: --set source.count=8 conflicts with --set n=3: source.count is ${n} (test.yaml:4:54); "
                      "set one of them"),
            std::string::npos)
      << sole;
  const std::string shared = errors_of(kParamTask, with_sets({"sink.expected=9", "n=3"}));
  EXPECT_NE(shared.find("--set sink.expected=9: error: --set sink.expected=9 conflicts with --set n=3: sink.expected is ${n} (test.yaml:7:52)"),
            std::string::npos)
      << shared;
}

TEST(TaskParams, AComponentParameterMadeFromATaskParameterIsSetThroughIt) {
  const std::string e = errors_of(R"(
params: { what: { type: string, default: disk } }
components:
  source: { type: examples.counter }
  bad: { type: examples.faulty, params: { message: "${what} failed" } }
connections: [ source.out -> bad.in ]
)", with_sets({"bad.message=all is well"}));
  EXPECT_NE(e.find("--set bad.message=all is well: error: bad.message is '${what} failed' (test.yaml:5:52), made from the task parameter what; "
                   "set it with --set what=..."),
            std::string::npos)
      << e;
}

// The value typed is what must change: an error it causes where the file uses it is said at the --set.
TEST(TaskParams, AnErrorCausedByASetValueIsSaidAtTheSet) {
  const char* yaml = R"(
params: { d: { type: double, default: 1 } }
components:
  source: { type: examples.counter }
  sink: { type: examples.sink, params: { delay: "${d}" } }
connections: [ source.out -> sink.in ]
)";
  const std::string direct = errors_of(yaml, with_sets({"d=20"}));
  EXPECT_NE(direct.find("--set d=20: error: parameter 'delay' must be in [0, 10]; found 20 (sink.delay is ${d} at test.yaml:5:49)"),
            std::string::npos)
      << direct;
  EXPECT_EQ(direct.find("test.yaml:5:49: error"), std::string::npos) << direct;
  const std::string through = errors_of(yaml, with_sets({"sink.delay=20"}));
  EXPECT_NE(through.find("--set sink.delay=20: error: parameter 'delay' must be in [0, 10]; found 20 (sink.delay is ${d} at test.yaml:5:49)"),
            std::string::npos)
      << through;
  // A value from the file is still said at the file.
  const std::string file = errors_of(R"(
params: { d: { type: double, default: 20 } }
components:
  source: { type: examples.counter }
  sink: { type: examples.sink, params: { delay: "${d}" } }
connections: [ source.out -> sink.in ]
)");
  EXPECT_NE(file.find("test.yaml:5:49: error: parameter 'delay' must be in [0, 10]; found 20"), std::string::npos) << file;
}

// `--set "scene.mesh=/d/banana.obj #mustard.obj"` loaded /d/banana.obj: the '#' was read as a YAML comment.
TEST(TaskParams, ASetValueForAStringOrAPathIsTakenAsWrittenWhole) {
  const char* chain = R"(
components:
  source: { type: examples.counter, params: { count: 2 } }
  bad: { type: examples.faulty }
  sink: { type: examples.sink }
connections: [ source.out -> bad.in, bad.out -> sink.in ]
)";
  auto message = [&](const std::string& set) { return std::get<std::string>(load(chain, with_sets({set})).find("bad")->params.at("message")); };
  EXPECT_EQ(message("bad.message=disk #2 failed"), "disk #2 failed");
  EXPECT_EQ(message("bad.message=\"quoted\""), "\"quoted\"");  // the shell's quotes are gone; these are the value's
  EXPECT_EQ(message("bad.message= [1, 2]"), " [1, 2]");
  EXPECT_EQ(message("bad.message="), "");
  // Numbers, bools and lists are read as YAML, as before.
  EXPECT_EQ(std::get<std::int64_t>(load(chain, with_sets({"source.count=3 # three"})).find("source")->params.at("count")), 3);
  EXPECT_NE(errors_of(chain, with_sets({"bad.fail_after=[1]"})).find("--set bad.fail_after=[1]: error: parameter 'fail_after' expects a int; found a list"),
            std::string::npos);
  // A path: whole, with '#', spaces or a newline in it; the newline shown as \n in a message.
  const fba::test::TempDir dir;
  const char* reader = R"(
params: { data: { type: path } }
components:
  reader: { type: test.reader, params: { file: "${data}" } }
)";
  for (const std::string name : {"banana.obj #mustard.obj", "two\nlines.obj"}) {
    const std::string path = dir.file(name, "v 0 0 0\n");
    const auto task = load(reader, with_sets({"data=" + path}));
    EXPECT_EQ(std::get<std::string>(task.params.at(0).value), path);
    EXPECT_EQ(std::get<std::string>(task.find("reader")->params.at("file")), path);
  }
  const std::string missing = (dir.path() / "no\nsuch.obj").string();
  const std::string e = errors_of(reader, with_sets({"data=" + missing}));
  EXPECT_NE(e.find("error: parameter 'data': path '" + dir.path().string() + "/no\\nsuch.obj' does not exist"), std::string::npos) << e;
}

// scene.mesh, scene.x: one group of parameters, set and used by the whole dotted name.
const char* kGroupTask = R"(
params:
  run.count: { type: int, default: 5, min: 1 }
  run.cap: { type: int, default: 4 }
components:
  source: { type: examples.counter, params: { count: "${run.count}" } }
  sink: { type: examples.sink, params: { expected: "${run.count}" } }
connections:
  - { from: source.out, to: sink.in, capacity: "${run.cap}" }
)";

TEST(TaskParams, WordsJoinedByDotsGroupThemAndAreSetByTheWholeName) {
  const auto task = load(kGroupTask, with_sets({"run.count=7"}));
  EXPECT_EQ(std::get<std::int64_t>(task.find("source")->params.at("count")), 7);
  EXPECT_EQ(std::get<std::int64_t>(task.find("sink")->params.at("expected")), 7);
  EXPECT_EQ(task.connections.at(0).capacity, 4u);
  ASSERT_EQ(task.params.size(), 2u);
  EXPECT_EQ(task.params[0].name, "run.count");
  EXPECT_EQ(task.params[0].source, "--set");
  // A member the group does not have: the group's members, not "no component 'run'".
  const std::string e = errors_of(kGroupTask, with_sets({"run.size=3"}));
  EXPECT_NE(e.find("--set run.size=3: error: --set run.size: the task has no parameter 'run.size'; its group 'run' has run.count, run.cap"),
            std::string::npos)
      << e;
  // The shared parameter's message names the whole name to set.
  const std::string shared = errors_of(kGroupTask, with_sets({"sink.expected=2"}));
  EXPECT_NE(shared.find("sink.expected comes from the task parameter 'run.count' (also source.count); set it with --set run.count=..."),
            std::string::npos)
      << shared;
}

TEST(TaskParams, AGroupNamedAfterAComponentOrABadDottedNameIsRefusedAtItsPlace) {
  // --set sink.expected=... would mean either.
  const std::string clash = errors_of(R"(
params:
  sink.expected: { type: int, default: 5 }
components:
  source: { type: examples.counter }
  sink: { type: examples.sink }
connections: [ source.out -> sink.in ]
)");
  EXPECT_NE(clash.find("test.yaml:3:3: error: parameter 'sink.expected' has the form of component 'sink''s parameter 'expected'"),
            std::string::npos)
      << clash;
  for (const char* name : {"run..count", ".count", "run.", "run.co-unt"}) {
    const std::string bad = errors_of(std::string("\nparams:\n  \"") + name + R"(": { type: int, default: 5 }
components:
  source: { type: examples.counter }
  sink: { type: examples.sink }
connections: [ source.out -> sink.in ]
)");
    EXPECT_NE(bad.find("test.yaml:3:3: error: parameter name '" + std::string(name) + "' must be letters, digits and '_'"), std::string::npos)
        << name << "\n" << bad;
  }
}

TEST(Profiles, BindTheSlotsToTypesAndTheirParams) {
  TempDir dir;
  const auto file = dir.write("task.yaml", kSlottedTask);
  dir.write("profiles/pass.yaml", kPassProfile);
  const auto task = fba::load_task(file, fba::test::registry(), with_sets({"n=4"}, "pass"));
  EXPECT_EQ(task.profile, "pass");
  ASSERT_EQ(task.slots.size(), 2u);
  EXPECT_EQ(task.find("source")->type->spec.type_name(), "examples.counter");
  EXPECT_EQ(std::get<std::int64_t>(task.find("source")->params.at("count")), 4);
  EXPECT_EQ(task.find("pass")->type->spec.type_name(), "examples.passthrough");
  EXPECT_EQ(task.find_slot("pass")->doc, "what forwards them");
  EXPECT_EQ(task.find_slot("source")->bound.str(), (file.parent_path() / "profiles" / "pass.yaml").string() + ":4:3");
  EXPECT_EQ(task.find_slot("source")->where.str(), file.string() + ":5:3");
  // The bound task runs like any other.
  fba::Task run(task, fba::test::with(fba::ExecutorKind::Deterministic));
  const auto r = run.run();
  EXPECT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  ASSERT_TRUE(r.final_event);
  EXPECT_EQ(r.final_event->source, "sink");
  // summary.json names the profile and the task parameters' values.
  const auto summary = nlohmann::json::parse(fba::summary_json(r, task));
  EXPECT_EQ(summary["profile"]["name"], "pass");
  EXPECT_EQ(summary["params"]["n"]["value"], 4);
  EXPECT_EQ(summary["params"]["n"]["source"], "--set");
}

TEST(Profiles, TheTasksProfileKeyIsTheDefaultAndOptionsOverrideIt) {
  TempDir dir;
  const auto file = dir.write("task.yaml", std::string(kSlottedTask) + "profile: pass\n");
  dir.write("profiles/pass.yaml", kPassProfile);
  dir.write("profiles/faulty.yaml", R"(
components:
  source: { type: examples.counter, params: { count: "${n}" } }
  pass: { type: examples.faulty }
)");
  EXPECT_EQ(fba::load_task(file, fba::test::registry()).find("pass")->type->spec.type_name(), "examples.passthrough");
  EXPECT_EQ(fba::load_task(file, fba::test::registry(), with_sets({}, "faulty")).find("pass")->type->spec.type_name(), "examples.faulty");
  // A path: relative to the working folder.
  const auto by_path = fba::load_task(file, fba::test::registry(), with_sets({}, (dir.write("elsewhere/p.yaml", kPassProfile)).string()));
  EXPECT_EQ(by_path.profile, "pass");
}

// Simulated devices make a virtual clock valid, real ones do not: the profile's executor
// overrides the task file's (--executor, a RunOptions field, overrides both).
TEST(Profiles, AProfileChoosesTheExecutorForTheDevicesItBinds) {
  TempDir dir;
  const auto file = dir.write("task.yaml", std::string(kSlottedTask) + "executor: threaded\n");
  dir.write("profiles/pass.yaml", kPassProfile);
  dir.write("profiles/virtual.yaml", std::string(kPassProfile) + "executor: deterministic\n");
  EXPECT_EQ(fba::load_task(file, fba::test::registry(), with_sets({}, "pass")).executor, fba::ExecutorKind::Threaded);
  EXPECT_EQ(fba::load_task(file, fba::test::registry(), with_sets({}, "virtual")).executor, fba::ExecutorKind::Deterministic);
  dir.write("profiles/bad.yaml", std::string(kPassProfile) + "executor: realtime\n");
  const std::string e = load_errors(file, with_sets({}, "bad"));
  EXPECT_NE(e.find("profiles/bad.yaml:6:11: error: executor 'realtime' is not one of: threaded, deterministic"), std::string::npos) << e;
}

TEST(Profiles, ATaskWithSlotsAndNoProfileNamesTheProfilesBesideIt) {
  TempDir dir;
  const auto file = dir.write("task.yaml", kSlottedTask);
  dir.write("profiles/pass.yaml", kPassProfile);
  dir.write("profiles/other.yaml", kPassProfile);
  const std::string e = load_errors(file);
  EXPECT_NE(e.find("task.yaml:5:3: error: the task has device slots (source, pass) and no profile binds them; choose one with "
                   "--profile NAME or 'profile: NAME' in the task; profiles next to the task: other, pass"),
            std::string::npos)
      << e;
  const std::string m = load_errors(file, with_sets({}, "nope"));
  EXPECT_NE(m.find("--profile nope: error: profile 'nope': the file does not exist"), std::string::npos) << m;
  EXPECT_NE(m.find("profiles next to the task: other, pass"), std::string::npos) << m;
}

TEST(Profiles, EverySlotIsBoundAndNothingElse) {
  TempDir dir;
  const auto file = dir.write("task.yaml", kSlottedTask);
  const auto profile = dir.write("profiles/bad.yaml", R"(profile: bad
components:
  source: { type: examples.counter }
  sink: { type: examples.sink }
  extra: { type: examples.sink }
)");
  const std::string e = load_errors(file, with_sets({}, "bad"));
  const std::string p = (fs::path(file).parent_path() / "profiles" / "bad.yaml").string();
  // The unbound slot at the task's line, naming the profile file.
  EXPECT_NE(e.find("task.yaml:6:3: error: slot 'pass' is not bound by profile 'bad' (" + p + ":1:1)"), std::string::npos) << e;
  // What the profile binds beyond the slots at the profile's line, naming the task's.
  EXPECT_NE(e.find(p + ":4:3: error: profile 'bad' binds 'sink', which is not a device slot of the task (" + file.string() +
                   "): the task defines it itself at " + file.string() + ":7:3; its slots: source, pass"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find(p + ":5:3: error: profile 'bad' binds 'extra', which is not a device slot"), std::string::npos) << e;
  (void)profile;
}

TEST(Profiles, ProfileParamsJoinTheTasksAndRelativePathsResolveInTheProfilesFolder) {
  TempDir dir;
  const auto file = dir.write("task.yaml", R"(
components:
  reader: { profile: true }
  other: { profile: true }
  sink: { type: examples.sink }
connections: [ reader.size -> sink.in ]
)");
  const auto data = dir.write("profiles/data.txt", "12345");
  dir.write("profiles/files.yaml", R"(
params:
  file: { type: path, default: data.txt }
components:
  reader: { type: test.reader, params: { file: "${file}" } }
  other: { type: test.reader, params: { file: data.txt } }
)");
  const auto task = fba::load_task(file, fba::test::registry(), with_sets({}, "files"));
  EXPECT_EQ(std::get<std::string>(task.find("reader")->params.at("file")), data.string());
  EXPECT_EQ(std::get<std::string>(task.find("other")->params.at("file")), data.string());
  ASSERT_EQ(task.params.size(), 1u);
  EXPECT_EQ(task.params[0].source, "profile default");
  // --set on a bound component works as on any other.
  const auto set = fba::load_task(file, fba::test::registry(), with_sets({"other.mode=lines"}, "files"));
  EXPECT_EQ(std::get<std::string>(set.find("other")->params.at("mode")), "lines");
}

TEST(Profiles, AParameterDeclaredByTaskAndProfileIsAnError) {
  TempDir dir;
  const auto file = dir.write("task.yaml", kSlottedTask);
  dir.write("profiles/twice.yaml", std::string(kPassProfile) + "params: { n: { type: int, default: 2 } }\n");
  const std::string e = load_errors(file, with_sets({}, "twice"));
  EXPECT_NE(e.find("error: parameter 'n' is declared by the task already (at " + file.string() + ":3:3)"), std::string::npos) << e;
}

// The mechanism behind `fba-run --check --profile`: two profiles whose slots offer the same
// interface are interchangeable; one that differs is found, and the difference said.
TEST(Profiles, SlotInterfacesShowWhetherProfilesAreInterchangeable) {
  TempDir dir;
  const auto file = dir.write("task.yaml", kSlottedTask);
  dir.write("profiles/pass.yaml", kPassProfile);
  dir.write("profiles/faulty.yaml", R"(
components:
  source: { type: examples.counter, params: { count: "${n}" } }
  pass: { type: examples.faulty, params: { fail_after: 100 } }
)");
  dir.write("profiles/countdown.yaml", R"(
components:
  source: { type: examples.counter, params: { count: "${n}" } }
  pass: { type: test.countdown }
)");
  const auto& reg = fba::test::registry();
  const auto pass = fba::load_task(file, reg, with_sets({}, "pass"));
  const auto faulty = fba::load_task(file, reg, with_sets({}, "faulty"));
  const auto countdown = fba::load_task(file, reg, with_sets({}, "countdown"));
  for (const char* slot : {"source", "pass"})
    EXPECT_TRUE(fba::interface_differences(fba::slot_interface(pass, slot), fba::slot_interface(faulty, slot)).empty()) << slot;
  const auto diff = fba::interface_differences(fba::slot_interface(pass, "pass"), fba::slot_interface(countdown, "pass"));
  ASSERT_EQ(diff.size(), 2u);
  EXPECT_EQ(diff[0], "input 'in': any in examples.passthrough, fba.Int in test.countdown");
  EXPECT_EQ(diff[1], "output 'out': like input 'in' in examples.passthrough, fba.Int in test.countdown");
  EXPECT_THROW(fba::slot_interface(pass, "sink"), std::out_of_range);  // a component, not a slot
  const std::string text = fba::describe(fba::slot_interface(pass, "pass"));
  EXPECT_EQ(text, "    inputs:  in (any)\n    outputs: out (like input 'in')\n    events:  error, finished\n");
}

// The profile's source.count and the task's sink.expected both take n.
TEST(Profiles, ASetOfAProfileComponentsParameterFollowsTheSameRules) {
  TempDir dir;
  const auto file = dir.write("task.yaml", kSlottedTask);
  const auto profile = dir.write("profiles/pass.yaml", kPassProfile);
  const std::string conflict = load_errors(file, with_sets({"n=4", "source.count=5"}, "pass"));
  EXPECT_NE(conflict.find("--set source.count=5: error: --set source.count=5 conflicts with --set n=4: source.count is ${n} (" +
                          profile.string() + ":4:54); set one of them"),
            std::string::npos)
      << conflict;
  const std::string shared = load_errors(file, with_sets({"source.count=5"}, "pass"));
  EXPECT_NE(shared.find("--set source.count=5: error: source.count comes from the task parameter 'n' (also sink.expected); set it with --set n=..."),
            std::string::npos)
      << shared;
}

// `--profile ''` (an unset shell variable) ran the task's default profile.
TEST(Profiles, AnEmptyProfileNameIsRefused) {
  TempDir dir;
  const auto file = dir.write("task.yaml", std::string(kSlottedTask) + "profile: pass\n");
  dir.write("profiles/pass.yaml", kPassProfile);
  auto given_empty = with_sets({});
  given_empty.profile_given = true;
  const std::string e = load_errors(file, given_empty);
  EXPECT_NE(e.find("--profile '': error: --profile expects a profile's name (profiles/NAME.yaml beside the task) or a file; found an empty "
                   "name; profiles next to the task: pass"),
            std::string::npos)
      << e;
  EXPECT_EQ(e.find("slot"), std::string::npos) << e;  // one error, not one per slot
  // Without --profile, the task's own.
  EXPECT_EQ(fba::load_task(file, fba::test::registry(), with_sets({})).profile, "pass");
  const auto empty_key = dir.write("empty.yaml", std::string(kSlottedTask) + "profile: ''\n");
  const std::string k = load_errors(empty_key);
  EXPECT_NE(k.find("empty.yaml:12:10: error: 'profile:' expects a profile's name"), std::string::npos) << k;
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
