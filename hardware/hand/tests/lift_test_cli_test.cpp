// fba-lift-test's command line: every number is checked against its range before any work (the
// ranges of sim.hand's parameters), a --grasp that is not a regular file is refused rather than
// waited on, and --grasp reads a run's summary.json, where the grasp is the one a component
// reported (grasp.synthesis' results.grasp), as fba-evaluate grasp --summary reads it.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "object_placement.hpp"
#include "ring_grasp.hpp"
#include "support/build_paths.hpp"
#include "support/child_process.hpp"
#include "support/data_sets.hpp"
#include "support/temp_dir.hpp"

namespace {

using fba::test::kCan;

TEST(LiftTestCli, EveryNumberIsCheckedAgainstItsRangeBeforeAnyWork) {
  const std::pair<std::string, std::string> cases[] = {
      {"--repeat 0", "--repeat must be in [1, 10000]; found 0"},
      {"--repeat -1", "--repeat must be in [1, 10000]; found -1"},
      {"--repeat 99999999999", "--repeat must be in [1, 10000]; found 99999999999"},
      {"--repeat 2.5", "--repeat must be an integer in [1, 10000]; found '2.5'"},
      {"--x nan", "--x must be a finite number in [-1, 1]; found 'nan'"},
      {"--y 1x", "--y must be a number in [-1, 1]; found '1x'"},
      {"--yaw -inf", "--yaw must be a finite number in [-360, 360]; found '-inf'"},
      {"--mass 0", "--mass must be in [0.001, 10]; found 0"},
      {"--force 1e999", "--force must be a finite number in [15, 60]; found '1e999'"},
      {"--height 1.5", "--height must be in [0, 1]; found 1.5"},
      {"--thumb-angle 400", "--thumb-angle must be in [-360, 360]; found 400"},
      {"--synthesise 2", "--synthesise must be in [3, 1000000] (0: off); found 2"},
      {"--candidates 0", "--candidates must be in [1, 1000]; found 0"},
      {"--rest flat", "--rest must be upright or side; found 'flat'"},
      {"--voxel 0.1", "--voxel must be in [0.5, 20]; found 0.1"},
      {"--grasp g.json --synthesise 100", "--grasp and --synthesise: expected one of them; found both"},
      {"--bogus 1", "unknown option '--bogus'; expected one of --candidates, --force, --grasp"},
      {"--x", "--x: expected a value after it; found the end of the line"}};
  for (const auto& [args, says] : cases) {
    const auto r = fba::test::run_shell("'" + fba::test::program("fba-lift-test") + "' '" + kCan + "' " + args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("fba-lift-test: " + says), std::string::npos) << args << "\n" << r.output;
    EXPECT_EQ(r.output.find("scene built"), std::string::npos) << args << ": refused after the work\n" << r.output;
  }
}

// Opening a FIFO for reading waits for a writer, maybe forever: refused, saying what it is.
TEST(LiftTestCli, AGraspThatIsNotARegularFileIsRefusedNotWaitedOn) {
  const fba::test::TempDir dir;
  const std::string fifo = dir.file("grasp.fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  fba::test::Child lift({fba::test::program("fba-lift-test"), kCan, "--grasp", fifo});
  const int status = lift.wait(0);  // -1: it hung
  const std::string output = lift.read_until("");
  EXPECT_EQ(status, 2) << output;
  EXPECT_NE(output.find("--grasp: expected a regular file; '" + fifo + "' is a FIFO"), std::string::npos) << output;

  const auto r = fba::test::run_shell("'" + fba::test::program("fba-lift-test") + "' '" + kCan + "' --grasp '" + dir.path().string() + "'");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("' is a folder"), std::string::npos) << r.output;
}

// A run's summary.json as fba-run writes it: the grasp is in the synthesis component's results.
// The ring grasp around the can at mid height holds (lift_test_test.cpp), so this one must too.
TEST(LiftTestCli, AGraspIsReadFromARunsSummaryAsTheComponentReportedIt) {
  const fba::TriangleMesh can = fba::sim_hand::place_on_table(fba::geometry::load_mesh(kCan), {});
  const fba::Grasp g = fba::sim_hand::ring_grasp(can, fba::geometry::mesh_bounds(can).center().z(), M_PI);
  nlohmann::json grasp{{"approach", {g.approach.x(), g.approach.y(), g.approach.z()}}, {"spread", g.spread}, {"aperture", g.aperture}};
  for (const auto& c : g.contacts)
    grasp["contacts"].push_back({{"position", {c.position.x(), c.position.y(), c.position.z()}},
                                 {"normal", {c.normal.x(), c.normal.y(), c.normal.z()}}});
  const nlohmann::json summary{
      {"run_id", "a-run"},
      {"outcome", "success"},
      {"components", {{"camera", {{"type", "sim.camera"}}}, {"synthesis", {{"type", "grasp.synthesis"}, {"results", {{"grasp", grasp}}}}}}}};
  const fba::test::TempDir dir;
  const std::string file = dir.file("summary.json", summary.dump(2));
  const auto r = fba::test::run_shell("'" + fba::test::program("fba-lift-test") + "' '" + kCan + "' --grasp '" + file + "'");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("held yes"), std::string::npos) << r.output;

  // A run that selected no grasp: said so, not a parse error deep in the JSON.
  const std::string none = dir.file("none.json", R"({"run_id": "b", "outcome": "failure", "components": {"synthesis": {"results": {}}}})");
  const auto n = fba::test::run_shell("'" + fba::test::program("fba-lift-test") + "' '" + kCan + "' --grasp '" + none + "'");
  EXPECT_EQ(n.status, 2) << n.output;
  EXPECT_NE(n.output.find("--grasp: expected a run's summary.json with a grasp"), std::string::npos) << n.output;
  EXPECT_NE(n.output.find("found none in '" + none + "'"), std::string::npos) << n.output;
}

}  // namespace
