// tasks/grasp.yaml: the grasp loop with its arm, camera and hand as device slots, bound by a profile
// (tasks/profiles/sim.yaml), and the robot's measured transforms, its parameters under every profile
// and the robot the live view is sent.
#include <signal.h>

#include <gtest/gtest.h>

#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <fba/registry.hpp>
#include <fba/task.hpp>

#include "support/built_plugins.hpp"
#include "support/child_process.hpp"
#include "support/fba_run.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"
#include "support/live_client.hpp"

namespace {

using fba::test::built_plugins;

const std::string kGrasp = fba::test::tasks_dir() + "/grasp.yaml";

fba::LoadOptions profile(const std::string& name, std::vector<std::string> sets = {}) {
  fba::LoadOptions o;
  o.profile = name;
  for (auto& s : sets) o.overrides.push_back({std::move(s)});
  return o;
}

}  // namespace

// The object is one parameter: the camera's mesh and the hand's cannot be set apart.
TEST(GraspTask, TheObjectIsOneParameterOfCameraAndHand) {
  try {
    fba::load_task(kGrasp, built_plugins(), profile("sim", {"camera.mesh=" + fba::test::tasks_dir() + "/grasp.yaml"}));
    FAIL() << "loaded";
  } catch (const fba::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("camera.mesh comes from the task parameter 'scene.mesh' (also hand.mesh); set it with --set scene.mesh=..."),
              std::string::npos)
        << e.what();
  }
  const std::string mesh = fba::test::ycb_mesh("YcbMustardBottle");
  const auto task = fba::load_task(kGrasp, built_plugins(), profile("sim", {"scene.mesh=" + mesh}));
  EXPECT_EQ(std::get<std::string>(task.find("camera")->params.at("mesh")), mesh);
  EXPECT_EQ(std::get<std::string>(task.find("hand")->params.at("mesh")), mesh);
}

TEST(GraspTask, CheckShowsTheParametersAndEachSlotsTypeAndInterface) {
  const auto r = fba::test::fba_run({kGrasp, "--check", "--profile", "sim", "--set", "depth=7"});
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* line : {"parameter depth = 7  (int, --set)\n", "parameter scene.mesh = ", "  (path, profile default)\n", "profile sim (",
                           "slot arm: sim.arm\n", "slot camera: sim.camera\n    inputs:  pose (fba.Pose, optional)\n    outputs: frame (fba.Frame)\n",
                           "slot hand: sim.hand\n    inputs:  commands (fba.HandCommand, optional), grasp (fba.Grasp), trajectory (fba.JointTrajectory, "
                           "optional)\n    outputs: result (fba.GraspExecution)\n"
                           "    events:  dropped, held, error, finished\n"})
    EXPECT_NE(r.output.find(line), std::string::npos) << line << " in:\n" << r.output;
}

// The robot's measured transforms are the task's parameters: set once, under every profile, they
// reach every component that reads the robot (each declares the robot's parameters alike), the
// slots' arm and sim.hand as the task's own reach, synthesis and planner.
TEST(GraspTask, TheRobotsMeasuredTransformsSetOnceReachEveryComponentThatReadsTheRobot) {
  const std::map<std::string, std::vector<double>> measured{{"base_pose", {-0.44, 0.01, 0.002, 0, 0, 0.01}},
                                                            {"flange_to_palm", {0.001, 0, 0.08, 0, 0, 0.02}},
                                                            {"flange_to_camera", {0, 0.061, 0.029, 0.01, 0, 0}}};
  std::vector<std::string> sets;
  for (const auto& [name, v] : measured) {
    std::string list;
    for (double x : v) list += (list.empty() ? "" : ",") + std::to_string(x);
    sets.push_back("robot." + name + "=[" + list + "]");
  }
  const std::map<std::string, std::set<std::string>> readers{
      {"sim", {"arm", "hand", "reach", "synthesis", "planner"}},
      {"emulated", {"arm", "reach", "synthesis", "planner"}},
      {"real", {"arm", "reach", "synthesis", "planner"}}};
  std::map<std::string, fba::ParamSpec> declared;  // as the first reader declares them: the others alike
  for (const auto& [name, expected] : readers) {
    const auto task = fba::load_task(kGrasp, built_plugins(), profile(name, sets));
    std::set<std::string> found;
    for (const auto& c : task.components) {
      const fba::Spec& spec = c.type->spec;
      if (!spec.find_param("urdf")) continue;
      found.insert(c.name);
      for (const auto& [param, value] : measured) {
        ASSERT_NE(spec.find_param(param), nullptr) << c.name << " (" << spec.type_name() << ") reads the robot without " << param;
        EXPECT_EQ(std::get<std::vector<double>>(c.params.at(param)), value) << name << ": " << c.name << "." << param;
      }
      for (const char* param : {"urdf", "base_pose", "flange_to_palm", "flange_to_camera"}) {
        const fba::ParamSpec& p = *spec.find_param(param);
        const fba::ParamSpec& first = declared.emplace(param, p).first->second;
        EXPECT_EQ(p.type, first.type) << c.name << "." << param;
        EXPECT_EQ(p.default_value, first.default_value) << c.name << "." << param;
        EXPECT_EQ(p.sizes, first.sizes) << c.name << "." << param;
        EXPECT_EQ(p.doc, first.doc) << c.name << "." << param;
      }
    }
    EXPECT_EQ(found, expected) << name;
  }
}

namespace {

// The origin of the URDF's joint `joint`: its xyz and rpy, six numbers (empty when it has none).
std::vector<double> joint_origin(const std::string& urdf, const std::string& joint) {
  const std::regex origin("<joint name=\"" + joint + "\"[\\s\\S]*?<origin xyz=\"([^\"]*)\" rpy=\"([^\"]*)\"");
  std::smatch m;
  if (!std::regex_search(urdf, m, origin)) return {};
  std::istringstream numbers(m[1].str() + " " + m[2].str());
  std::vector<double> v;
  for (double x; numbers >> x;) v.push_back(x);
  return v;
}

}  // namespace

// The robot a live view draws is the one the components use: the arm sends it as a view, its URDF
// with the measured transforms in place, so a base set on the task is where the page puts the base.
TEST(GraspTask, TheLiveViewIsSentTheRobotWithItsMeasuredBase) {
  using namespace fba::test;
  const std::vector<double> base{0.12, -0.34, 0.05, 0, 0, 0.5};
  Child child(fba_run_command({kGrasp, "--set", "robot.base_pose=[0.12,-0.34,0.05,0,0,0.5]", "--serve", "0"}));
  const std::string prefix = "fba-run: live view at ";
  const std::string line = child.read_line_with(prefix, kHangLimit);
  ASSERT_EQ(line.rfind(prefix, 0), 0u) << child.read_until(prefix, {});
  const LiveUrl url = parse_live_url(line.substr(prefix.size()));
  LiveSocket socket(url);
  beast::error_code ec;
  socket.handshake(url.origin(), url.token, ec);
  ASSERT_FALSE(ec) << ec.message();
  nlohmann::json robot;
  while (robot.is_null()) {
    const std::string text = socket.read(ec);
    ASSERT_FALSE(ec) << "the stream ended without the arm's robot: " << ec.message();
    const nlohmann::json m = nlohmann::json::parse(text);
    ASSERT_FALSE(m["type"] == "task" && m.contains("robot")) << "the task message carries no robot of its own";
    if (m["type"] == "view" && m["port"] == "arm.robot") robot = m["view"];
  }
  child.wait(SIGINT, kHangLimit);
  ASSERT_EQ(robot["kind"], "robot");
  const std::vector<double> origin = joint_origin(robot["urdf"].get<std::string>(), "world_to_base");
  ASSERT_EQ(origin.size(), 6u) << robot["urdf"];
  for (std::size_t i = 0; i < 6; ++i) EXPECT_NEAR(origin[i], base[i], 1e-12) << i;
  EXPECT_NE(robot["name"].get<std::string>().find("base_pose"), std::string::npos) << robot["name"];
}

// A measured transform of five numbers, set on the task: the task does not load, and each place
// it reaches says which parameter, what it needs and where the value came from.
TEST(GraspTask, AMalformedMeasuredTransformIsAClearErrorNamingTheParameter) {
  try {
    fba::load_task(kGrasp, built_plugins(), profile("sim", {"robot.flange_to_camera=[0,0.06,0.03,0,0]"}));
    FAIL() << "loaded";
  } catch (const fba::ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--set robot.flange_to_camera=[0,0.06,0.03,0,0]: error: component 'arm' (sim.arm): parameter 'flange_to_camera' "
                        "must have 0 or 6 numbers; found 5 (arm.flange_to_camera is ${robot.flange_to_camera} at "),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("component 'reach' (motion.reach_planner): parameter 'flange_to_camera' must have 0 or 6 numbers; found 5"),
              std::string::npos)
        << what;
  }
}
