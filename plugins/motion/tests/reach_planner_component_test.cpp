// motion.reach_planner through the component harness: a plan from the newest model and joints,
// its stages following the plan's steps on the clock, and a refusal as the event `unreachable`.
#include <gtest/gtest.h>

#include <algorithm>

#include <nlohmann/json.hpp>

#include <fba/testing.hpp>
#include <fba/types/hand_command.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/joint_trajectory.hpp>

#include "support/reach_scenes.hpp"
#include "support/built_plugins.hpp"

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

TEST(ReachPlannerComponent, AGraspItCannotTakeIsAnUnreachableEventWithTheRefusalAndTheReason) {
  ComponentHarness h(fba::test::built_plugins(), "motion.reach_planner");
  h.push("octree", box_model(kBox));
  h.push("joint_state", named_joints(home()));
  h.push("grasp", box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.01));
  h.run();
  EXPECT_TRUE(h.packets("trajectory").empty());
  EXPECT_TRUE(h.packets("hand").empty());
  const auto events = h.events();
  const auto it = std::find_if(events.begin(), events.end(), [](const fba::Event& e) { return e.name == "unreachable"; });
  ASSERT_NE(it, events.end());
  EXPECT_EQ(nlohmann::json::parse(it->payload),
            (nlohmann::json{{"refusal", "table"}, {"reason", "the grasp puts the thumb into the table"}}));
  EXPECT_EQ(h.stage(), "idle");
}

TEST(ReachPlannerComponent, AJointStateWithoutOneOfTheArmsJointsIsARefusalNamingIt) {
  ComponentHarness h(fba::test::built_plugins(), "motion.reach_planner");
  fba::JointState partial = named_joints(home());
  partial.names.pop_back();
  partial.positions.pop_back();
  h.push("octree", box_model(kBox));
  h.push("joint_state", partial);
  h.push("grasp", box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07));
  h.run();
  const auto events = h.events();
  const auto it = std::find_if(events.begin(), events.end(), [](const fba::Event& e) { return e.name == "unreachable"; });
  ASSERT_NE(it, events.end());
  EXPECT_EQ(nlohmann::json::parse(it->payload)["reason"], "the joint state has no position for joint 'shoulder_pan_joint'");
}

TEST(ReachPlannerComponent, ANewGraspReplacesThePlanBeingFollowed) {
  ComponentHarness h(fba::test::built_plugins(), "motion.reach_planner");
  h.push("octree", box_model(kBox));
  h.push("joint_state", named_joints(home()));
  h.push("grasp", box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07));
  h.run();
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
