// fba-inspect's command-line contract: the same option checks as fba-run, a version, and the
// data types' pages.
#include <gtest/gtest.h>

#include "support/build_paths.hpp"
#include "support/child_process.hpp"
#include "support/fba_run.hpp"

namespace {

using namespace fba::test;

Result inspect(std::vector<std::string> args) {
  args.insert(args.begin(), fba::test::program("fba-inspect"));
  return run(std::move(args));
}

TEST(InspectCli, PrintsItsVersion) {
  const auto r = inspect({"--version"});
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output.rfind("fba-inspect ", 0), 0u) << r.output;
  EXPECT_EQ(r.output.back(), '\n');
}

// fba-run refused a plugin folder that does not exist while fba-inspect took it silently.
TEST(InspectCli, APluginPathThatIsNotAFolderIsRefused) {
  const fs::path file = temp_dir("inspect") / "plugin.txt";
  std::ofstream(file) << "not a folder\n";
  for (const std::string dir : {std::string("/nonexistent"), file.string()}) {
    const auto r = inspect({"-p", dir});
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("fba-inspect: --plugin-path '" + dir + "' is not a folder"), std::string::npos) << r.output;
  }
}

// A core type, so that it runs in every build (the ThreadSanitizer one has no vision plugin).
TEST(InspectCli, ShowsADataTypeWithItsLayoutAndWhereItIsDeclared) {
  const auto r = inspect({"-p", fba::test::plugin_dir(), "fba.Int"});
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output.rfind("fba.Int (data type)\n  A 64-bit signed integer.\n  layout: size 8, alignment 8, version ", 0), 0u)
      << r.output;
  EXPECT_NE(r.output.find("declared in: <fba/packet.hpp>"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("fba-examples.so"), std::string::npos) << r.output;  // a plugin that uses it
}

TEST(InspectCli, AnUnknownNameIsAnErrorThatSaysWhatWasLookedFor) {
  const auto r = inspect({"-p", fba::test::plugin_dir(), "no.such"});
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("no component type or data type 'no.such'"), std::string::npos) << r.output;
}

}  // namespace
