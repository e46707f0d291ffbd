// fba::check_construction, fba-run --check's last step: the task's filters constructed as a run
// constructs them, so that what their constructors find is found before anything runs; sensors
// and actuators, which own devices, left alone.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <fba/registry.hpp>
#include <fba/task.hpp>
#include <fba/task_config.hpp>

#include "support/build_paths.hpp"
#include "support/temp_dir.hpp"

namespace {

namespace fs = std::filesystem;

// The examples, the misbehaving test plugin and the bad plugins (the broken ones among them are refused, as on any path).
fba::Registry& registry() {
  static fba::Registry r = [] {
    fba::Registry reg;
    reg.load_path({fba::test::plugin_dir(), fba::test::binary_dir() + "/core/tests/bad_plugins",
                   fba::test::binary_dir() + "/tests/tasks/misbehaving/plugins"});
    return reg;
  }();
  return r;
}

// Every diagnostic the check gives the task, a line each; a task that passes is a test failure.
std::string construction_errors(const fba::TaskConfig& config) {
  try {
    fba::check_construction(config);
  } catch (const fba::ConfigError& e) {
    std::string s;
    for (const auto& d : e.diagnostics()) s += d.str() + "\n";
    return s;
  }
  ADD_FAILURE() << "the task passed the check";
  return {};
}

TEST(ConstructionCheck, AHandleTheSpecLeavesOutIsFoundWithoutARun) {
  const auto config = fba::load_task_text(
      "components:\n"
      "  src: { type: examples.counter, params: { count: 3 } }\n"
      "  forgetful: { type: bad.undeclared_handle }\n"
      "  sink: { type: examples.sink }\n"
      "connections: [ src.out -> forgetful.in, forgetful.out -> sink.in ]\n",
      "t.yaml", ".", registry());
  const std::string text = construction_errors(config);
  EXPECT_NE(text.find("t.yaml:3:"), std::string::npos) << text;  // where the component is in the task
  EXPECT_NE(text.find("component 'forgetful' (bad.undeclared_handle)"), std::string::npos) << text;
  EXPECT_NE(text.find("uses output 'forgotten', which its spec does not declare"), std::string::npos) << text;
}

TEST(ConstructionCheck, AFilterWhoseConstructorThrowsIsFound) {
  const auto config = fba::load_task_text(
      "components:\n"
      "  src: { type: examples.counter, params: { count: 3 } }\n"
      "  m: { type: test.misbehaving, params: { mode: throw_in_constructor_int } }\n"
      "  sink: { type: examples.sink }\n"
      "connections: [ src.out -> m.in, m.out -> sink.in ]\n",
      "t.yaml", ".", registry());
  const std::string text = construction_errors(config);
  EXPECT_NE(text.find("t.yaml:3:"), std::string::npos) << text;
  EXPECT_NE(text.find("component 'm' (test.misbehaving) threw a non-exception"), std::string::npos) << text;
}

TEST(ConstructionCheck, ATaskWhoseFiltersConstructPasses) {
  const auto config = fba::load_task_text(
      "components:\n"
      "  src: { type: examples.counter, params: { count: 3 } }\n"
      "  p: { type: examples.passthrough }\n"
      "  sink: { type: examples.sink }\n"
      "connections: [ src.out -> p.in, p.out -> sink.in ]\n",
      "t.yaml", ".", registry());
  EXPECT_NO_THROW(fba::check_construction(config));
}

TEST(ConstructionCheck, SensorsAndActuatorsAreNotConstructed) {
  fba::test::TempDir dir("check");
  const fs::path mark = dir.path() / "constructed";
  const auto config = fba::load_task_text(
      "components:\n"
      "  src: { type: examples.counter, params: { count: 3 } }\n"
      "  device: { type: bad.marking_actuator, params: { mark: " + mark.string() + " } }\n"
      "connections: [ src.out -> device.in ]\n",
      "t.yaml", ".", registry());
  fba::check_construction(config);
  EXPECT_FALSE(fs::exists(mark));
  fba::Task task(config);  // a run constructs it: the mark is what the check would have left
  EXPECT_TRUE(fs::exists(mark));
}

}  // namespace
