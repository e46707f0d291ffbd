// fba-evaluate grasp --batch from the shell: tasks/grasp.yaml run by fba-run on a small list,
// the table with the issue's columns, and a run that cannot start its task as a row with the reason.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "evaluate_grasp.hpp"
#include "fba/geometry/mesh_io.hpp"
#include "support/child_process.hpp"
#include "support/build_paths.hpp"
#include "support/temp_dir.hpp"
#include "support/data_sets.hpp"

namespace {

namespace fs = std::filesystem;

using Result = fba::test::Result;

using fba::test::evaluate_grasp;
using fba::test::given_run_id;
using fba::test::line_starting;
using fba::test::write_fba_run_stand_in;

class EvaluateGraspBatch : public testing::Test {
 protected:
  fba::test::TempDir tmp_;
  const fs::path dir_ = tmp_.path();
};

std::string mustard() { return fba::test::ycb_mesh("YcbMustardBottle"); }

TEST_F(EvaluateGraspBatch, ASmallListGivesTheTableWithTheIssuesColumnsAndAFailedRunAsARowWithItsReason) {
  const fs::path l = dir_ / "list.yaml";
  // Depth 4 and at most 3 views: quick; whether a grasp is found there does not matter here.
  std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\n"
                   << "fba_run_args: [-e, deterministic]\n"
                   << "pose_set:\n  - scene.mesh={mesh}\n  - scene.yaw={yaw}\n"
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
                             "nodes", "reason", "runs", "grasp", "med_eps", "rand_p99", ">p99", "rand_FC", "synth_s"})
    EXPECT_NE(r.output.find(column), std::string::npos) << column << "\n" << r.output;
  EXPECT_NE(line_starting(r.output, "uniform  YcbMustardBottle   0 0 30"), "") << r.output;
  // The mustard bottle ran to the task's own verdict, in its own folder, with figures.
  const std::string ran = line_starting(r.output, "loop     YcbMustardBottle   0 0 30");
  ASSERT_FALSE(ran.empty()) << r.output;
  EXPECT_TRUE(ran.find("success") != std::string::npos || ran.find("failure") != std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(out / "loop" / "01-YcbMustardBottle" / "summary.json"));
  // fba-run wrote the run id the batch gave it, by which the batch knows the summary is this run's.
  {
    std::ifstream in(out / "loop" / "01-YcbMustardBottle" / "summary.json");
    const auto summary = nlohmann::json::parse(in, nullptr, false);
    EXPECT_NE(given_run_id(out / "loop" / "01-YcbMustardBottle"), "");
    EXPECT_EQ(summary.value("run_id", "?"), given_run_id(out / "loop" / "01-YcbMustardBottle")) << r.output;
  }
  const std::string mustard_summary = line_starting(r.output, "loop     YcbMustardBottle      1 ");
  EXPECT_FALSE(mustard_summary.empty()) << r.output;
  EXPECT_NE(line_starting(r.output, "uniform  all                   2 "), "") << r.output;
  // The missing mesh is a row with fba-run's outcome and reason (its summary.json), not the end of the batch.
  const std::string failed = line_starting(r.output, "loop     no-such-mesh.obj");
  EXPECT_NE(failed.find("configuration_error"), std::string::npos) << r.output;
  EXPECT_NE(failed.find("parameter 'scene.mesh'"), std::string::npos) << r.output;

  std::ifstream in(out / "runs.json");
  const auto runs = nlohmann::json::parse(in, nullptr, false);
  ASSERT_TRUE(runs.is_array()) << "runs.json";
  ASSERT_EQ(runs.size(), 4u);  // loop: mustard, missing; uniform: mustard, missing
  EXPECT_GT(runs[0]["nodes"].get<long long>(), 0);
  // Synthesis's time on each view it analysed (the mustard run's views, at most 3).
  ASSERT_TRUE(runs[0]["synthesis_s"].is_array()) << runs[0].dump(2);
  EXPECT_GE(runs[0]["synthesis_s"].size(), 1u) << runs[0].dump(2);
  EXPECT_LE(runs[0]["synthesis_s"].size(), 3u) << runs[0].dump(2);
  for (const auto& s : runs[0]["synthesis_s"]) EXPECT_GT(s.get<double>(), 0.0) << runs[0].dump(2);
  EXPECT_TRUE(runs[1]["synthesis_s"].empty()) << runs[1].dump(2);  // the missing mesh ran no synthesis
  // The carver's comparison with uniform detail, though the run was stopped by an event rule (held,
  // or synthesis giving up) and never reached the end of its stream.
  ASSERT_TRUE(runs[0].contains("detail")) << runs[0].dump(2);
  EXPECT_GT(runs[0]["detail"].value("uniform_nodes", 0), 0) << runs[0].dump(2);
  EXPECT_TRUE(runs[0]["detail"].contains("saved_share")) << runs[0].dump(2);
  EXPECT_EQ(runs[1]["outcome"], "configuration_error");
  // A selected grasp's contacts as placed on the mesh, and the normals' error over the variant.
  if (runs[0].value("selected", false)) {
    ASSERT_EQ(runs[0]["contacts"].size(), 3u) << runs[0].dump(2);
    EXPECT_GE(runs[0]["contacts"][0].value("normal_error_deg", -1.0), 0.0) << runs[0].dump(2);
    EXPECT_GE(runs[0]["contacts"][0].value("moved_mm", -1.0), 0.0) << runs[0].dump(2);
    // What synthesis had resolved under the fingers; a grasp settled for on its contacts says so.
    const std::string resolved = runs[0].value("resolved", "");
    EXPECT_TRUE(resolved == "surface" || resolved == "contacts") << runs[0].dump(2);
    EXPECT_EQ(resolved == "contacts", ran.find("selected on its contacts alone, the surface around them not all resolved") != std::string::npos) << ran;
  }
  EXPECT_NE(r.output.find("model normals at the selected contacts on the object"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("variant  contacts median_deg  p75_deg  max_deg  off_mesh"), std::string::npos) << r.output;
  EXPECT_EQ(runs[2]["variant"], "uniform");
  // The variants side by side, per object and overall.
  EXPECT_NE(r.output.find("side by side (loop / uniform):"), std::string::npos) << r.output;
  EXPECT_NE(line_starting(r.output, "YcbMustardBottle   "), "") << r.output;
  // Uniform paired with the loop run by run: each of the two runs counted once; the missing mesh
  // selected nothing in either.
  const std::size_t paired = r.output.find("paired with loop, run by run");
  ASSERT_NE(paired, std::string::npos) << r.output;
  std::istringstream row(line_starting(r.output.substr(paired), "uniform "));
  std::string name;
  std::size_t both = 0, only_ref = 0, only_var = 0, neither = 0, pairs = 0;
  double p_selected = -1;
  row >> name >> both >> only_ref >> only_var >> neither >> p_selected >> pairs;
  ASSERT_TRUE(row) << r.output;
  EXPECT_GE(p_selected, 0.0) << r.output;
  EXPECT_LE(p_selected, 1.0) << r.output;
  EXPECT_EQ(both + only_ref + only_var + neither, 2u) << r.output;
  EXPECT_GE(neither, 1u) << r.output;
  EXPECT_LE(pairs, both) << r.output;
  EXPECT_TRUE(fs::exists(out / "table.txt"));
  // index.html beside the table: a row per run, linking its report.html when fba-run wrote one (a
  // build with the live view's page), else its summary.json.
  std::ifstream index_file(out / "index.html");
  std::stringstream index;
  index << index_file.rdbuf();
  for (const std::string run : {"loop/01-YcbMustardBottle/", "loop/02-no-such-mesh.obj/", "uniform/01-YcbMustardBottle/"}) {
    const std::string target = fs::exists(out / run / "report.html") ? "report.html" : "summary.json";
    EXPECT_NE(index.str().find("href=\"" + run + target + "\""), std::string::npos) << run << "\n" << index.str();
  }
}

// The poses a dry run would give fba-run: scene.x, scene.y, scene.yaw of each command line.
std::vector<std::array<double, 3>> dry_run_poses(const std::string& output) {
  std::vector<std::array<double, 3>> poses;
  std::istringstream in(output);
  for (std::string line; std::getline(in, line);) {
    std::array<double, 3> p{};
    int found = 0;
    for (const auto& [key, slot] : {std::pair{"scene.x=", 0}, {"scene.y=", 1}, {"scene.yaw=", 2}}) {
      const std::size_t at = line.find(key);
      if (at == std::string::npos) continue;
      p[slot] = std::stod(line.substr(at + std::string(key).size()));
      ++found;
    }
    if (found == 3) poses.push_back(p);
  }
  return poses;
}

TEST_F(EvaluateGraspBatch, RandomRunsDrawTheSamePosesFromTheSameSeedWithinTheirRangesAfterTheListedRuns) {
  const fs::path l = dir_ / "list.yaml";
  const auto write = [&](int seed) {
    std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\n"
                     << "pose_set:\n  - scene.mesh={mesh}\n  - scene.x={x}\n  - scene.y={y}\n  - scene.yaw={yaw}\n"
                     << "runs:\n  - { mesh: " << mustard() << ", pose: [0.5, 0.5, 7] }\n"
                     << "random_runs:\n  meshes: [" << mustard() << ", " << mustard() << "]\n  per_mesh: 20\n"
                     << "  x: [-0.01, 0.01]\n  y: [0.02, 0.03]\n  yaw: [90, 180]\n  seed: " << seed << "\n";
  };
  write(7);
  const Result a = evaluate_grasp("--batch " + l.string() + " --dry-run -o " + (dir_ / "out").string());
  ASSERT_EQ(a.status, 0) << a.output;
  const auto poses = dry_run_poses(a.output);
  ASSERT_EQ(poses.size(), 41u) << a.output;
  EXPECT_EQ(poses[0], (std::array<double, 3>{0.5, 0.5, 7})) << a.output;
  double lowest_x = 1, highest_x = -1;
  for (std::size_t i = 1; i < poses.size(); ++i) {
    const auto& [x, y, yaw] = poses[i];
    EXPECT_GE(x, -0.01);
    EXPECT_LE(x, 0.01);
    EXPECT_GE(y, 0.02);
    EXPECT_LE(y, 0.03);
    EXPECT_GE(yaw, 90);
    EXPECT_LE(yaw, 180);
    // Rounded to a millimetre and a degree, as a list written by hand would have them.
    EXPECT_NEAR(x * 1000, std::round(x * 1000), 1e-9) << x;
    EXPECT_EQ(yaw, std::round(yaw));
    lowest_x = std::min(lowest_x, x);
    highest_x = std::max(highest_x, x);
  }
  EXPECT_GT(highest_x - lowest_x, 0.01) << "40 draws should spread over most of the range\n" << a.output;
  // Nothing run, nothing written.
  EXPECT_EQ(a.output.find("fba-evaluate grasp --batch:"), std::string::npos) << a.output;
  EXPECT_FALSE(fs::exists(dir_ / "out"));

  const Result again = evaluate_grasp("--batch " + l.string() + " --dry-run");
  EXPECT_EQ(dry_run_poses(again.output), poses);
  write(8);
  const Result other = evaluate_grasp("--batch " + l.string() + " --dry-run");
  EXPECT_NE(dry_run_poses(other.output), poses);
}

TEST_F(EvaluateGraspBatch, BadRandomRunsAreAClearErrorWithTheirPlace) {
  const fs::path l = dir_ / "list.yaml";
  const std::string head = "task: " + fba::test::tasks_dir() + "/grasp.yaml\nrandom_runs:\n  meshes: [m.obj]\n";
  const std::pair<std::string, std::string> cases[] = {
      {"  per_mesh: 0\n  seed: 1\n", "list.yaml:4:13: random_runs per_mesh: expected a whole number from 1 to 10000, found '0'"},
      {"  per_mesh: 3\n", "list.yaml:3:3: random_runs: expected a key 'seed'"},
      {"  per_mesh: 3\n  seed: 1\n  x: [0.02, 0.01]\n", "list.yaml:6:6: random_runs x: expected low <= high, found [0.02, 0.01]"},
      {"  per_mesh: 3\n  seed: 1\n  z: [0, 1]\n", "list.yaml:6:3: random_runs: unknown key 'z'"},
      {"  per_mesh: 3\n  seed: -1\n", "random_runs seed: expected a whole number"}};
  for (const auto& [tail, message] : cases) {
    std::ofstream(l) << head << tail;
    const Result r = evaluate_grasp("--batch " + l.string() + " --dry-run");
    EXPECT_EQ(r.status, 2) << tail << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << tail << r.output;
  }
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
  EXPECT_NE(row.find("configuration_error"), std::string::npos) << r.output;
  // The whole reason is in runs.json (the table clips it to a line), with fba-run's own words (the
  // reason in its summary.json, which it writes at a configuration error too).
  std::ifstream in(dir_ / "out" / "runs.json");
  const auto runs = nlohmann::json::parse(in, nullptr, false);
  ASSERT_TRUE(runs.is_array() && runs.size() == 1u) << r.output;
  const std::string reason = runs[0].value("reason", "");
  EXPECT_EQ(reason.rfind("--set scene.mesh=", 0), 0u) << reason << "\n" << r.output;
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

// A run laid on its side (scene.rest=side in its --set) is judged on the mesh laid on its side, as
// the run had it: the true surface was once placed upright whatever the run's rest, so the same
// grasp's contacts moved the same distance onto either.
TEST_F(EvaluateGraspBatch, ARunOnItsSideIsJudgedOnTheMeshOnItsSide) {
  const fs::path l = dir_ / "list.yaml";
  std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\n"
                   << "runs:\n  - { mesh: " << mustard() << " }\n  - { mesh: " << mustard() << ", set: [scene.rest=side] }\n";
  const fs::path stand_in = write_fba_run_stand_in(dir_ / "grasps.sh", R"(printf '{"run_id": "%s", "outcome": "success", "grasp": {"contacts": [
      {"position": [-0.03, 0, 0.05], "normal": [1, 0, 0]}, {"position": [0.03, 0.02, 0.05], "normal": [-1, 0, 0]},
      {"position": [0.03, -0.02, 0.05], "normal": [-1, 0, 0]}]}}' "$id" > "$dir/summary.json")");
  const Result r = evaluate_grasp("--batch " + l.string() + " --random 0 --fba-run " + stand_in.string() + " -o " + (dir_ / "out").string());
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream in(dir_ / "out" / "runs.json");
  const auto rows = nlohmann::json::parse(in, nullptr, false);
  ASSERT_EQ(rows.size(), 2u) << rows.dump();
  ASSERT_TRUE(rows[0].contains("contacts") && rows[1].contains("contacts")) << rows.dump();
  EXPECT_NE(rows[0]["contacts"][0]["moved_mm"], rows[1]["contacts"][0]["moved_mm"]) << rows.dump();
}

// A run's summary.json is taken only when it carries the run id the batch gave the run: a run that
// failed before writing one is not reported with the summary an earlier run left in its folder.
TEST_F(EvaluateGraspBatch, ARunIsReportedWithItsOwnSummaryOnlyNeverAnOlderRunsOrAnothers) {
  const fs::path l = dir_ / "list.yaml";
  std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\n"
                   << "runs:\n  - { mesh: " << mustard() << " }\n";
  const fs::path run = dir_ / "out" / "task" / "01-YcbMustardBottle";
  const std::string row_start = "task     YcbMustardBottle   0 0 0";
  const auto stale_success = [&] {
    fs::create_directories(run);
    std::ofstream(run / "summary.json") << R"({"run_id": "an-older-run", "outcome": "success", "reason": "held"})";
  };
  const auto batch = [&](const fs::path& fba_run) {
    return evaluate_grasp("--batch " + l.string() + " --random 0 --fba-run " + fba_run.string() + " -o " + (dir_ / "out").string());
  };
  // A run that fails without writing a summary, where an older run's success is.
  stale_success();
  Result r = batch(write_fba_run_stand_in(dir_ / "fails.sh", "echo 'fba-run: the task does not load' >&2; exit 2"));
  ASSERT_EQ(r.status, 0) << r.output;
  std::string row = line_starting(r.output, row_start);
  EXPECT_NE(row.find("no summary"), std::string::npos) << r.output;
  EXPECT_NE(row.find("exit 2, no summary.json; fba-run said: fba-run: the task does not load"), std::string::npos) << row;
  EXPECT_EQ(row.find("success"), std::string::npos) << row;

  // A summary written by something else than this run (another run id), and one without a run id.
  r = batch(write_fba_run_stand_in(dir_ / "other.sh", R"(printf '{"run_id": "someone-else", "outcome": "success"}' > "$dir/summary.json")"));
  ASSERT_EQ(r.status, 0) << r.output;
  row = line_starting(r.output, row_start);
  EXPECT_NE(row.find("no summary"), std::string::npos) << r.output;
  EXPECT_NE(row.find("summary.json is not this run's: run_id someone-else, expected " + given_run_id(run)), std::string::npos) << row;
  r = batch(write_fba_run_stand_in(dir_ / "no-id.sh", R"(printf '{"outcome": "success"}' > "$dir/summary.json")"));
  row = line_starting(r.output, row_start);
  EXPECT_NE(row.find("summary.json is not this run's: no run_id, expected " + given_run_id(run)), std::string::npos) << row;

  // Its own summary, with the id it was given: taken, whatever the folder held before.
  stale_success();
  r = batch(write_fba_run_stand_in(dir_ / "own.sh", R"(printf '{"run_id": "%s", "outcome": "failure", "reason": "no grasp"}' "$id" > "$dir/summary.json")"));
  ASSERT_EQ(r.status, 0) << r.output;
  row = line_starting(r.output, row_start);
  EXPECT_NE(row.find("failure"), std::string::npos) << r.output;
  EXPECT_NE(row.find("no grasp"), std::string::npos) << r.output;
  // Each batch gives its runs ids of their own, so a summary of an earlier batch in the same folder
  // is not this run's either.
  const std::string first = given_run_id(run);
  batch(dir_ / "own.sh");
  EXPECT_NE(given_run_id(run), first);
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

// Mistakes in a list, each refused before anything runs with its place and what was expected.
TEST_F(EvaluateGraspBatch, ListMistakesAreRefusedWithTheirPlaceBeforeAnyRun) {
  const fs::path l = dir_ / "list.yaml";
  const std::string task = "task: " + fba::test::tasks_dir() + "/grasp.yaml\n";
  const std::string runs = "runs:\n  - { mesh: " + mustard() + " }\n";
  std::string meshes;  // 20 meshes, 10000 poses each: more runs than a batch may have
  for (int i = 0; i < 20; ++i) meshes += std::string(i ? ", " : "") + "m" + std::to_string(i) + ".obj";
  const std::pair<std::string, std::string> cases[] = {
      // A variant's name is its folder under -o: '..' would write beside it.
      {task + runs + "variants:\n  - { name: .. }\n",
       "list.yaml:5:13: variant name: expected a plain folder name (no '/' or space, not '.' or '..'); found '..'"},
      {task + runs + "variants:\n  - { name: . }\n", "list.yaml:5:13: variant name: expected a plain folder name"},
      {task + runs + "variants:\n  - { name: a/b }\n", "list.yaml:5:13: variant name: expected a plain folder name"},
      // yaml-cpp would take the first of two equal keys and drop the second silently.
      {task + task + runs, "list.yaml:2:1: duplicate key 'task': expected each key once, found it at " + l.string() + ":1:1 already"},
      {task + "runs:\n  - { mesh: a.obj, pose: [0, 0, 0], mesh: b.obj }\n", "list.yaml:3:37: duplicate key 'mesh': expected each key once, found it at " + l.string() + ":3:7 already"},
      {task + runs + "random_runs:\n  meshes: [m.obj]\n  per_mesh: 1\n  seed: 1\n  seed: 2\n", "list.yaml:8:3: duplicate key 'seed'"},
      {task + runs + "pose_set:\n  - scene.x={x\n",
       "list.yaml:5:5: pose_set: expected a placeholder closed by '}' ({mesh}, {x}, {y} or {yaw}); found '{x' unclosed at character 9 of "
       "'scene.x={x'"},
      {task + "runs: []\n", "list.yaml:2:7: runs: expected at least one run {mesh, pose: [x, y, yaw]} (or random_runs), found an empty list"},
      {task + "runs: {mesh: m.obj}\n", "list.yaml:2:7: runs: expected a list of {mesh, pose: [x, y, yaw], set: [...]}, found a mapping"},
      {task, "list.yaml:1:1: expected a key 'runs' (a list of {mesh, pose: [x, y, yaw]}) or 'random_runs'; found neither"},
      {task + runs + "random_runs:\n  meshes: [" + meshes + "]\n  per_mesh: 10000\n  seed: 1\n",
       "list.yaml:6:13: random_runs: expected at most 100000 runs in a batch; found (20 meshes x 10000 poses + 1 listed runs) x 1 "
       "variant(s) = 200001 runs"}};
  for (const auto& [list, message] : cases) {
    std::ofstream(l) << list;
    const Result r = evaluate_grasp("--batch " + l.string() + " --dry-run");
    EXPECT_EQ(r.status, 2) << list << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << list << r.output;
  }
}

// The grasp measure needs a closed mesh: an open one in a list is refused at its place before the
// runs, not found out after them.
TEST_F(EvaluateGraspBatch, AnOpenMeshIsRefusedAtItsPlaceBeforeAnyRun) {
  fba::TriangleMesh open = fba::geometry::make_box({-0.03, -0.03, 0}, {0.03, 0.03, 0.1});
  open.triangles.pop_back();  // one face of the box half open: three edges of one triangle only
  fba::geometry::write_ply(open, dir_ / "open.ply");
  const fs::path l = dir_ / "list.yaml";
  std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\n"
                   << "runs:\n  - { mesh: " << mustard() << " }\n  - { mesh: open.ply, pose: [0, 0, 90] }\n";
  const fs::path out = dir_ / "out";
  const Result r = evaluate_grasp("--batch " + l.string() + " --random 0 -o " + out.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("list.yaml:4:13: mesh '" + (dir_ / "open.ply").string() +
                          "': expected a closed surface (what is measured is inside it: the volume and centre of mass of a grasp's object, the voxels of a model's truth); found 3 boundary edges"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(out)) << "nothing runs";
}

// SIGTERM, SIGINT or SIGHUP to the batch: its running runs get the same signal and end, the runs
// not started are not run, and the table is written for the runs that finished. The stand-in for
// fba-run finishes the first run at once and waits in the others, writing its pid for the check.
TEST_F(EvaluateGraspBatch, ASignalStopsTheRunningRunsAndWritesTheTableOfTheFinishedOnes) {
  const fs::path stand_in = write_fba_run_stand_in(dir_ / "fba-run.sh", R"(echo $$ > "$dir/pid"
case "$dir" in */01-*) printf '{"run_id": "%s", "outcome": "success"}' "$id" > "$dir/summary.json"; exit 0;; esac
exec sleep 600)");
  const fs::path l = dir_ / "list.yaml";
  std::ofstream(l) << "task: " << fba::test::tasks_dir() << "/grasp.yaml\nruns:\n"
                   << "  - { mesh: " << mustard() << " }\n  - { mesh: " << mustard() << " }\n"
                   << "  - { mesh: " << mustard() << " }\n  - { mesh: " << mustard() << " }\n";
  for (const int sig : {SIGTERM, SIGINT, SIGHUP}) {
    // A signal this test was started ignoring (a background job's SIGINT, nohup's SIGHUP) is
    // ignored by the batch too, as it should be: nothing to test with it.
    struct sigaction now {};
    sigaction(sig, nullptr, &now);
    if (now.sa_handler == SIG_IGN) continue;
    SCOPED_TRACE(strsignal(sig));
    const fs::path out = dir_ / ("out-" + std::to_string(sig));
    fba::test::Child batch({fba::test::program("fba-evaluate"), "grasp", "--batch", l.string(), "--jobs", "2", "--random", "0",
                            "--fba-run", stand_in.string(), "-o", out.string()});
    // Signalled once the first run has ended and the batch has started the next two.
    const std::string progress = batch.read_until("01-YcbMustardBottle: exit 0");
    ASSERT_NE(progress.find("01-YcbMustardBottle: exit 0"), std::string::npos) << progress;
    ASSERT_TRUE(fba::test::wait_for_file(out / "task" / "02-YcbMustardBottle" / "pid")) << progress;
    ASSERT_TRUE(fba::test::wait_for_file(out / "task" / "03-YcbMustardBottle" / "pid")) << progress;
    const int status = batch.wait(sig);
    const std::string output = batch.read_until("");
    EXPECT_EQ(status, 128 + sig) << output;
    // No run outlives the batch: it waited for each (a child not reaped would still be there).
    for (const char* run : {"02-YcbMustardBottle", "03-YcbMustardBottle"}) {
      pid_t pid = 0;
      std::ifstream(out / "task" / run / "pid") >> pid;
      ASSERT_GT(pid, 0) << run;
      EXPECT_NE(kill(pid, 0), 0) << run << " (pid " << pid << ") outlived the batch";
      if (kill(pid, 0) == 0) kill(pid, SIGKILL);  // not left running after a failure
    }
    // The table of the finished run, the others marked, also in table.txt and runs.json.
    EXPECT_NE(line_starting(output, "task     YcbMustardBottle   0 0 0").find("success"), std::string::npos) << output;
    EXPECT_NE(output.find("stopped by " + std::string(sig == SIGTERM ? "SIGTERM" : sig == SIGINT ? "SIGINT" : "SIGHUP") +
                          ": 1 of 4 runs finished"),
              std::string::npos)
        << output;
    std::ifstream in(out / "runs.json");
    const auto runs = nlohmann::json::parse(in, nullptr, false);
    ASSERT_TRUE(runs.is_array() && runs.size() == 4u) << output;
    EXPECT_EQ(runs[0]["outcome"], "success");
    EXPECT_EQ(runs[1]["outcome"], "interrupted");
    EXPECT_NE(runs[1]["reason"].get<std::string>().find("interrupted (the batch was stopped by"), std::string::npos) << runs[1];
    EXPECT_EQ(runs[2]["outcome"], "interrupted");
    EXPECT_EQ(runs[3]["outcome"], "not run");
    EXPECT_NE(runs[3]["reason"].get<std::string>().find("the batch was stopped by"), std::string::npos) << runs[3];
    EXPECT_TRUE(fs::exists(out / "table.txt"));
    // The figures are the finished run's: one run, which selected no grasp.
    EXPECT_NE(line_starting(output, "task     YcbMustardBottle      1 "), "") << output;
  }
}

}  // namespace
