// Reach planning on known scenes: a box before the arm grasped from above, its far side, the
// table, space not yet carved, and the same plan twice.
#include <gtest/gtest.h>

#include "fba/motion/joint_path.hpp"
#include "fba/motion/reach_planner.hpp"
#include "fba/motion/robot_collision.hpp"
#include "support/reach_scenes.hpp"

using namespace fba::motion;
using namespace fba::motion::test;

namespace {

// The model of kBox on the table and of a box of space the views have not carved yet, `size`
// about `centre`.
fba::Octree box_and_uncarved(const Eigen::Vector3d& centre, const Eigen::Vector3d& size) {
  const auto box = fba::grasp::test::box_sdf(Eigen::Vector3d(0, 0, kBox.z() / 2), kBox);
  const auto uncarved = fba::grasp::test::box_sdf(centre, size);
  return fba::grasp::test::voxelise([&](const Eigen::Vector3d& p) { return std::min(box(p), uncarved(p)); }, workspace(), 6);
}

// The robot's collisions as `planner` checks them for `grasp`: the hand open for it, `model` the obstacle.
RobotCollision robot_for(const ReachPlanner& planner, const fba::Grasp& grasp, const fba::Octree& model) {
  const ReachParams& p = planner.params();
  RobotCollision robot(planner.arm(), p.flange_from_palm);
  robot.set_hand(place_hand(grasp, p.clearance).opening, grasp.spread);
  robot.set_model(ReachPlanner::obstacles(model));
  return robot;
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
  EXPECT_FALSE(refused.model_blocked);  // the arm itself: no view clears it

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
  EXPECT_FALSE(side.model_blocked);
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
  const JointPath path = plan_joint_path(forward, backward, arm.limits(), free, {2000, 30, 0.02, 1});
  EXPECT_FALSE(path.ok);
  EXPECT_EQ(path.why.rfind("no collision-free path found in 2000 poses checked: ", 0), 0u) << path.why;
  EXPECT_NE(path.why.find("touches the table"), std::string::npos) << path.why;
}

// Space the views have not carved yet stands above the box where the hand comes down: refused
// until it is carved.
TEST(ReachPlanner, SpaceNotYetCarvedIsAnObstacleUntilItIsCarved) {
  const fba::Octree before = box_and_uncarved(Eigen::Vector3d(0, 0, 0.15), Eigen::Vector3d(0.09, 0.09, 0.10));
  const fba::Grasp grasp = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07);
  ASSERT_EQ(RobotCollision(planner().arm(), ReachParams{}.flange_from_palm).collision(ready()), "");
  const ReachPlan refused = planner().plan(grasp, before, ready());
  EXPECT_FALSE(refused.ok);
  EXPECT_EQ(refused.refusal, Refusal::Collision);
  EXPECT_EQ(refused.why.rfind("the pregrasp puts the thumb into the model at (", 0), 0u) << refused.why;
  EXPECT_TRUE(refused.model_blocked);  // what synthesis asks views for (the hand's way in)
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

// At a view pose the open hand's fingers reach 24 cm past the flange, into space the views have not
// carved yet above the object: the arm backs out along the flange's axis until the hand is clear,
// and plans from there; the trajectory begins with that retreat. Backing out less than it takes is
// refused with the reason, each way tried.
TEST(ReachPlanner, AStartWhoseFingersAreInSpaceNotYetCarvedBacksOutAlongTheFlangesAxisFirst) {
  // A slab above the box, between where the thumb and the fingers come down for the grasp below
  // (at x = -5 cm and +5 cm), where the hand's fingers are at home (6 cm either side of y = 0).
  const fba::Octree model = box_and_uncarved(Eigen::Vector3d(-0.015, 0, 0.15), Eigen::Vector3d(0.03, 0.14, 0.06));
  const fba::Grasp grasp = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07);
  const ReachParams& p = planner().params();
  RobotCollision robot = robot_for(planner(), grasp, model);
  const std::string touches = robot.collision(home());
  ASSERT_NE(touches.find("touches the model"), std::string::npos) << touches;
  ASSERT_EQ(touches.find("palm"), std::string::npos) << touches;  // the fingers, in space not yet carved
  robot.check_model(false);
  ASSERT_EQ(robot.collision(home()), "");  // nothing else

  const ReachPlan plan = planner().plan(grasp, model, home());
  expect_a_sound_plan(planner(), plan, grasp, model, home());
  ASSERT_GE(plan.backout_path.size(), 2u);
  EXPECT_GT(plan.figures.backout, 0.0);
  EXPECT_LE(plan.figures.backout, p.max_backout + 1e-9);
  // Straight back along the flange's axis, the flange turning not at all, one cartesian step apart.
  const Eigen::Isometry3d start = planner().arm().forward(home());
  for (std::size_t i = 1; i < plan.backout_path.size(); ++i) {
    const Eigen::Isometry3d at = planner().arm().forward(plan.backout_path[i]);
    const Eigen::Vector3d moved = at.translation() - start.translation();
    EXPECT_NEAR(moved.dot(-start.linear().col(2)), p.cartesian_step * static_cast<double>(i), 1e-3) << i;
    EXPECT_LT((moved - moved.dot(start.linear().col(2)) * start.linear().col(2)).norm(), 1e-3) << i;
    EXPECT_LT(fba::arm::angle_between(at, start), 1e-2) << i;
  }
  EXPECT_NEAR(plan.figures.backout, p.cartesian_step * static_cast<double>(plan.backout_path.size() - 1), 1e-3);
  // reachable() backs out the same way, and plans the same pregrasp from there.
  const ReachPlan quick = planner().reachable(grasp, model, home());
  ASSERT_TRUE(quick.ok) << quick.why;
  EXPECT_EQ(quick.backout_path, plan.backout_path);
  EXPECT_EQ(quick.pregrasp_joints, plan.pregrasp_joints);

  // Allowed to back out a centimetre only, and no joint positions drawn: the fingers are still in
  // it there.
  ReachParams near = p;
  near.max_backout = 0.01;
  near.jiggle_draws = 0;
  const ReachPlan refused = ReachPlanner(arm_urdf(), near).plan(grasp, model, home());
  EXPECT_FALSE(refused.ok);
  EXPECT_EQ(refused.refusal, Refusal::Start);
  EXPECT_EQ(refused.why.rfind("the current joints put the ", 0), 0u) << refused.why;
  EXPECT_NE(refused.why.find(" into the model at ("), std::string::npos) << refused.why;
  EXPECT_NE(refused.why.find(", and backing out of it fails: along the flange's axis: 0.010 m back (max_backout), it still puts the "),
            std::string::npos)
      << refused.why;
  EXPECT_NE(refused.why.find("; straight up: 0.010 m back (max_backout), it still puts the "), std::string::npos) << refused.why;
  EXPECT_NE(refused.why.find("; by joints alone: not tried (jiggle_draws 0)"), std::string::npos) << refused.why;
  // Not at all: refused as before, whatever the draws.
  near.jiggle_draws = p.jiggle_draws;
  near.max_backout = 0;
  const ReachPlan kept = ReachPlanner(arm_urdf(), near).plan(grasp, model, home());
  EXPECT_EQ(kept.refusal, Refusal::Start);
  EXPECT_EQ(kept.why, "the current joints collide, with the hand open for the pregrasp: " + touches);
  // The grasp alone (check_start off, as grasp synthesis asks): reachable, from where the arm stands.
  near.check_start = false;
  const ReachPlan alone = ReachPlanner(arm_urdf(), near).reachable(grasp, model, home());
  EXPECT_TRUE(alone.ok) << alone.why;
  EXPECT_TRUE(alone.backout_path.empty());
  EXPECT_EQ(alone.start_joints, home());
}

// A view on the far side of the object, where the arm is stretched towards the end of its reach
// (the task's second view): it cannot back out along the flange's axis, away from its base, so it
// backs out straight up, and plans from there.
TEST(ReachPlanner, AStartTheArmCannotBackOutOfAlongTheFlangesAxisBacksOutStraightUp) {
  Eigen::VectorXd far(6);
  far << -0.2328, -0.7103, 0.6413, -0.4664, -1.5849, 3.1332;
  // Not carved yet: a slab beside the box, on the far side, where the fingers are.
  const fba::Octree model = box_and_uncarved(Eigen::Vector3d(0.07, 0, 0.15), Eigen::Vector3d(0.06, 0.16, 0.06));
  const fba::Grasp grasp = box_grasp(kBox, Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitZ(), 0.07);
  const ReachParams& p = planner().params();
  RobotCollision robot = robot_for(planner(), grasp, model);
  ASSERT_NE(robot.collision(far).find("touches the model"), std::string::npos);
  const Eigen::Isometry3d start = planner().arm().forward(far);
  ASSERT_GT(start.translation().x(), 0.2);  // beyond the object, seen from the arm's base at x = -0.45
  ASSERT_LT(start.linear().col(2).x(), -0.8);  // looking back towards it: backing out goes away from the base

  const ReachPlan plan = planner().plan(grasp, model, far);
  expect_a_sound_plan(planner(), plan, grasp, model, far);
  ASSERT_GE(plan.backout_path.size(), 2u);
  for (std::size_t i = 1; i < plan.backout_path.size(); ++i) {
    const Eigen::Vector3d moved = planner().arm().forward(plan.backout_path[i]).translation() - start.translation();
    EXPECT_NEAR(moved.z(), p.cartesian_step * static_cast<double>(i), 1e-3) << i;
    EXPECT_LT(moved.head<2>().norm(), 1e-3) << i;
  }
}

// Where no straight line backs the hand out (here: allowed a centimetre only, as when a view at the
// end of the arm's reach leaves no room along the flange's axis nor upwards), joint positions drawn
// around the current ones take it out: the trajectory starts with that one motion, every joint
// within jiggle_share of its range, and the plan from there is sound.
TEST(ReachPlanner, AStartNoLineBacksOutOfIsLeftByJointsAlone) {
  const fba::Octree model = box_and_uncarved(Eigen::Vector3d(-0.015, 0, 0.15), Eigen::Vector3d(0.03, 0.14, 0.06));
  const fba::Grasp grasp = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07);
  ReachParams p = planner().params();
  p.max_backout = 0.01;
  const ReachPlanner jiggling(arm_urdf(), p);
  const ReachPlan plan = jiggling.plan(grasp, model, home());
  expect_a_sound_plan(jiggling, plan, grasp, model, home());
  ASSERT_EQ(plan.backout_path.size(), 2u);
  EXPECT_EQ(plan.backout_path.front(), home());
  EXPECT_EQ(plan.start_joints, plan.backout_path.back());
  const auto& limits = jiggling.arm().limits();
  for (std::size_t i = 0; i < limits.size(); ++i)
    EXPECT_LE(std::abs(plan.start_joints(static_cast<Eigen::Index>(i)) - home()(static_cast<Eigen::Index>(i))),
              p.jiggle_share * (limits[i].upper - limits[i].lower) + 1e-12)
        << i;
  RobotCollision robot = robot_for(jiggling, grasp, model);
  EXPECT_EQ(robot.collision(plan.start_joints), "");
  EXPECT_NE(robot.collision(home()), "");
  // The same way out on every run.
  EXPECT_EQ(jiggling.reachable(grasp, model, home()).backout_path, plan.backout_path);
}
