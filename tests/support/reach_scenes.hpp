// The scenes reach planning is tested on: the project's arm, models voxelised from boxes in the
// tests' own code (tests/support/voxel_shapes.hpp), and grasps placed on them.
#pragma once

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "fba/motion/hand_placement.hpp"
#include "fba/motion/joint_path.hpp"
#include "fba/motion/reach_planner.hpp"
#include "fba/motion/robot_collision.hpp"
#include "fba/types/grasp.hpp"
#include "fba/types/octree.hpp"
#include "support/voxel_shapes.hpp"
#include "support/box_scene.hpp"
#include "support/build_paths.hpp"

namespace fba::motion::test {

using fba::test::box_grasp;
using fba::test::box_model;
using fba::test::workspace;

inline std::string arm_urdf() { return fba::test::source_dir() + "/hardware/robots/wrist_camera_arm.urdf"; }

// The project's arm's planner with the default parameters, built once per test program: its
// collision models take long to build.
inline const ReachPlanner& planner() {
  static const ReachPlanner p(arm_urdf());
  return p;
}

// sim.arm's initial joints: the camera 0.35 m from the origin, 60 degrees up on the arm's side.
inline Eigen::VectorXd home() {
  Eigen::VectorXd q(6);
  q << -0.4148, -2.1223, 2.2888, -2.2234, -1.3679, -0.3644;
  return q;
}

// The same pose drawn back 20 cm along the camera's line of sight: the open hand's fingers, 25 cm
// past the flange, clear of anything standing on the workspace's floor.
inline Eigen::VectorXd ready() {
  static const Eigen::VectorXd q = [] {
    const arm::ArmModel arm(arm_urdf(), "world", "flange");
    const Eigen::Isometry3d flange = arm.forward(home());
    return arm.inverse(Eigen::Translation3d(-0.2 * flange.linear().col(2)) * flange, home()).joints;
  }();
  return q;
}

// The boxes the tests grasp: 6 cm square, 10 cm and 14 cm tall.
inline const Eigen::Vector3d kBox(0.06, 0.06, 0.10);
inline const Eigen::Vector3d kTallBox(0.06, 0.06, 0.14);

// A box standing on the table, centred on (x, y), carved exactly: every other leaf is empty.
// The project's arm with other joint limits: `limits` gives [lower, upper] for each joint in the
// arm's order.
inline arm::ArmModel arm_with_limits(const std::vector<std::pair<double, double>>& limits) {
  std::ifstream in(arm_urdf());
  std::ostringstream text;
  text << in.rdbuf();
  std::string xml = text.str();
  const std::vector<std::string> joints{"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                        "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const std::size_t from = xml.find("lower=\"", xml.find("<joint name=\"" + joints[j] + "\""));
    const std::size_t to = xml.find("velocity=", from);
    xml.replace(from, to - from,
                "lower=\"" + std::to_string(limits[j].first) + "\" upper=\"" + std::to_string(limits[j].second) + "\" effort=\"28\" ");
  }
  return arm::ArmModel::from_string(xml, "wrist_camera_arm.urdf with other limits", "world", "flange");
}

// The rules every plan keeps: it starts at the current joints and stands still there; its times
// increase; every waypoint is within the joint limits and the speeds the planner was given; the
// approach ends at the grasp and the lift at the lift's pose; and, checked again finer than the
// planner checks, no motion touches anything: the hand open and the model an obstacle until the
// close, closed and the model not checked (the object in the hand) until the release. A start
// whose hand is in the model backs out of it first, touching neither the table nor the arm
// itself, and the hand opens where the back-out ends, clear of the model.
inline void expect_a_sound_plan(const ReachPlanner& planner, const ReachPlan& plan, const Grasp& grasp, const Octree& model,
                                const Eigen::VectorXd& current) {
  ASSERT_TRUE(plan.ok) << plan.why;
  const auto& arm = planner.arm();
  const ReachParams& p = planner.params();
  const auto& points = plan.trajectory.points;
  ASSERT_EQ(plan.trajectory.names, arm.joint_names());
  ASSERT_GE(points.size(), 2u);
  const auto at = [](const fba::JointTrajectoryPoint& w) {
    return Eigen::Map<const Eigen::VectorXd>(w.positions.data(), static_cast<Eigen::Index>(w.positions.size())).eval();
  };
  EXPECT_EQ(points.front().time, 0.0);
  EXPECT_EQ(at(points.front()), current);
  for (std::size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ(points[i].positions.size(), arm.size());
    ASSERT_EQ(points[i].velocities.size(), arm.size());
    if (i > 0) {
      EXPECT_GT(points[i].time, points[i - 1].time) << "waypoint " << i;
    }
    EXPECT_EQ(arm.limit_violation(at(points[i])), "") << "waypoint " << i;
    for (std::size_t j = 0; j < arm.size(); ++j)
      EXPECT_LE(std::abs(points[i].velocities[j]), arm.limits()[j].velocity * p.speed_scale * (1 + 1e-9)) << "waypoint " << i;
  }
  // The steps in order, back to back, and the arm where each says.
  const std::vector<std::string> names{"plan", "approach", "close", "lift", "hold", "retreat"};
  ASSERT_EQ(plan.steps.size(), p.retreat ? 6u : 5u);
  for (std::size_t s = 0; s < plan.steps.size(); ++s) {
    EXPECT_EQ(plan.steps[s].name, names[s]);
    if (s > 0) {
      EXPECT_EQ(plan.steps[s].start_s, plan.steps[s - 1].end_s);
    }
  }
  EXPECT_EQ(plan.steps.back().end_s, points.back().time);
  const auto joints_at = [&](double t) {
    const auto w = std::find_if(points.begin(), points.end(), [&](const fba::JointTrajectoryPoint& x) { return x.time >= t - 1e-9; });
    return at(*w);
  };
  const auto palm = [&](const Eigen::VectorXd& q) { return arm.forward(q) * p.flange_from_palm; };
  EXPECT_TRUE(joints_at(plan.steps[0].end_s).isApprox(plan.pregrasp_joints, 1e-12));
  EXPECT_TRUE(joints_at(plan.steps[1].end_s).isApprox(plan.grasp_joints, 1e-12));
  EXPECT_TRUE(joints_at(plan.steps[3].end_s).isApprox(plan.lift_joints, 1e-12));
  EXPECT_TRUE(palm(plan.pregrasp_joints).isApprox(plan.pregrasp_palm, 1e-4));
  EXPECT_TRUE(palm(plan.grasp_joints).isApprox(plan.grasp_palm, 1e-4));
  EXPECT_TRUE(palm(plan.lift_joints).isApprox(plan.lift_palm, 1e-4));
  EXPECT_NEAR((plan.lift_palm.translation() - plan.grasp_palm.translation()).z(), p.lift_height, 1e-12);

  // The hand: open for the pregrasp at once, close when the approach ends, open again (if it
  // retreats) once the object is back down.
  ASSERT_EQ(plan.hand.size(), p.retreat ? 3u : 2u);
  EXPECT_EQ(plan.hand[0].action, fba::HandCommand::Action::Open);
  if (plan.backout_path.empty()) {
    EXPECT_EQ(plan.hand[0].time, 0.0);
    EXPECT_EQ(plan.start_joints, current);
  } else {
    EXPECT_EQ(plan.backout_path.front(), current);
    EXPECT_EQ(plan.backout_path.back(), plan.start_joints);
    EXPECT_GT(plan.hand[0].time, 0.0);
  }
  EXPECT_TRUE(joints_at(plan.hand[0].time).isApprox(plan.start_joints, 1e-12));
  EXPECT_EQ(plan.hand[1].action, fba::HandCommand::Action::Close);
  EXPECT_EQ(plan.hand[1].time, plan.steps[1].end_s);
  EXPECT_EQ(plan.hand[1].force, p.finger_force);
  const double released = p.retreat ? plan.hand[2].time : points.back().time + 1;

  RobotCollision robot(arm, p.flange_from_palm);
  const std::array<Eigen::Vector3d, 3> contacts{grasp.contacts[0].position, grasp.contacts[1].position, grasp.contacts[2].position};
  robot.set_model(ReachPlanner::obstacles(model), contacts, p.contact_allowance);
  const double closed_width = place_hand(grasp, p.clearance).width;
  auto free = [&](const Eigen::VectorXd& q) { return robot.collision(q); };
  robot.set_hand(plan.opening, plan.spread);
  EXPECT_EQ(robot.collision(plan.start_joints), "");
  for (std::size_t i = 1; i < points.size(); ++i) {
    const bool holding = points[i - 1].time >= plan.hand[1].time && points[i].time <= released;
    const bool backing_out = points[i].time <= plan.hand[0].time;
    robot.set_hand(holding ? closed_width : plan.opening, plan.spread);
    robot.check_model(!holding && !backing_out);
    EXPECT_EQ(motion_collision(at(points[i - 1]), at(points[i]), p.collision_step / 4, free), "")
        << "between waypoints " << i - 1 << " and " << i << " at " << points[i].time << " s";
  }
}

}  // namespace fba::motion::test
