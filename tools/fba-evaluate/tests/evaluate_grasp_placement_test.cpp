// fba-evaluate grasp and its --batch mode count a grasp by the worse of its two placements on the
// true mesh (each contact along its normal, and at its closest point), and report both.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "evaluate_grasp.hpp"
#include "support/build_paths.hpp"

namespace {

namespace fs = std::filesystem;

using fba::test::evaluate_grasp;
using fba::test::line_starting;
using fba::test::write_fba_run_stand_in;

class EvaluateGraspPlacement : public fba::test::CubeTest {};

// The thumb on the -x face; the fingers 2 mm inside the +x face and half a millimetre under the
// top, pushing along -x: along their normals they land on the +x face (force closure), at their
// closest points on the top face (not). `z` is the cube's centre.
std::string edge_grasp(double z) {
  const auto at = [&](double dz) { return std::to_string(z + dz); };
  return R"({"contacts": [{"position": [-0.05, 0, )" + at(0.045) + R"(], "normal": [1, 0, 0]},
      {"position": [0.048, 0.02, )" + at(0.0495) + R"(], "normal": [-1, 0, 0]},
      {"position": [0.048, -0.02, )" + at(0.0495) + R"(], "normal": [-1, 0, 0]}]})";
}

// The same hand on flat faces, a millimetre off them and far from any edge.
std::string flat_grasp(double z) {
  const auto at = [&](double dz) { return std::to_string(z + dz); };
  return R"({"contacts": [{"position": [-0.051, 0, )" + at(0) + R"(], "normal": [1, 0, 0]},
      {"position": [0.051, 0.02, )" + at(0.01) + R"(], "normal": [-1, 0, 0]},
      {"position": [0.051, -0.02, )" + at(0.01) + R"(], "normal": [-1, 0, 0]}]})";
}

TEST_F(EvaluateGraspPlacement, AGraspOnAnEdgeIsNotForceClosureWhenItsClosestPlacementIsNot) {
  const fs::path s = dir_ / "summary.json";
  std::ofstream(s) << R"({"grasp": )" << edge_grasp(0) << "}";
  const auto r = evaluate_grasp("--mesh " + mesh() + " --summary " + s.string() + " --random 0");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("placed along the normals: force closure yes"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("placed at the closest points: force closure no"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("grasp: force closure no, epsilon 0.0000 (the worse placement: the closest points)"), std::string::npos)
      << r.output;
  // Each contact's closest point is said too, with its normal's error (90 degrees for a finger).
  EXPECT_NE(line_starting(r.output, "            closest point: (0.0480, 0.0200, 0.0495)").find("normal 90.0 deg off"), std::string::npos)
      << r.output;
}

TEST_F(EvaluateGraspPlacement, AGraspOnFlatFacesIsTheSameByBothPlacements) {
  const fs::path s = dir_ / "summary.json";
  std::ofstream(s) << R"({"grasp": )" << flat_grasp(0) << "}";
  const auto r = evaluate_grasp("--mesh " + mesh() + " --summary " + s.string() + " --random 0");
  EXPECT_EQ(r.status, 0) << r.output;
  const std::string along = line_starting(r.output, "placed along the normals: force closure yes, epsilon ");
  const std::string closest = line_starting(r.output, "placed at the closest points: force closure yes, epsilon ");
  ASSERT_FALSE(along.empty()) << r.output;
  ASSERT_FALSE(closest.empty()) << r.output;
  EXPECT_EQ(along.substr(along.find("epsilon")), closest.substr(closest.find("epsilon"))) << r.output;
  EXPECT_NE(r.output.find("grasp: force closure yes"), std::string::npos) << r.output;
}

// Two runs by a stand-in for fba-run: the first selects the edge grasp, the second the flat one.
TEST_F(EvaluateGraspPlacement, TheBatchCountsEachRunByItsWorsePlacementAndReportsBoth) {
  const fs::path l = dir_ / "list.yaml";
  std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\n"
                   << "runs:\n  - { mesh: " << mesh() << " }\n  - { mesh: " << mesh() << " }\n";
  const fs::path stand_in = write_fba_run_stand_in(
      dir_ / "grasps.sh", "case \"$dir\" in */01-*) g='" + edge_grasp(0.05) + "';; *) g='" + flat_grasp(0.05) + "';; esac\n" +
                              R"(printf '{"run_id": "%s", "outcome": "success", "grasp": %s}' "$id" "$g" > "$dir/summary.json")");
  const auto r = evaluate_grasp("--batch " + l.string() + " --random 0 --fba-run " + stand_in.string() + " -o " + (dir_ / "out").string());
  ASSERT_EQ(r.status, 0) << r.output;
  // The runs' lines: FC (the worse), then FC along the normals / at the closest points.
  EXPECT_NE(r.output.find("FC_n/c"), std::string::npos) << r.output;
  std::istringstream table(r.output);
  std::vector<std::string> fc;
  for (std::string line; std::getline(table, line);)
    if (line.rfind("task     cube.ply           0 0 0", 0) == 0) {
      std::istringstream words(line);
      std::string variant, object, x, y, yaw, outcome, views, worse, both;
      words >> variant >> object >> x >> y >> yaw >> outcome >> views >> worse >> both;
      fc.push_back(worse + " " + both);
    }
  ASSERT_EQ(fc.size(), 2u) << r.output;
  EXPECT_EQ(fc[0], "no yes/no") << r.output;
  EXPECT_EQ(fc[1], "yes yes/yes") << r.output;

  std::ifstream in(dir_ / "out" / "runs.json");
  const auto rows = nlohmann::json::parse(in, nullptr, false);
  ASSERT_EQ(rows.size(), 2u) << rows.dump();
  EXPECT_EQ(rows[0]["force_closure"], false) << rows[0].dump(2);
  EXPECT_EQ(rows[0]["worse"], "closest") << rows[0].dump(2);
  EXPECT_EQ(rows[0]["placements"]["along_normal"]["force_closure"], true) << rows[0].dump(2);
  EXPECT_EQ(rows[0]["placements"]["closest"]["force_closure"], false) << rows[0].dump(2);
  ASSERT_EQ(rows[0]["placements"]["closest"]["contacts"].size(), 3u) << rows[0].dump(2);
  EXPECT_NEAR(rows[0]["placements"]["closest"]["contacts"][1]["position"][2].get<double>(), 0.1, 1e-6) << rows[0].dump(2);
  EXPECT_NEAR(rows[0]["placements"]["along_normal"]["contacts"][1]["position"][0].get<double>(), 0.05, 1e-6) << rows[0].dump(2);
  EXPECT_EQ(rows[1]["force_closure"], true) << rows[1].dump(2);
  const double along = rows[1]["placements"]["along_normal"]["epsilon"], closest = rows[1]["placements"]["closest"]["epsilon"];
  EXPECT_GT(along, 0) << rows[1].dump(2);
  EXPECT_NEAR(along, closest, 1e-9) << rows[1].dump(2);
  EXPECT_EQ(rows[1]["epsilon"].get<double>(), std::min(along, closest)) << rows[1].dump(2);
  // The summary: two grasps, one force closure, one the placements split on.
  std::istringstream summary(line_starting(r.output, "task     all "));
  std::string variant, object, grasp, fc_share;
  std::size_t runs = 0;
  summary >> variant >> object >> runs >> grasp >> fc_share;
  EXPECT_EQ(runs, 2u) << r.output;
  EXPECT_EQ(fc_share, "50%") << r.output;
  const std::string all = line_starting(r.output, "task     all ");
  EXPECT_EQ(all.substr(all.find_last_not_of(' ') ), "1") << r.output;
}

}  // namespace
