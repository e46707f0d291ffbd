// sim.hand through the component harness: a grasp in, the lift test's result and an event out.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <fba/testing.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/grasp_execution.hpp>
#include <fba/types/hand_command.hpp>
#include "fba/geometry/object_families.hpp"
#include <fba/types/joint_trajectory.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "lift_test.hpp"
#include "ring_grasp.hpp"
#include "scenes.hpp"
#include "support/built_plugins.hpp"
#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"
#include "support/events.hpp"
#include "support/mesh_files.hpp"

namespace {

using fba::testing::ComponentHarness;

using fba::sim_hand::test::open_then_close;
using fba::test::find_event;
using fba::test::kCan;

// The ring grasp on the can as sim.hand places it (at x, y, yaw degrees).
fba::Grasp can_grasp(double x, double y, double yaw_deg, double thumb_deg) {
  const auto placed = fba::sim_hand::place_on_table(fba::geometry::load_mesh(kCan), {x, y, yaw_deg * M_PI / 180});
  return fba::sim_hand::ring_grasp(placed, fba::geometry::mesh_bounds(placed).center().z(), thumb_deg * M_PI / 180);
}

TEST(SimHand, GoodGraspHoldsAndSaysSo) {
  ComponentHarness h(fba::test::built_plugins(), "sim.hand", {{"mesh", kCan}, {"object_x", 0.05}, {"object_yaw", 20.0}});
  h.push<fba::Grasp>("grasp", can_grasp(0.05, 0, 20, 180));
  EXPECT_EQ(h.run(), 1);
  const auto results = h.values<fba::GraspExecution>("result");
  ASSERT_EQ(results.size(), 1u);
  EXPECT_TRUE(results[0].held) << results[0].reason;
  EXPECT_GE(results[0].contacts.size(), 3u);
  const auto held = find_event(h.events(), "held");
  ASSERT_TRUE(held);
  EXPECT_FALSE(find_event(h.events(), "dropped"));
  const auto payload = nlohmann::json::parse(held->payload);
  EXPECT_EQ(payload["held"], true);
  EXPECT_EQ(payload["contacts"].size(), results[0].contacts.size());
  EXPECT_DOUBLE_EQ(payload["slip_m"].get<double>(), results[0].slip_m);
  // What MuJoCo collided the object as: its boxes and their fit to the mesh.
  EXPECT_GT(payload["object"]["boxes"].get<int>(), 10);
  EXPECT_DOUBLE_EQ(payload["object"]["voxel_m"].get<double>(), 0.003);
  EXPECT_GT(payload["object"]["iou"].get<double>(), 0.95);
}

// An OBJ beyond MuJoCo's 200,000 faces: once MuJoCo refused the scene ("perhaps this is an ASCII
// file?"); MuJoCo is now given the object's voxels as boxes, or a convex object's hull of at most
// a thousand vertices, whatever its triangles. A can of 60,000 sides, convex: its hull.
TEST(SimHand, AMeshOverMuJoCosFaceLimitIsGrasped) {
  fba::test::TempDir dir;
  const auto obj = dir.path() / "fine_can.obj";
  auto can = fba::geometry::make_cylinder_shape(0.035, 0.1, 60000);
  for (auto& v : can.vertices) v.z() += 0.05f;  // its base on the table
  ASSERT_GT(can.triangles.size(), 200000u);
  fba::test::write_obj(can, obj);
  ComponentHarness h(fba::test::built_plugins(), "sim.hand", {{"mesh", obj.string()}});
  h.push<fba::Grasp>("grasp", fba::sim_hand::ring_grasp(can, 0.05, 0));
  h.run();
  const auto results = h.values<fba::GraspExecution>("result");
  ASSERT_EQ(results.size(), 1u);
  EXPECT_TRUE(results[0].held) << results[0].reason;
  const auto held = find_event(h.events(), "held");
  ASSERT_TRUE(held);
  EXPECT_EQ(nlohmann::json::parse(held->payload)["object"]["collides_as"], "convex hull");
}

TEST(SimHand, InTheMeshFrameGraspsAndContactsAreInTheMeshFilesCoordinates) {
  // The world sim.camera renders the mesh in: the can as the file has it, centred near z = 0.
  const auto mesh = fba::geometry::load_mesh(kCan);
  const auto bounds = fba::geometry::mesh_bounds(mesh);
  ASSERT_LT(bounds.min().z(), -0.05);
  ComponentHarness h(fba::test::built_plugins(), "sim.hand", {{"mesh", kCan}, {"world", "mesh"}});
  h.push<fba::Grasp>("grasp", fba::sim_hand::ring_grasp(mesh, bounds.center().z(), M_PI));
  h.run();
  const auto results = h.values<fba::GraspExecution>("result");
  ASSERT_EQ(results.size(), 1u);
  EXPECT_TRUE(results[0].held) << results[0].reason;
  ASSERT_FALSE(results[0].contacts.empty());
  for (const auto& c : results[0].contacts) {
    EXPECT_GT(c.position.z(), bounds.min().z() - 0.01) << c.link;
    EXPECT_LT(c.position.z(), bounds.max().z() + 0.01) << c.link;
  }
}

TEST(SimHand, BadGraspGivesDroppedWithTheReason) {
  ComponentHarness h(fba::test::built_plugins(), "sim.hand", {{"mesh", kCan}});
  auto grasp = can_grasp(0, 0, 0, 0);
  for (auto& c : grasp.contacts) c.position.z() += 0.2;  // closes on the air above the can
  h.push<fba::Grasp>("grasp", grasp);
  h.run();
  const auto results = h.values<fba::GraspExecution>("result");
  ASSERT_EQ(results.size(), 1u);
  EXPECT_FALSE(results[0].held);
  const auto dropped = find_event(h.events(), "dropped");
  ASSERT_TRUE(dropped);
  const auto payload = nlohmann::json::parse(dropped->payload);
  EXPECT_EQ(payload["held"], false);
  EXPECT_EQ(payload["reason"], results[0].reason);
  EXPECT_NE(results[0].reason.find("no contact"), std::string::npos) << results[0].reason;
}

// The safe state opens the hand and ends the simulation: a grasp that would hold is not executed
// after it, and the result says why.
TEST(SimHand, AfterTheSafeStateNoGraspIsExecuted) {
  ComponentHarness h(fba::test::built_plugins(), "sim.hand", {{"mesh", kCan}});
  h.safe_state();
  h.push<fba::Grasp>("grasp", can_grasp(0, 0, 0, 0));
  h.run();
  const auto results = h.values<fba::GraspExecution>("result");
  ASSERT_EQ(results.size(), 1u);
  EXPECT_FALSE(results[0].held);
  EXPECT_NE(results[0].reason.find("safe state"), std::string::npos) << results[0].reason;
}

// object_rest: side lays the can on its side (its axis along y after the quarter turn about x),
// where the ring grasp at its mid height, from above, still holds it.
TEST(SimHand, AnObjectLaidOnItsSideRestsOnTheTable) {
  const auto mesh = fba::geometry::load_mesh(kCan);
  const auto upright = fba::geometry::mesh_bounds(fba::sim_hand::place_on_table(mesh, {}));
  fba::sim_hand::ObjectPlacement side;
  side.rest = "side";
  const auto placed = fba::sim_hand::place_on_table(mesh, side);
  const auto lying = fba::geometry::mesh_bounds(placed);
  EXPECT_NEAR(lying.min().z(), 0.0, 1e-6);
  EXPECT_NEAR(lying.sizes().y(), upright.sizes().z(), 1e-4);  // the can's height now lies along y
  EXPECT_NEAR(lying.sizes().z(), upright.sizes().y(), 1e-4);
  side.rest = "sideways";
  EXPECT_THROW(fba::sim_hand::place_on_table(mesh, side), std::invalid_argument);
}

// A reach plan as motion.reach_planner sends it: the grasp names the contacts, the trajectory and
// the commands drive the arm and the hand in the world, and the close ends in held.
TEST(SimHand, AReachPlansTrajectoryAndCommandsAreExecutedInTheWorld) {
  fba::test::TempDir dir;
  const auto obj = dir.path() / "box.obj";
  const Eigen::Vector3d size(0.06, 0.06, 0.10);
  fba::test::write_obj(fba::sim_hand::test::box_mesh(size), obj);
  ComponentHarness h(fba::test::built_plugins(), "sim.hand", {{"mesh", obj.string()}}, {"commands", "trajectory"});
  const fba::Grasp g = fba::sim_hand::test::box_grasp(size, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.06);
  const fba::sim_hand::LiftTest world(fba::sim_hand::test::box_mesh(size), {});
  const auto plan = fba::sim_hand::test::planner().plan(g, fba::sim_hand::test::box_model(size), world.start_joints());
  ASSERT_TRUE(plan.ok) << plan.why;
  h.push<fba::Grasp>("grasp", g);
  h.push<fba::JointTrajectory>("trajectory", plan.trajectory);
  for (const auto& c : plan.hand) h.push<fba::HandCommand>("commands", c);
  h.run();
  const auto results = h.values<fba::GraspExecution>("result");
  ASSERT_EQ(results.size(), 1u);  // at the close
  EXPECT_TRUE(results[0].held) << results[0].reason;
  EXPECT_TRUE(find_event(h.events(), "held"));
}

// As hw.robotiq_3f does, the twin closes with the Robotiq's least grip force, 15 N, when a close asks
// for less: the same contact forces as a close with 15 N, and other ones than with 30 N.
TEST(SimHand, ACloseWithLessThanTheHandsLeastForceClosesWithItsLeast) {
  fba::test::TempDir dir;
  const auto obj = dir.path() / "box.obj";
  const Eigen::Vector3d size(0.06, 0.06, 0.10);
  fba::test::write_obj(fba::sim_hand::test::box_mesh(size), obj);
  const fba::Grasp g = fba::sim_hand::test::box_grasp(size, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.06);
  const fba::sim_hand::LiftTest world(fba::sim_hand::test::box_mesh(size), {});
  const auto plan = fba::sim_hand::test::planner().plan(g, fba::sim_hand::test::box_model(size), world.start_joints());
  ASSERT_TRUE(plan.ok) << plan.why;
  const auto contact_forces = [&](double newtons) {
    ComponentHarness h(fba::test::built_plugins(), "sim.hand", {{"mesh", obj.string()}}, {"commands", "trajectory"});
    h.push<fba::Grasp>("grasp", g);
    h.push<fba::JointTrajectory>("trajectory", plan.trajectory);
    for (auto c : plan.hand) {
      if (c.action == fba::HandCommand::Action::Close) c.force = newtons;
      h.push<fba::HandCommand>("commands", c);
    }
    h.run();
    const auto results = h.values<fba::GraspExecution>("result");
    std::vector<double> forces;
    if (results.size() == 1)
      for (const auto& c : results[0].contacts) forces.push_back(c.force);
    return forces;
  };
  const std::vector<double> weak = contact_forces(5), least = contact_forces(15), firm = contact_forces(30);
  ASSERT_GE(least.size(), 3u);
  EXPECT_EQ(weak, least);
  EXPECT_NE(firm, least);
}

// Commands without a trajectory connected: the arm stays where it starts, and the hand closes
// there, on nothing.
TEST(SimHand, CommandsWithoutATrajectoryCloseWhereTheArmStands) {
  ComponentHarness h(fba::test::built_plugins(), "sim.hand", {{"mesh", kCan}}, {"commands"});
  for (const auto& command : open_then_close()) h.push<fba::HandCommand>("commands", command);
  h.run();
  const auto results = h.values<fba::GraspExecution>("result");
  ASSERT_EQ(results.size(), 1u);
  EXPECT_FALSE(results[0].held);
  EXPECT_NE(results[0].reason.find("no contact with the object"), std::string::npos) << results[0].reason;
}

TEST(SimHand, MissingMeshIsAClearError) {
  fba::test::TempDir dir;
  const std::string missing = (dir.path() / "no_such_mesh.obj").string();
  try {
    ComponentHarness h(fba::test::built_plugins(), "sim.hand", {{"mesh", missing}});
    FAIL() << "no error";
  } catch (const fba::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_mesh.obj"), std::string::npos) << e.what();
  }
}

TEST(SimHand, MeshThatDoesNotLoadIsAClearError) {
  fba::test::TempDir dir;
  const std::string broken = dir.file("broken.obj", "this is not a mesh\n");
  EXPECT_THROW(ComponentHarness(fba::test::built_plugins(), "sim.hand", {{"mesh", broken}}), fba::ConfigError);
}

}  // namespace
