// The types' views are there whenever a plugin that uses the types is loaded: this program links
// only the core, as fba-run does, so the views come from the libraries the plugins load (each type's
// header keeps its library among a plugin's needed libraries: robot_types_views.hpp, image_views.hpp).
#include <gtest/gtest.h>

#include <filesystem>

#include <fba/data_type.hpp>
#include <fba/registry.hpp>
#include <fba/view.hpp>

#include "support/build_paths.hpp"

namespace {

fba::ViewFunction view_of_type(const char* name) { return fba::find_view(fba::find_type(name)); }

}  // namespace

TEST(ViewRegistration, ComesWithThePluginsThatUseTheTypes) {
  ASSERT_EQ(view_of_type("fba.Frame"), nullptr) << "this program must not link the types' libraries";
  ASSERT_EQ(view_of_type("fba.Pose"), nullptr);
  fba::Registry registry;
  // sim.arm sends poses, joint states and takes trajectories, and calls no function of the robot
  // types' library. (Built when the arm's kinematics libraries are there.)
  const std::filesystem::path arm = fba::test::plugin_dir() + "/fba-sim_arm.so";
  if (std::filesystem::exists(arm)) {
    registry.load_plugin(arm);
    EXPECT_NE(view_of_type("fba.Pose"), nullptr);
    EXPECT_NE(view_of_type("fba.JointState"), nullptr);
    EXPECT_NE(view_of_type("fba.JointTrajectory"), nullptr);
    EXPECT_EQ(view_of_type("fba.Frame"), nullptr) << "the arm uses no image type";
  }
  // sim.camera renders a fba.Frame from a fba.Pose and calls no function of the image types' library.
  registry.load_plugin(fba::test::plugin_dir() + "/fba-sim.so");
  EXPECT_NE(view_of_type("fba.Frame"), nullptr);
  EXPECT_NE(view_of_type("fba.Pose"), nullptr);
  registry.load_plugin(fba::test::plugin_dir() + "/fba-vision.so");
  for (const char* type : {"fba.Silhouette", "fba.Octree", "fba.Grasp", "fba.GraspCandidates", "fba.RegionsOfInterest"})
    EXPECT_NE(view_of_type(type), nullptr) << type;
}
