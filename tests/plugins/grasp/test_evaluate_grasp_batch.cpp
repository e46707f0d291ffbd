// fba-evaluate grasp --batch from the shell: tasks/grasp.yaml run by fba-run on a small list,
// the table with the issue's columns, and a run that cannot start its task as a row with the reason.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "evaluate_grasp.hpp"
#include "support/build_paths.hpp"
#include "support/shared_data.hpp"

namespace {

namespace fs = std::filesystem;

using Result = fba::test::CommandResult;

using fba::test::evaluate_grasp;

// The line of `text` that starts with `start`, or "".
std::string line_starting(const std::string& text, const std::string& start) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(start, 0) == 0) return line;
  return "";
}

class EvaluateGraspBatch : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(testing::TempDir()) / ("fba-evaluate-grasp-batch-" + std::to_string(getpid()) + "-" +
                                           testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

std::string mustard() { return fba::test::ycb_mesh("YcbMustardBottle"); }

TEST_F(EvaluateGraspBatch, ASmallListGivesTheTableWithTheIssuesColumnsAndAFailedRunAsARowWithItsReason) {
  const fs::path l = dir_ / "list.yaml";
  // Depth 4 and at most 3 views: quick; whether a grasp is found there does not matter here.
  std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\n"
                   << "fba_run_args: [-e, deterministic]\n"
                   << "pose_set:\n  - mesh={mesh}\n  - object_yaw={yaw}\n"
                   << "set: [carver.max_depth=4, synthesis.max_views=3]\n"
                   << "variants:\n  - { name: loop, set: [carver.compare_uniform=true] }\n"
                   << "  - { name: uniform, set: [carver.occupancy_threshold=0] }\n"
                   << "runs:\n"
                   << "  - { mesh: " << mustard() << ", pose: [0, 0, 30] }\n"
                   << "  - { mesh: " << (dir_ / "no-such-mesh.obj").string() << " }\n";
  const fs::path out = dir_ / "out";
  const Result r = evaluate_grasp("--batch " + l.string() + " --jobs 2 --random 50 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  // The per-run table and the summary table, with their columns.
  for (const char* column : {"variant", "object", "pose x y yaw", "outcome", "views", "FC", "epsilon", "held", "wall_s", "cpu_s",
                             "nodes", "reason", "runs", "grasp", "med_eps", "rand_p99", ">p99", "rand_FC"})
    EXPECT_NE(r.output.find(column), std::string::npos) << column << "\n" << r.output;
  EXPECT_NE(line_starting(r.output, "uniform  YcbMustardBottle   0 0 30"), "") << r.output;
  // The mustard bottle ran to the task's own verdict, in its own folder, with figures.
  const std::string ran = line_starting(r.output, "loop     YcbMustardBottle   0 0 30");
  ASSERT_FALSE(ran.empty()) << r.output;
  EXPECT_TRUE(ran.find("success") != std::string::npos || ran.find("failure") != std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(out / "loop" / "01-YcbMustardBottle" / "summary.json"));
  const std::string mustard_summary = line_starting(r.output, "loop     YcbMustardBottle      1 ");
  EXPECT_FALSE(mustard_summary.empty()) << r.output;
  EXPECT_NE(line_starting(r.output, "uniform  all                   2 "), "") << r.output;
  // The missing mesh is a row with fba-run's reason, not the end of the batch.
  const std::string failed = line_starting(r.output, "loop     no-such-mesh.obj");
  EXPECT_NE(failed.find("no summary"), std::string::npos) << r.output;
  EXPECT_NE(failed.find("exit 2"), std::string::npos) << r.output;
  EXPECT_NE(failed.find("parameter 'mesh'"), std::string::npos) << r.output;

  std::ifstream in(out / "runs.json");
  const auto runs = nlohmann::json::parse(in, nullptr, false);
  ASSERT_TRUE(runs.is_array()) << "runs.json";
  ASSERT_EQ(runs.size(), 4u);  // loop: mustard, missing; uniform: mustard, missing
  EXPECT_GT(runs[0]["nodes"].get<long long>(), 0);
  // The carver's comparison with uniform detail, though the run was stopped by an event rule (held,
  // or synthesis giving up) and never reached the end of its stream.
  ASSERT_TRUE(runs[0].contains("detail")) << runs[0].dump(2);
  EXPECT_GT(runs[0]["detail"].value("uniform_nodes", 0), 0) << runs[0].dump(2);
  EXPECT_TRUE(runs[0]["detail"].contains("saved_share")) << runs[0].dump(2);
  EXPECT_EQ(runs[1]["outcome"], "no summary");
  // A selected grasp's contacts as placed on the mesh, and the normals' error over the variant.
  if (runs[0].value("selected", false)) {
    ASSERT_EQ(runs[0]["contacts"].size(), 3u) << runs[0].dump(2);
    EXPECT_GE(runs[0]["contacts"][0].value("normal_error_deg", -1.0), 0.0) << runs[0].dump(2);
    EXPECT_GE(runs[0]["contacts"][0].value("moved_mm", -1.0), 0.0) << runs[0].dump(2);
    // What synthesis had resolved under the fingers; a grasp settled for on its contacts says so.
    const std::string resolved = runs[0].value("resolved", "");
    EXPECT_TRUE(resolved == "surface" || resolved == "contacts") << runs[0].dump(2);
    EXPECT_EQ(resolved == "contacts", ran.find("selected on its contacts alone after the last view") != std::string::npos) << ran;
  }
  EXPECT_NE(r.output.find("model normals at the selected contacts on the object"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("variant  contacts median_deg  p75_deg  max_deg  off_mesh"), std::string::npos) << r.output;
  EXPECT_EQ(runs[2]["variant"], "uniform");
  // The variants side by side, per object and overall.
  EXPECT_NE(r.output.find("side by side (loop / uniform):"), std::string::npos) << r.output;
  EXPECT_NE(line_starting(r.output, "YcbMustardBottle   "), "") << r.output;
  EXPECT_TRUE(fs::exists(out / "table.txt"));
}

TEST_F(EvaluateGraspBatch, AMeshTheTaskCannotLoadIsARowWithFbaRunsReason) {
  // Given to fba-run as it is: the child refuses the task, and its own message is the reason.
  const fs::path l = dir_ / "list.yaml";
  std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\n"
                   << "pose_set:\n  - scene.mesh={mesh}\n  - hand.mesh={mesh}\n"
                   << "runs:\n  - { mesh: " << (dir_ / "missing.obj").string() << " }\n";
  const Result r = evaluate_grasp("--batch " + l.string() + " --random 0 -o " + (dir_ / "out").string());
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string row = line_starting(r.output, "task     missing.obj");
  EXPECT_NE(row.find("no summary"), std::string::npos) << r.output;
  EXPECT_NE(row.find("exit 2"), std::string::npos) << r.output;
  // The whole reason is in runs.json (the table clips it to a line), with fba-run's own words.
  std::ifstream in(dir_ / "out" / "runs.json");
  const auto runs = nlohmann::json::parse(in, nullptr, false);
  ASSERT_TRUE(runs.is_array() && runs.size() == 1u) << r.output;
  const std::string reason = runs[0].value("reason", "");
  EXPECT_NE(reason.find("fba-run said: --set "), std::string::npos) << reason << "\n" << r.output;
  EXPECT_NE(reason.find("missing.obj"), std::string::npos) << reason << "\n" << r.output;
}

// A stand-in for fba-run that hangs or crashes: the batch carries on, each run a row saying so.
TEST_F(EvaluateGraspBatch, AHungOrCrashedRunIsARowAndTheBatchGoesOn) {
  const fs::path hang = dir_ / "hang.sh", crash = dir_ / "crash.sh";
  std::ofstream(hang) << "#!/bin/sh\nexec sleep 60\n";
  std::ofstream(crash) << "#!/bin/sh\nkill -SEGV $$\n";
  for (const auto& f : {hang, crash}) fs::permissions(f, fs::perms::owner_all);
  const fs::path l = dir_ / "list.yaml";
  std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\n"
                   << "timeout_s: 0.5\n"
                   << "runs:\n  - { mesh: " << mustard() << " }\n";
  Result r = evaluate_grasp("--batch " + l.string() + " --random 0 --fba-run " + hang.string() + " -o " + (dir_ / "hang").string());
  ASSERT_EQ(r.status, 0) << r.output;
  std::string row = line_starting(r.output, "task     YcbMustardBottle   0 0 0");
  EXPECT_NE(row.find("timed out"), std::string::npos) << r.output;

  r = evaluate_grasp("--batch " + l.string() + " --random 0 --fba-run " + crash.string() + " -o " + (dir_ / "crash").string());
  ASSERT_EQ(r.status, 0) << r.output;
  row = line_starting(r.output, "task     YcbMustardBottle   0 0 0");
  EXPECT_NE(row.find("crashed"), std::string::npos) << r.output;
  EXPECT_NE(row.find("killed by signal 11"), std::string::npos) << row;
}

TEST_F(EvaluateGraspBatch, ABadListIsAClearErrorWithItsPlace) {
  const fs::path l = dir_ / "list.yaml";
  std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\n"
                   << "pose_set:\n  - scene.mesh={mesh}\n  - hand.object_yaw={angle}\n"
                   << "runs:\n  - { mesh: m.obj }\n";
  Result r = evaluate_grasp("--batch " + l.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("list.yaml:4:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("unknown placeholder {angle}"), std::string::npos) << r.output;

  std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\n"
                   << "runs:\n  - { mesh: m.obj, pose: [0, 0] }\n";
  r = evaluate_grasp("--batch " + l.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("pose: expected [x, y, yaw]"), std::string::npos) << r.output;

  std::ofstream(l) << "task: no-such-task.yaml\nruns:\n  - { mesh: m.obj }\n";
  r = evaluate_grasp("--batch " + l.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("task: no such file"), std::string::npos) << r.output;

  r = evaluate_grasp("--batch " + (dir_ / "absent.yaml").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("is not a readable file"), std::string::npos) << r.output;
}

}  // namespace
