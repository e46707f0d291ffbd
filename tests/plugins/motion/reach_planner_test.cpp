// Reach planning on known scenes: a box before the arm grasped from above, its far side, the
// table, space not yet carved, and the same plan twice.
#include <gtest/gtest.h>

#include "fba/motion/joint_path.hpp"
#include "fba/motion/reach_planner.hpp"
#include "fba/motion/robot_collision.hpp"
#include "scenes.hpp"

using namespace fba::motion;
using namespace fba::motion::test;

namespace {

const ReachPlanner& planner() {
  static const ReachPlanner p(arm_urdf());
  return p;
}

}  // namespace

TEST(ReachPlanner, ABoxBeforeTheArmIsTakenFromAboveOnACollisionFreeTimedTrajectory) {
  const fba::Octree model = box_model(kBox);
  const fba::Grasp grasp = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07);
  const ReachPlan plan = planner().plan(grasp, model, home());
  expect_a_sound_plan(planner(), plan, grasp, model, home());
  EXPECT_GE(plan.figures.ik_attempts, 1 + 5 + 10);  // the pregrasp, then 1 cm steps: 5 cm in, 10 cm up
  EXPECT_GT(plan.figures.path_length, 0);
  // The hand's commands carry the pregrasp: the contacts' 6 cm plus 1 cm a side, fingers 4 cm apart.
  EXPECT_NEAR(plan.hand[0].opening, 0.08, 1e-12);
  EXPECT_NEAR(plan.hand[0].spread, 0.04, 1e-12);
}

TEST(ReachPlanner, ReachableChecksEverythingButThePathAndAgreesWithThePlan) {
  const fba::Octree model = box_model(kBox);
  const fba::Grasp grasp = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07);
  const ReachPlan quick = planner().reachable(grasp, model, home());
  ASSERT_TRUE(quick.ok) << quick.why;
  EXPECT_TRUE(quick.trajectory.points.empty());
  const ReachPlan plan = planner().plan(grasp, model, home());
  EXPECT_EQ(quick.pregrasp_joints, plan.pregrasp_joints);
  EXPECT_EQ(quick.lift_joints, plan.lift_joints);
  const fba::Grasp too_low = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.01);
  EXPECT_EQ(planner().reachable(too_low, model, home()).why, planner().plan(too_low, model, home()).why);
}

// The far side of a tall box, from the arm's base: horizontally the hand would have to turn back
// on the forearm; from above at 45 degrees the arm reaches over the box.
TEST(ReachPlanner, AGraspOnTheFarSideIsReachedRoundTheObjectOrRefusedWithItsReason) {
  const fba::Octree model = box_model(kTallBox);
  const fba::Grasp level = box_grasp(kTallBox, Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitX(), 0.1);
  const ReachPlan refused = planner().plan(level, model, home());
  EXPECT_FALSE(refused.ok);
  EXPECT_EQ(refused.refusal, Refusal::Collision);
  EXPECT_EQ(refused.why.rfind("every IK solution for the pregrasp at (0.200, 0.000, 0.100), approach (-1.000, ", 0), 0u) << refused.why;
  EXPECT_NE(refused.why.find("palm touches forearm_link"), std::string::npos) << refused.why;

  const fba::Grasp over = box_grasp(kTallBox, Eigen::Vector3d::UnitY(), Eigen::Vector3d(-1, 0, -1), 0.08);
  const ReachPlan reached = planner().plan(over, model, home());
  expect_a_sound_plan(planner(), reached, over, model, home());
  EXPECT_FALSE(reached.figures.direct);  // the straight joint-space line is blocked: the path goes round
}

TEST(ReachPlanner, AGraspWhoseHandWouldReachIntoTheTableIsRefused) {
  // From the side at 1.5 cm up, the palm (13 cm across the approach) reaches 5 cm below the top.
  const Eigen::Vector3d low(0.06, 0.06, 0.03);
  const ReachPlan side = planner().plan(box_grasp(low, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitX(), 0.015), box_model(low), home());
  EXPECT_EQ(side.refusal, Refusal::Table);
  EXPECT_EQ(side.why, "the pregrasp puts the palm into the table");
  // From above at 1 cm up, the fingers reach 2.5 cm past their contacts.
  const ReachPlan deep =
      planner().plan(box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.01), box_model(kBox), home());
  EXPECT_EQ(deep.refusal, Refusal::Table);
  EXPECT_EQ(deep.why, "the grasp puts the thumb into the table");
}

// An arm whose shoulder may not point up (its lift joint limited to [-0.3, 3.14]) and whose other
// joints are held: from the upper arm forward to the upper arm backward it can only swing through
// straight down, 34 cm into the table.
TEST(ReachPlanner, APathThatCouldOnlyGoThroughTheTableIsRefused) {
  const double w1 = 0, w2 = M_PI / 2, w3 = 0;
  const auto arm = arm_with_limits({{-1e-3, 1e-3}, {-0.3, 3.14}, {-1.6, 1.8}, {w1 - 1e-3, w1 + 1e-3}, {w2 - 1e-3, w2 + 1e-3}, {w3 - 1e-3, w3 + 1e-3}});
  RobotCollision robot(arm, ReachParams{}.flange_from_palm);
  Eigen::VectorXd forward(6), backward(6);
  forward << 0, -0.2, -M_PI / 2 + 0.2, w1, w2, w3;   // the forearm up
  backward << 0, 3.1, 3 * M_PI / 2 - 3.1, w1, w2, w3;
  ASSERT_EQ(robot.collision(forward), "");
  ASSERT_EQ(robot.collision(backward), "");
  const auto free = [&](const Eigen::VectorXd& q) { return robot.collision(q); };
  EXPECT_NE(motion_collision(forward, backward, 0.02, free).find("touches the table"), std::string::npos);
  const JointPath path = plan_joint_path(forward, backward, arm.limits(), free, {0.2, 0.02, 1});
  EXPECT_FALSE(path.ok);
  EXPECT_EQ(path.why.rfind("no collision-free path found in 0.2 s: ", 0), 0u) << path.why;
  EXPECT_NE(path.why.find("touches the table"), std::string::npos) << path.why;
}

// Space the views have not carved yet stands above the box where the hand comes down: refused
// until it is carved.
TEST(ReachPlanner, SpaceNotYetCarvedIsAnObstacleUntilItIsCarved) {
  const auto box = fba::grasp::test::box_sdf(Eigen::Vector3d(0, 0, kBox.z() / 2), kBox);
  const auto uncarved = fba::grasp::test::box_sdf(Eigen::Vector3d(0, 0, 0.15), Eigen::Vector3d(0.09, 0.09, 0.10));
  const fba::Octree before = fba::grasp::test::voxelise([&](const Eigen::Vector3d& p) { return std::min(box(p), uncarved(p)); }, workspace(), 6);
  const fba::Grasp grasp = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07);
  ASSERT_EQ(RobotCollision(planner().arm(), ReachParams{}.flange_from_palm).collision(ready()), "");
  const ReachPlan refused = planner().plan(grasp, before, ready());
  EXPECT_FALSE(refused.ok);
  EXPECT_EQ(refused.refusal, Refusal::Collision);
  EXPECT_EQ(refused.why.rfind("the pregrasp puts the thumb into the model at (", 0), 0u) << refused.why;
  const fba::Octree after = box_model(kBox);
  expect_a_sound_plan(planner(), planner().plan(grasp, after, ready()), grasp, after, ready());
}

TEST(ReachPlanner, TheSameSeedGivesTheSameTrajectory) {
  const fba::Octree model = box_model(kTallBox);
  const fba::Grasp over = box_grasp(kTallBox, Eigen::Vector3d::UnitY(), Eigen::Vector3d(-1, 0, -1), 0.08);
  const ReachPlan first = planner().plan(over, model, home());
  ASSERT_TRUE(first.ok) << first.why;
  ASSERT_FALSE(first.figures.direct);  // searched, not the straight line
  const ReachPlanner again(arm_urdf());
  for (const ReachPlan& second : {planner().plan(over, model, home()), again.plan(over, model, home())}) {
    ASSERT_EQ(second.trajectory.points.size(), first.trajectory.points.size());
    for (std::size_t i = 0; i < first.trajectory.points.size(); ++i) {
      EXPECT_EQ(second.trajectory.points[i].time, first.trajectory.points[i].time) << i;
      EXPECT_EQ(second.trajectory.points[i].positions, first.trajectory.points[i].positions) << i;
    }
  }
}

TEST(ReachPlanner, ParametersOutOfRangeAreRefusedByName) {
  ReachParams p;
  p.planning_time = 0;
  try {
    ReachPlanner(arm_urdf(), p);
    FAIL() << "accepted planning_time 0";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "reach planner: planning_time must be > 0, found 0");
  }
}
