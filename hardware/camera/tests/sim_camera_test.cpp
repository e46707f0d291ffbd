// sim.camera against its twin vision.camera: one interface, so a profile can swap them; the
// parameter that names the object's world; and an object outside the workspace refused.
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include <fba/testing.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "support/built_plugins.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"
#include "support/mesh_files.hpp"
#include "support/child_process.hpp"
#include "support/temp_dir.hpp"

namespace {

using fba::testing::ComponentHarness;

using fba::test::kCan;

std::vector<std::tuple<std::string, std::string, bool>> ports(const std::vector<fba::PortSpec>& list) {
  std::vector<std::tuple<std::string, std::string, bool>> out;
  for (const auto& p : list) out.emplace_back(p.name, p.type->name, p.required);
  return out;
}

std::vector<std::string> events(const fba::Spec& s) {
  std::vector<std::string> out;
  for (const auto& e : s.events()) out.push_back(e.name);
  return out;
}

}  // namespace

TEST(SimCameraSpec, PortsAndEventsAreVisionCameras) {
  const auto sim = fba::test::built_plugins().find("sim.camera");
  const auto real = fba::test::built_plugins().find("vision.camera");
  ASSERT_TRUE(sim && real);
  EXPECT_EQ(sim->spec.kind(), real->spec.kind());
  EXPECT_EQ(ports(sim->spec.inputs()), ports(real->spec.inputs()));
  EXPECT_EQ(ports(sim->spec.outputs()), ports(real->spec.outputs()));
  EXPECT_EQ(events(sim->spec), events(real->spec));
}

TEST(SimCamera, TheLastViewpointIsFollowedByLostAsTheEndOfAVideoFile) {
  ComponentHarness h(fba::test::built_plugins(), "sim.camera",
                     {{"mesh", kCan}, {"views", 3}, {"width", 64}, {"height", 48}, {"fx", 60.0}});
  h.run();
  EXPECT_EQ(h.packets("frame").size(), 3u);
  const auto all = h.events();
  std::vector<fba::Event> lost;
  for (const auto& e : all)
    if (e.name == "lost") lost.push_back(e);
  ASSERT_EQ(lost.size(), 1u);
  EXPECT_EQ(lost[0].payload, "sim_YcbMasterChefCan");  // the frames' source: the mesh's folder, as its file is model.obj
}

TEST(SimCamera, TheOldNameOfTheWorldParameterIsRefusedListingTheNewOne) {
  try {
    ComponentHarness h(fba::test::built_plugins(), "sim.camera", {{"mesh", kCan}, {"frame", "table"}});
    FAIL() << "'frame' (now the output's name only) was taken as a parameter";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("has no parameter 'frame'"), std::string::npos) << what;
    EXPECT_NE(what.find("world"), std::string::npos) << what;
  }
}

namespace {

// tasks/grasp.yaml's workspace, where the sim profile's camera requires the object to stand.
const std::vector<double> kWorkspace = {-0.13, -0.13, -0.02, 0.13, 0.13, 0.24};

// Why sim.camera refused to be built with these parameters; empty if it was built.
std::string refusal(fba::testing::Params params) {
  params.emplace("world", "table");
  params.emplace("workspace", kWorkspace);
  try {
    ComponentHarness h(fba::test::built_plugins(), "sim.camera", params);
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

}  // namespace

TEST(SimCamera, AMeshInMillimetresIsRefusedAsOutsideTheWorkspace) {
  fba::test::TempDir dir;
  fba::TriangleMesh can = fba::geometry::load_mesh(kCan);
  for (auto& v : can.vertices) v *= 1000;
  const auto obj = dir.path() / "can_mm.obj";
  fba::test::write_obj(can, obj);
  const std::string what = refusal({{"mesh", obj.string()}});
  EXPECT_NE(what.find("the object 'can_mm' is outside the workspace: expected it within [-0.130, -0.130, -0.020, 0.130, 0.130, 0.240]"),
            std::string::npos)
      << what;
  EXPECT_NE(what.find("found it 102.289 x 102.446 x 140.144 m centred at"), std::string::npos) << what;
  EXPECT_NE(what.find("it is larger than the workspace; divided by 1000 it would be 0.102 x 0.102 x 0.140 m: the mesh may be in "
                      "millimetres while metres are expected"),
            std::string::npos)
      << what;
}

TEST(SimCamera, AnObjectMovedOutOfTheWorkspaceIsRefusedWithItsPlace) {
  const std::string what = refusal({{"mesh", kCan}, {"object_x", 0.3}});
  EXPECT_NE(what.find("the object 'YcbMasterChefCan' is outside the workspace: expected it within [-0.130, -0.130, -0.020, 0.130, 0.130, 0.240]"),
            std::string::npos)
      << what;
  EXPECT_NE(what.find("found it 0.102 x 0.102 x 0.140 m centred at (0.292, 0.015, 0.070) (object_x 0.3, object_y 0): its centre "
                      "lies outside the workspace"),
            std::string::npos)
      << what;
  EXPECT_EQ(what.find("millimetres"), std::string::npos) << what;
}

TEST(SimCamera, AnObjectInTheWorkspaceIsRendered) {
  EXPECT_EQ(refusal({{"mesh", kCan}, {"object_x", 0.02}, {"object_yaw", 40.0}}), "");
}

// Through the task as a user runs it: the sim profile gives the camera the task's workspace, and
// the refusal is a configuration error at the camera's line, before anything runs.
TEST(SimCamera, TheGraspTaskRefusesAnObjectOutsideItsWorkspaceAtTheCamerasLine) {
  for (const char* type : {"sim.arm", "sim.hand", "grasp.synthesis", "examples.counter"})
    if (!fba::test::built_plugins().find(type)) GTEST_SKIP() << type << " is not built";
  fba::test::TempDir dir;
  const auto r = fba::test::run_shell("'" + fba::test::program("fba-run") + "' '" + fba::test::tasks_dir() +
                                        "/grasp.yaml' --set scene.x=0.3 -o '" + dir.path().string() + "'");
  EXPECT_EQ(r.status, 2) << r.output;  // a configuration error
  EXPECT_NE(r.output.find("profiles/sim.yaml:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("component 'camera' (sim.camera) refused its configuration: the object 'YcbMustardBottle' is outside the workspace"),
            std::string::npos)
      << r.output;
}
