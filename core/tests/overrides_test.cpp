// The --set options on their own (core/src/overrides.cpp): how one is split, and what a --set of a
// component parameter means when the task file writes that parameter with ${...}.
#include <gtest/gtest.h>

#include <fba/task_config.hpp>

#include "overrides.hpp"
#include "fixture_components.hpp"

using fba::test::errors_of;
using fba::test::kChain;
using fba::test::load;

TEST(SetOptions, SplitAtTheFirstEqualsSignAndTheLastDotBeforeIt) {
  std::string problem;
  const auto o = fba::parse_set("scene.mesh=/d/a=b.obj #mustard.obj", problem);
  ASSERT_TRUE(o) << problem;
  EXPECT_EQ(o->target, "scene.mesh");
  EXPECT_EQ(o->owner, "scene");
  EXPECT_EQ(o->param, "mesh");
  EXPECT_EQ(o->value, "/d/a=b.obj #mustard.obj");
  EXPECT_EQ(o->where().str(), "--set scene.mesh=/d/a=b.obj #mustard.obj");
  const auto plain = fba::parse_set("depth=", problem);
  ASSERT_TRUE(plain) << problem;
  EXPECT_EQ(plain->owner, "");
  EXPECT_EQ(plain->param, "depth");
  EXPECT_EQ(plain->value, "");
  const auto inner = fba::parse_set("pair/front/first.count=3", problem);
  ASSERT_TRUE(inner) << problem;
  EXPECT_EQ(inner->owner, "pair/front/first");
  for (const char* bad : {"depth", "=3", ".count=3", "source.=3", "source.co unt=3"}) {
    problem.clear();
    EXPECT_FALSE(fba::parse_set(bad, problem)) << bad;
    EXPECT_EQ(problem, "expected component.parameter=value, or parameter=value for a task parameter") << bad;
  }
}

TEST(SetOptions, StringsAndPathsAreTakenAsWrittenOtherTypesAreReadAsYaml) {
  EXPECT_TRUE(fba::taken_as_written(fba::ParamType::String));
  EXPECT_TRUE(fba::taken_as_written(fba::ParamType::Path));
  for (auto t : {fba::ParamType::Bool, fba::ParamType::Int, fba::ParamType::Double, fba::ParamType::DoubleList})
    EXPECT_FALSE(fba::taken_as_written(t)) << fba::to_string(t);
}

TEST(SetOptions, AMalformedOrRepeatedOneIsAnErrorAtItself) {
  const fba::Overrides o({{"n=1"}, {"n"}, {"n=2"}});
  ASSERT_EQ(o.errors().size(), 2u);
  EXPECT_EQ(o.errors()[0].str(), "--set n: error: expected component.parameter=value, or parameter=value for a task parameter");
  EXPECT_EQ(o.errors()[1].str(), "--set n=2: error: 'n' is set twice on the command line (also by --set n=1)");
  ASSERT_EQ(o.unused().size(), 1u);
  EXPECT_EQ(o.unused()[0]->text, "n=1");
}

TEST(SetOptions, ALiteralComponentParameterIsSetDirectly) {
  fba::Overrides o({{"source.count=9"}});
  EXPECT_EQ(o.for_task_param("count"), nullptr);
  const auto c = o.for_component_param("source.count");
  ASSERT_NE(c.option, nullptr);
  EXPECT_TRUE(c.apply);
  EXPECT_EQ(c.refusal, "");
  EXPECT_TRUE(o.unused().empty());
}

// The value shown for the task parameter (--check, summary.json) is then the value that runs.
TEST(SetOptions, TheOnlyUseOfATaskParameterSetsTheParameter) {
  fba::Overrides o({{"carver.max_depth=8"}});
  o.add_use({"carver.max_depth", true, "${depth}", {"grasp.yaml", 51, 26}, {"depth"}, true});
  const fba::SetOption* s = o.for_task_param("depth");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->target, "carver.max_depth");
  const auto c = o.for_component_param("carver.max_depth");
  EXPECT_FALSE(c.apply);
  EXPECT_EQ(c.refusal, "");
  EXPECT_TRUE(o.unused().empty());
  // An error at the use is the --set's.
  const auto b = o.blame({"grasp.yaml", 51, 26});
  ASSERT_TRUE(b);
  EXPECT_EQ(b->set.str(), "--set carver.max_depth=8");
  EXPECT_EQ(b->use, "carver.max_depth is ${depth} at grasp.yaml:51:26");
  EXPECT_FALSE(o.blame({"grasp.yaml", 51, 10}));
}

TEST(SetOptions, ASetOfATaskParameterAndOneOfAComponentParameterItFeedsConflict) {
  fba::Overrides o({{"depth=3"}, {"carver.max_depth=8"}});
  o.add_use({"carver.max_depth", true, "${depth}", {"tasks/grasp.yaml", 51, 26}, {"depth"}, true});
  const fba::SetOption* s = o.for_task_param("depth");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->text, "depth=3");
  const auto c = o.for_component_param("carver.max_depth");
  EXPECT_FALSE(c.apply);
  EXPECT_EQ(c.refusal, "--set carver.max_depth=8 conflicts with --set depth=3: carver.max_depth is ${depth} (tasks/grasp.yaml:51:26); "
                       "set one of them");
  EXPECT_EQ(o.blame({"tasks/grasp.yaml", 51, 26})->set.str(), "--set depth=3");
}

TEST(SetOptions, AComponentParameterSharedWithOthersOrMadeFromTaskParametersIsRefused) {
  fba::Overrides o({{"camera.mesh=/d/banana.obj"}, {"out.file=/tmp/x"}});
  o.add_use({"camera.mesh", true, "${scene.mesh}", {"sim.yaml", 20, 22}, {"scene.mesh"}, true});
  o.add_use({"hand.mesh", true, "${scene.mesh}", {"sim.yaml", 23, 22}, {"scene.mesh"}, true});
  o.add_use({"capacity", false, "${scene.mesh}", {"task.yaml", 9, 40}, {"scene.mesh"}, true});
  o.add_use({"out.file", true, "${dir}/${name}.txt", {"task.yaml", 7, 30}, {"dir", "name"}, false});
  for (const char* name : {"scene.mesh", "dir", "name"}) EXPECT_EQ(o.for_task_param(name), nullptr) << name;
  const auto shared = o.for_component_param("camera.mesh");
  EXPECT_FALSE(shared.apply);
  EXPECT_EQ(shared.refusal, "camera.mesh comes from the task parameter 'scene.mesh' (also hand.mesh, capacity at task.yaml:9:40); "
                            "set it with --set scene.mesh=...");
  const auto made = o.for_component_param("out.file");
  EXPECT_FALSE(made.apply);
  EXPECT_EQ(made.refusal, "out.file is '${dir}/${name}.txt' (task.yaml:7:30), made from the task parameters dir, name; set them with --set dir=...");
}

// Through the loader: a --set replaces what the file says, checked by the same rules.
TEST(Loader, OverridesReplaceFileValuesAndAreChecked) {
  fba::LoadOptions o;
  o.overrides = {{"source.count=42"}};
  EXPECT_EQ(std::get<std::int64_t>(load(kChain, o).find("source")->params.at("count")), 42);
  o.overrides = {{"source.count=-3"}};
  EXPECT_NE(errors_of(kChain, o).find("--set source.count=-3: error: parameter 'count' must be in"), std::string::npos);
  o.overrides = {{"nobody.count=3"}};
  EXPECT_NE(errors_of(kChain, o).find("no component 'nobody'"), std::string::npos);
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
