// Plugins are checked before use and refused with the file and the reason.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <fstream>

#include <fba/registry.hpp>
#include <fba/task.hpp>

#include "test_components.hpp"

namespace {

std::string refusal(const std::string& file, fba::Registry& r) {
  try {
    r.load_plugin(file);
  } catch (const fba::PluginError& e) {
    EXPECT_EQ(e.file(), file);
    return e.reason();
  }
  return "";
}

std::string bad(const std::string& name) { return std::string(FBA_BAD_PLUGIN_DIR) + "/" + name + ".so"; }
std::string examples() { return std::string(FBA_TEST_PLUGIN_DIR) + "/fba-examples.so"; }

}  // namespace

TEST(Plugin, ASharedObjectWithoutTheRecordIsRefused) {
  fba::Registry r;
  EXPECT_NE(refusal(bad("no_symbol"), r).find("is not an fba plugin: the symbol 'fba_plugin_info' is missing"), std::string::npos);
}

TEST(Plugin, AnotherAbiVersionIsRefusedBeforeAnyOfItsCodeRuns) {
  fba::Registry r;
  const auto why = refusal(bad("wrong_abi"), r);
  EXPECT_NE(why.find("was built for fba plugin ABI 999 (fba 9.9.9)"), std::string::npos) << why;
}

TEST(Plugin, AnUndefinedReferenceIsNamed) {
  fba::Registry r;
  const auto why = refusal(bad("undefined_reference"), r);
  EXPECT_NE(why.find("cannot be loaded"), std::string::npos) << why;
  EXPECT_NE(why.find("fba_test_function_nobody_defines"), std::string::npos) << why;
}

TEST(Plugin, ATypeRegisteredTwiceNamesBothFiles) {
  fba::Registry r;
  r.load_plugin(examples());
  const auto why = refusal(bad("duplicate_type"), r);
  EXPECT_NE(why.find("registers component type 'examples.counter', which " + examples() + " registered already"), std::string::npos) << why;
  EXPECT_EQ(r.find("examples.counter")->origin, examples());  // the first one stays
}

TEST(Plugin, APluginWithoutComponentsIsRefused) {
  fba::Registry r;
  EXPECT_NE(refusal(bad("no_components"), r).find("registers no component types"), std::string::npos);
}

TEST(Plugin, AFileThatIsNoSharedObjectIsRefused) {
  const std::string file = testing::TempDir() + "garbage.so";
  std::ofstream(file) << "this is not ELF";
  fba::Registry r;
  EXPECT_NE(refusal(file, r).find("cannot be loaded"), std::string::npos);
  EXPECT_NE(refusal(testing::TempDir() + "missing.so", r).find("no such file"), std::string::npos);
}

TEST(Plugin, LoadPathReportsEveryFailureAndKeepsTheGoodOnes) {
  fba::Registry r;
  const auto errors = r.load_path({FBA_TEST_PLUGIN_DIR, FBA_BAD_PLUGIN_DIR});
  EXPECT_GE(errors.size(), 5u);
  EXPECT_NE(r.find("examples.passthrough"), nullptr);
}

TEST(Plugin, TheLibraryStaysLoadedWhileAComponentFromItLives) {
  std::unique_ptr<fba::Task> task;
  {
    fba::Registry r;
    r.load_plugin(examples());
    const auto cfg = fba::load_task_text("components:\n  c: { type: examples.counter, params: { count: 3 } }\n", "t.yaml", ".", r);
    task = std::make_unique<fba::Task>(cfg);
  }  // the registry is gone; the task's components still hold the library
  EXPECT_NE(dlopen(examples().c_str(), RTLD_NOW | RTLD_NOLOAD), nullptr);
  const auto result = task->run();
  EXPECT_EQ(result.outcome, fba::Outcome::Success) << result.reason;
}
