// tasks/grasp.yaml: the grasp loop with its arm, camera and hand as device slots, bound by a profile
// (tasks/profiles/sim.yaml).
#include <gtest/gtest.h>

#include <fba/registry.hpp>
#include <fba/task.hpp>

#include "support/built_plugins.hpp"
#include "support/fba_run.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"

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
