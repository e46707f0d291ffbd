// The scenes the whole-robot lift test is tested on: boxes and a U standing on the table before the
// arm, grasps placed on them, and reach planning's plans for them (the project's URDF, models
// voxelised in the tests' own code, tests/support/voxel_shapes.hpp).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "arm_model.hpp"
#include "fba/geometry/mesh_io.hpp"
#include "fba/motion/reach_planner.hpp"
#include "fba/types/grasp.hpp"
#include "fba/types/hand_command.hpp"
#include "fba/types/joint_trajectory.hpp"
#include "fba/types/octree.hpp"
#include "support/voxel_shapes.hpp"
#include "support/box_scene.hpp"
#include "support/wrist_camera_arm.hpp"

namespace fba::sim_hand::test {

using fba::test::box_grasp;
using fba::test::box_model;
using fba::test::workspace;

// The hand opened to a pregrasp (10 cm, the fingers 4 cm apart), then closed with 15 N at
// `close_time` on the arm's trajectory.
inline std::vector<HandCommand> open_then_close(double close_time = 0) {
  HandCommand open;
  open.opening = 0.1;
  open.spread = 0.04;
  HandCommand close;
  close.action = HandCommand::Action::Close;
  close.force = 15;
  close.time = close_time;
  return {open, close};
}

// A box standing on the table, centred on (x, y).
inline TriangleMesh box_mesh(const Eigen::Vector3d& size, double x = 0, double y = 0) {
  return geometry::make_box(Eigen::Vector3d(x - size.x() / 2, y - size.y() / 2, 0), Eigen::Vector3d(x + size.x() / 2, y + size.y() / 2, size.z()));
}

// The same box carved exactly, 4 mm leaves: reach planning's model of it.
// Reach planning for the project's robot, as sim.hand's own plans are made (no retreat: the
// verdict is in at the hold's end).
inline motion::ReachPlanner planner() {
  motion::ReachParams p;
  p.retreat = false;
  return motion::ReachPlanner(fba::test::wrist_camera_arm_urdf(), p);
}

// The arm's joints that put the palm at world_from_palm (the palm 7.5 cm out along the flange's
// axis), nearest `seed`.
inline Eigen::VectorXd joints_for_palm(const Eigen::Isometry3d& world_from_palm, const Eigen::VectorXd& seed) {
  static const arm::ArmModel arm(fba::test::wrist_camera_arm_urdf(), "world", "flange");
  const auto ik = arm.inverse(world_from_palm * Eigen::Translation3d(0, 0, -0.075), seed);
  return ik.ok ? ik.joints : Eigen::VectorXd();
}

// The palm pointing down (its x along the world's x) with its frame at `at`.
inline Eigen::Isometry3d palm_down(const Eigen::Vector3d& at) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  t.translation() = at;
  return t;
}

// A trajectory through the joint vectors, `dt` apart, still at both ends (velocities by central
// differences).
inline JointTrajectory through(const std::vector<Eigen::VectorXd>& q, double dt, const std::vector<std::string>& names) {
  JointTrajectory t;
  t.names = names;
  for (std::size_t i = 0; i < q.size(); ++i) {
    Eigen::VectorXd v = Eigen::VectorXd::Zero(q[i].size());
    if (i > 0 && i + 1 < q.size()) v = (q[i + 1] - q[i - 1]) / (2 * dt);
    t.points.push_back({double(i) * dt, {q[i].data(), q[i].data() + q[i].size()}, {v.data(), v.data() + v.size()}});
  }
  return t;
}

}  // namespace fba::sim_hand::test
