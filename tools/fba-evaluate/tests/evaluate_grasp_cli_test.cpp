// fba-evaluate grasp from the shell: a grasp in summary.json on a true mesh, random sets, and
// clear errors for bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "evaluate_grasp.hpp"
#include "support/build_paths.hpp"

namespace {

namespace fs = std::filesystem;

using Result = fba::test::Result;

using fba::test::evaluate_grasp;

class EvaluateGraspCli : public fba::test::CubeTest {
 protected:
  std::string summary(const std::string& grasp) const {
    const fs::path p = dir_ / "summary.json";
    std::ofstream(p) << R"({"outcome": "success", "grasp": )" << grasp << "}";
    return p.string();
  }
};

TEST_F(EvaluateGraspCli, AGraspOnOpposingFacesIsForceClosureAndBeatsRandomSets) {
  // Thumb on -x, two fingers on +x, given a little off the surface: they are placed on it.
  const std::string s = summary(R"({"contacts": [
      {"position": [-0.051, 0.0, 0.0], "normal": [1, 0, 0]},
      {"position": [0.052, 0.02, 0.0], "normal": [-1, 0, 0]},
      {"position": [0.052, -0.02, 0.0], "normal": [-1, 0, 0]}]})");
  const Result r = evaluate_grasp("--mesh " + mesh() + " --summary " + s + " --random 300");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("moved 1.00 mm along its normal"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("grasp: force closure yes"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("random 300 sets: force closure"), std::string::npos) << r.output;
}

TEST_F(EvaluateGraspCli, EachContactSaysHowFarItsNormalIsFromTheSurfaces) {
  // The thumb's normal 20 degrees off the face's: the model's error the grasp must absorb.
  const std::string s = summary(R"({"contacts": [
      {"position": [-0.05, 0.0, 0.0], "normal": [0.9396926, 0.3420201, 0]},
      {"position": [0.05, 0.02, 0.0], "normal": [-1, 0, 0]},
      {"position": [0.05, -0.02, 0.0], "normal": [-1, 0, 0]}]})");
  const Result r = evaluate_grasp("--mesh " + mesh() + " --summary " + s + " --random 0");
  auto line = [&](const std::string& start) {
    const auto at = r.output.find(start);
    return at == std::string::npos ? std::string() : r.output.substr(at, r.output.find('\n', at) - at);
  };
  EXPECT_NE(line("contact 0 (thumb)").find("moved 0.00 mm along its normal; normal 20.0 deg off the surface's"), std::string::npos)
      << r.output;
  EXPECT_NE(line("contact 1").find("moved 0.00 mm along its normal; normal 0.0 deg off the surface's"), std::string::npos)
      << r.output;
}

TEST_F(EvaluateGraspCli, AGraspOnOneFaceIsNotForceClosureAndExitsOne) {
  const std::string s = summary(R"({"contacts": [
      {"position": [0.05, 0.0, 0.0], "normal": [-1, 0, 0]},
      {"position": [0.05, 0.02, 0.01], "normal": [-1, 0, 0]},
      {"position": [0.05, -0.02, 0.01], "normal": [-1, 0, 0]}]})");
  const Result r = evaluate_grasp("--mesh " + mesh() + " --summary " + s + " --random 0");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("grasp: force closure no, epsilon 0.0000"), std::string::npos) << r.output;
}

TEST_F(EvaluateGraspCli, RandomSetsGiveTheirFigures) {
  const Result r = evaluate_grasp("--mesh " + mesh() + " --random 200");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("random FC"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("cube.ply"), std::string::npos) << r.output;
}

// fba-run's summary.json: the grasp is the one grasp.synthesis reported, under its results.
TEST_F(EvaluateGraspCli, ReadsTheGraspAComponentReported) {
  const std::string grasp = R"({"contacts": [{"position": [-0.05, 0, 0], "normal": [1, 0, 0]}, )"
                            R"({"position": [0.05, 0.02, 0], "normal": [-1, 0, 0]}, )"
                            R"({"position": [0.05, -0.02, 0], "normal": [-1, 0, 0]}]})";
  const fs::path p = dir_ / "run-summary.json";
  std::ofstream(p) << R"({"outcome": "success", "events": [], "components": {"carver": {"type": "vision.octree_carver"},)"
                   << R"( "synthesis": {"type": "grasp.synthesis", "results": {"views": 4, "grasp": )" << grasp << "}}}}";
  Result r = evaluate_grasp("--mesh " + mesh() + " --summary " + p.string() + " --random 0");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("grasp: force closure yes"), std::string::npos) << r.output;

  const fs::path bad = dir_ / "bad-grasp.json";
  std::ofstream(bad) << R"({"components": {"synthesis": {"results": {"grasp": {"contacts": [1, 2]}}}}})";
  r = evaluate_grasp("--mesh " + mesh() + " --summary " + bad.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("components.synthesis.results.grasp.contacts: expected an array of 3 contacts"), std::string::npos)
      << r.output;
}

TEST_F(EvaluateGraspCli, BadInputIsAClearErrorWithStatusTwo) {
  Result r = evaluate_grasp("--mesh " + (dir_ / "missing.obj").string() + " --random 10");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("file does not exist"), std::string::npos) << r.output;

  r = evaluate_grasp("--mesh " + mesh() + " --summary " + summary(R"({"contacts": []})"));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("grasp.contacts: expected an array of 3 contacts"), std::string::npos) << r.output;

  std::ofstream(dir_ / "nograsp.json") << R"({"outcome": "failure"})";
  r = evaluate_grasp("--mesh " + mesh() + " --summary " + (dir_ / "nograsp.json").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("has no \"grasp\" object"), std::string::npos) << r.output;

  std::ofstream(dir_ / "broken.json") << "{ not json";
  r = evaluate_grasp("--mesh " + mesh() + " --summary " + (dir_ / "broken.json").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("is not valid JSON"), std::string::npos) << r.output;

  r = evaluate_grasp("--mesh " + mesh() + " --random 0");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("nothing to evaluate"), std::string::npos) << r.output;

  r = evaluate_grasp("--mesh " + mesh() + " --random 10 --mesh-pose 1 2");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--mesh-pose needs 6 numbers"), std::string::npos) << r.output;
}

TEST_F(EvaluateGraspCli, HelpDocumentsTheSummaryShape) {
  const Result r = evaluate_grasp("--help");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.output.find("\"contacts\": [ {\"position\": [x, y, z], \"normal\": [x, y, z]}"), std::string::npos)
      << r.output;
}

}  // namespace
