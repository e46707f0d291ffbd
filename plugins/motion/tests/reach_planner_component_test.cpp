// motion.reach_planner through the component harness: a plan from the newest model and joints,
// its stages following the plan's steps on the clock, a refusal as the event `unreachable`, and
// the palm where the robot's parameter flange_to_palm puts it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include <fba/task_config.hpp>
#include <fba/testing.hpp>
#include <fba/types/hand_command.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/joint_trajectory.hpp>

#include "support/reach_scenes.hpp"
#include "support/built_plugins.hpp"
#include "support/events.hpp"

using fba::testing::ComponentHarness;
using namespace fba::motion::test;

namespace {

// The arm's joints, named and in reverse order: the planner reads them by name.
fba::JointState named_joints(const Eigen::VectorXd& q) {
  fba::JointState s;
  s.names = {"wrist_3_joint", "wrist_2_joint", "wrist_1_joint", "elbow_joint", "shoulder_lift_joint", "shoulder_pan_joint"};
  for (Eigen::Index i = q.size() - 1; i >= 0; --i) s.positions.push_back(q(i));
  return s;
}

std::int64_t nanoseconds(double s) { return static_cast<std::int64_t>(std::llround(s * 1e9)); }

// The box's model, the arm at `joints`, and a grasp of the box from above with its contacts at
// `height`, given to the planner at once.
void plan_from_above(ComponentHarness& h, const fba::JointState& joints, double height) {
  h.push("octree", box_model(kBox));
  h.push("joint_state", joints);
  h.push("grasp", box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), height));
  h.run();
}

}  // namespace

TEST(ReachPlannerComponent, PlansTheGraspFromTheNewestModelAndJointsAndItsStagesFollowThePlan) {
  ComponentHarness h(fba::test::built_plugins(), "motion.reach_planner", {{"hold_time", 1.5}});
  EXPECT_EQ(h.stage(), "idle");
  h.push("grasp", box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07));
  h.run();
  EXPECT_TRUE(h.packets("trajectory").empty());  // no model or joints yet: the grasp waits
  h.push("octree", box_model(kBox));
  h.push("joint_state", named_joints(home()));
  h.run();
  ASSERT_EQ(h.packets("trajectory").size(), 1u) << h.failure();
  const auto trajectory = h.values<fba::JointTrajectory>("trajectory")[0];
  EXPECT_EQ(trajectory.names.front(), "shoulder_pan_joint");
  const Eigen::VectorXd start = home();
  EXPECT_EQ(trajectory.points.front().positions, std::vector<double>(start.data(), start.data() + 6));
  const auto hand = h.values<fba::HandCommand>("hand");
  ASSERT_EQ(hand.size(), 3u);
  EXPECT_EQ(hand[0].action, fba::HandCommand::Action::Open);
  EXPECT_EQ(hand[1].action, fba::HandCommand::Action::Close);
  EXPECT_EQ(hand[2].action, fba::HandCommand::Action::Open);
  EXPECT_EQ(h.stage(), "plan");

  // As time passes (a joint state arriving runs the component), the stage is the plan's step.
  auto stage_at = [&](double t) {
    h.set_time(nanoseconds(t));
    h.push("joint_state", named_joints(home()));
    h.run();
    return h.stage();
  };
  EXPECT_EQ(stage_at(hand[1].time - 0.01), "approach");
  EXPECT_EQ(stage_at(hand[1].time + 0.01), "close");
  EXPECT_EQ(stage_at(hand[1].time + 1.0 + 0.01), "lift");  // the hand's 1 s to close, then the lift
  // The hold: the arm still for 1.5 s, between two waypoints.
  const auto& p = trajectory.points;
  const auto hold = std::adjacent_find(p.begin(), p.end(), [](const auto& a, const auto& b) { return std::abs(b.time - a.time - 1.5) < 1e-9; });
  ASSERT_NE(hold, p.end());
  EXPECT_EQ(hold->positions, (hold + 1)->positions);
  EXPECT_EQ(stage_at(hold->time + 0.75), "hold");
  EXPECT_EQ(stage_at(trajectory.points.back().time - 0.01), "retreat");
  EXPECT_EQ(stage_at(trajectory.points.back().time + 0.01), "idle");
  EXPECT_EQ(h.failure(), "");
}

// A grasp that comes while the arm moves (to a view asked for before it was selected) waits for
// the arm to stop: the arm takes a trajectory only where it stands still, and the plan starts from
// the joints where it stopped.
TEST(ReachPlannerComponent, AGraspWaitsForTheArmToStandStill) {
  ComponentHarness h(fba::test::built_plugins(), "motion.reach_planner");
  h.push("octree", box_model(kBox));
  fba::JointState moving = named_joints(home());
  moving.velocities.assign(moving.positions.size(), 0.0);
  moving.velocities[1] = 0.2;
  h.push("joint_state", moving);
  h.push("grasp", box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07));
  h.run();
  EXPECT_TRUE(h.packets("trajectory").empty());
  EXPECT_EQ(h.stage(), "idle");
  fba::JointState still = named_joints(home());
  still.velocities.assign(still.positions.size(), 0.0);
  h.push("joint_state", still);
  h.run();
  ASSERT_EQ(h.packets("trajectory").size(), 1u) << h.failure();
  const Eigen::VectorXd start = home();
  EXPECT_EQ(h.values<fba::JointTrajectory>("trajectory")[0].points.front().positions, std::vector<double>(start.data(), start.data() + 6));
}

TEST(ReachPlannerComponent, AGraspItCannotTakeIsAnUnreachableEventWithTheRefusalAndTheReason) {
  ComponentHarness h(fba::test::built_plugins(), "motion.reach_planner");
  plan_from_above(h, named_joints(home()), 0.01);
  EXPECT_TRUE(h.packets("trajectory").empty());
  EXPECT_TRUE(h.packets("hand").empty());
  const auto unreachable = fba::test::find_event(h.events(), "unreachable");
  ASSERT_TRUE(unreachable.has_value());
  EXPECT_EQ(nlohmann::json::parse(unreachable->payload),
            (nlohmann::json{{"refusal", "table"}, {"reason", "the grasp puts the thumb into the table"}}));
  EXPECT_EQ(h.stage(), "idle");
}

TEST(ReachPlannerComponent, AJointStateWithoutOneOfTheArmsJointsIsARefusalNamingIt) {
  ComponentHarness h(fba::test::built_plugins(), "motion.reach_planner");
  fba::JointState partial = named_joints(home());
  partial.names.pop_back();
  partial.positions.pop_back();
  plan_from_above(h, partial, 0.07);
  const auto unreachable = fba::test::find_event(h.events(), "unreachable");
  ASSERT_TRUE(unreachable.has_value());
  EXPECT_EQ(nlohmann::json::parse(unreachable->payload)["reason"], "the joint state has no position for joint 'shoulder_pan_joint'");
}

TEST(ReachPlannerComponent, ANewGraspReplacesThePlanBeingFollowed) {
  ComponentHarness h(fba::test::built_plugins(), "motion.reach_planner");
  plan_from_above(h, named_joints(home()), 0.07);
  const auto hand = h.values<fba::HandCommand>("hand");
  ASSERT_EQ(hand.size(), 3u) << h.failure();
  h.set_time(nanoseconds(hand[1].time + 0.01));
  h.push("joint_state", named_joints(home()));
  h.run();
  EXPECT_EQ(h.stage(), "close");
  // One it cannot take: refused, and nothing left to follow.
  h.push("grasp", box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.01));
  h.run();
  EXPECT_EQ(h.stage(), "idle");
  h.set_time(nanoseconds(hand[2].time + 0.01));
  h.push("joint_state", named_joints(home()));
  h.run();
  EXPECT_EQ(h.stage(), "idle");
  EXPECT_EQ(h.failure(), "");
}

namespace {

// The flange's pose where the plan closes the hand (the trajectory's waypoint at the close), for
// the box's grasp from above, with the planner's parameters `params`.
Eigen::Isometry3d flange_at_close(const fba::testing::Params& params) {
  ComponentHarness h(fba::test::built_plugins(), "motion.reach_planner", params);
  plan_from_above(h, named_joints(home()), 0.07);
  const auto trajectory = h.values<fba::JointTrajectory>("trajectory");
  const auto hand = h.values<fba::HandCommand>("hand");
  if (trajectory.size() != 1 || hand.size() != 3) throw std::runtime_error("no plan: " + h.failure());
  const auto& points = trajectory[0].points;
  const auto at = std::find_if(points.begin(), points.end(), [&](const auto& p) { return std::abs(p.time - hand[1].time) < 1e-9; });
  if (at == points.end()) throw std::runtime_error("no waypoint at the close");
  static const fba::arm::ArmModel to_flange(arm_urdf(), "world", "flange");
  return to_flange.forward(Eigen::Map<const Eigen::VectorXd>(at->positions.data(), 6));
}

}  // namespace

// The palm measured elsewhere on the flange (the robot's parameter flange_to_palm): the plan puts
// the palm where the grasp needs it all the same, so the flange stands elsewhere, by the
// difference. Without the parameter, the URDF's flange_to_palm joint places it.
TEST(ReachPlannerComponent, AFlangeToPalmSetThroughTheParameterMovesThePalmItPlansFor) {
  const std::vector<double> urdf_palm{0, 0, 0.075, 0, 0, 0};  // hardware/robots/wrist_camera_arm.urdf
  const std::vector<double> measured{0.004, -0.003, 0.09, 0, 0, 0.2};
  const Eigen::Isometry3d flange = flange_at_close({});
  const Eigen::Isometry3d flange_measured = flange_at_close({{"flange_to_palm", measured}});
  const Eigen::Isometry3d palm = flange * fba::arm::pose_from_xyz_rpy(urdf_palm, "urdf");
  const Eigen::Isometry3d palm_measured = flange_measured * fba::arm::pose_from_xyz_rpy(measured, "measured");
  // The same palm pose (within the IK's tolerances), reached with the flange 1.5 cm further back.
  EXPECT_LT((palm_measured.translation() - palm.translation()).norm(), 1e-3);
  EXPECT_LT(fba::arm::angle_between(palm_measured, palm), 2e-3);
  EXPECT_GT((flange_measured.translation() - flange.translation()).norm(), 0.01);
  // Read with the URDF's palm, the measured plan's hand would stand off the grasp.
  EXPECT_GT(((flange_measured * fba::arm::pose_from_xyz_rpy(urdf_palm, "urdf")).translation() - palm.translation()).norm(), 0.01);
}

TEST(ReachPlannerComponent, AMalformedFlangeToPalmIsAClearErrorNamingTheParameter) {
  try {
    ComponentHarness h(fba::test::built_plugins(), "motion.reach_planner", {{"flange_to_palm", std::vector<double>{0, 0, 0.075, 0, 0}}});
    FAIL() << "accepted";
  } catch (const fba::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("parameter 'flange_to_palm' must have 0 or 6 numbers; found 5"), std::string::npos) << e.what();
  }
}
