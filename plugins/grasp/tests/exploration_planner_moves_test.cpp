// grasp.exploration_planner with the arm's joints: every view goes out as the joints to move to,
// the straight joint-space motion there clear of the arm itself, the table and the model, checked
// here again on the project's arm; a view whose move crosses the model is passed over.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <fba/testing.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/pose.hpp>
#include <fba/types/regions_of_interest.hpp>

#include "fba/motion/joint_path.hpp"
#include "fba/motion/model_obstacles.hpp"
#include "fba/motion/robot_collision.hpp"
#include "support/built_plugins.hpp"
#include "support/events.hpp"
#include "support/reach_scenes.hpp"
#include "support/voxel_shapes.hpp"

using fba::testing::ComponentHarness;

namespace {

namespace mt = fba::motion::test;
using fba::grasp::test::box_sdf;
using fba::grasp::test::Sdf;

// A band of candidate views like tasks/grasp.yaml's but nearer the object (0.32 m, where the arm
// reaches 46 of them), on the simulated robot (the parameters' default).
fba::testing::Params band_of_views() {
  return {{"views", std::string("hemisphere")}, {"count", 48},         {"distance", 0.32},
          {"min_elevation_deg", 20.0},          {"max_elevation_deg", 70.0}, {"centre", std::vector<double>{0, 0, 0.09}},
          {"half_fov_deg", 25.0},               {"initial_layout", std::string("spread")}, {"reachable_only", true}};
}

// The object: a 6 x 6 x 10 cm block on the table; and a request for its +x face, about a model of
// three views.
const Sdf kObject = box_sdf({0, 0, 0.05}, {0.06, 0.06, 0.10});
fba::RegionsOfInterest block_plus_x_face() {
  fba::RegionsOfInterest r{{Eigen::AlignedBox3d(Eigen::Vector3d(0.025, -0.02, 0.02), Eigen::Vector3d(0.035, 0.02, 0.08))}};
  r.model_views = 3;
  return r;
}

// A model of three views over a cube wide enough to hold the arm's reach (9 mm leaves).
fba::Octree model_of(const Sdf& sdf) {
  return fba::grasp::test::voxelise(sdf, Eigen::AlignedBox3d(Eigen::Vector3d(-0.6, -0.6, -0.3), Eigen::Vector3d(0.6, 0.6, 0.9)), 7, {}, 3);
}

struct Robot {
  fba::arm::ArmModel to_camera{mt::arm_urdf(), "world", "camera"};
  fba::arm::ArmModel to_flange{mt::arm_urdf(), "world", "flange"};
  std::string urdf = [] {
    std::ifstream in(mt::arm_urdf());
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  fba::motion::RobotCollision collision{to_flange, fba::motion::urdf_flange_from_palm(urdf, "wrist_camera_arm.urdf", "world")};

  // What the straight motion from a to b touches of `model` (less what the robot stands in at a).
  std::string motion(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const fba::Octree& model) {
    collision.set_model(std::make_shared<const fba::motion::ModelObstacles>(model));
    collision.free_model_at(a, true);
    return fba::motion::motion_collision(a, b, 0.02, [this](const Eigen::VectorXd& q) { return collision.collision(q); });
  }
};

fba::JointState state_of(const fba::arm::ArmModel& arm, const Eigen::VectorXd& q) {
  fba::JointState s;
  s.names = arm.joint_names();
  s.positions.assign(q.data(), q.data() + q.size());
  s.velocities.assign(s.names.size(), 0.0);
  return s;
}

Eigen::VectorXd joints_of(const fba::JointState& s) { return Eigen::Map<const Eigen::VectorXd>(s.positions.data(), static_cast<Eigen::Index>(s.positions.size())); }

// The planner started with the arm at sim.arm's initial joints, then, the arm standing at the last
// initial view, asked for the request on `model`: the initial views' joints, the joints it sends
// next, and the view_chosen or no_view payload.
struct Answer {
  std::vector<Eigen::VectorXd> initial;
  Eigen::VectorXd start;
  std::vector<Eigen::VectorXd> joints;
  nlohmann::json chosen, no_view;
};
Answer ask(Robot& robot, const fba::Octree& model) {
  ComponentHarness h(fba::test::built_plugins(), "grasp.exploration_planner", band_of_views(), {"start", "joint_state"});
  Answer a;
  h.push<fba::JointState>("joint_state", state_of(robot.to_camera, mt::home()));
  h.push<std::int64_t>("start", 0);
  h.run();
  for (const auto& j : h.values<fba::JointState>("joint_target")) a.initial.push_back(joints_of(j));
  if (a.initial.size() != 3u) {
    ADD_FAILURE() << a.initial.size() << " initial views";
    return a;
  }
  a.start = a.initial.back();
  h.push<fba::JointState>("joint_state", state_of(robot.to_camera, a.start));
  h.push<fba::Octree>("octree", model);
  h.push<fba::RegionsOfInterest>("regions", block_plus_x_face());
  h.run();
  EXPECT_EQ(h.values<fba::Pose>("target").size(), 0u) << "a view went out as a pose";
  const auto sent = h.values<fba::JointState>("joint_target");
  for (std::size_t i = a.initial.size(); i < sent.size(); ++i) a.joints.push_back(joints_of(sent[i]));
  if (const auto e = fba::test::find_event(h.events(), "view_chosen")) a.chosen = nlohmann::json::parse(e->payload);
  if (const auto e = fba::test::find_event(h.events(), "no_view")) a.no_view = nlohmann::json::parse(e->payload);
  return a;
}

}  // namespace

TEST(ExplorationPlannerMoves, EveryViewGoesOutAsJointsWhoseMoveIsClear) {
  Robot robot;
  const fba::Octree model = model_of(kObject);
  const Answer a = ask(robot, model);
  // The initial views, chained from where the arm starts, before any model: clear of the arm
  // itself and the table.
  ASSERT_EQ(a.initial.size(), 3u);
  const fba::Octree nothing = model_of([](const Eigen::Vector3d&) { return 1.0; });
  EXPECT_EQ(robot.motion(mt::home(), a.initial[0], nothing), "");
  EXPECT_EQ(robot.motion(a.initial[0], a.initial[1], nothing), "");
  EXPECT_EQ(robot.motion(a.initial[1], a.initial[2], nothing), "");
  // The next: the joints put the camera at the view chosen, and the motion there touches nothing.
  ASSERT_EQ(a.joints.size(), 1u) << a.no_view.dump();
  const Eigen::VectorXd& goal = a.joints[0];
  const Eigen::Isometry3d camera = robot.to_camera.forward(goal);
  const auto& p = a.chosen.at("pose").at("position");
  EXPECT_LT((camera.translation() - Eigen::Vector3d(p[0], p[1], p[2])).norm(), 1e-3) << a.chosen.dump();
  EXPECT_EQ(robot.motion(a.start, goal, model), "");
  EXPECT_EQ(a.chosen.at("reason").get<std::string>().find("passed over"), std::string::npos) << a.chosen.dump();
}

// A block where the wrist passes halfway along the straight motion to the best view, the view
// itself clear of it: the planner passes that view over, says why, and sends one whose motion is
// clear.
TEST(ExplorationPlannerMoves, AViewWhoseMoveCrossesTheModelIsPassedOverForOneThatDoesNot) {
  Robot robot;
  const Answer free = ask(robot, model_of(kObject));
  ASSERT_EQ(free.joints.size(), 1u);
  const int best = free.chosen.at("view").get<int>();
  const Eigen::VectorXd halfway = free.start + 0.5 * (free.joints[0] - free.start);
  const Eigen::Vector3d block = robot.to_flange.forward(halfway).translation();
  const Sdf object_and_block = [b = box_sdf(block, Eigen::Vector3d::Constant(0.03))](const Eigen::Vector3d& x) {
    return std::min(kObject(x), b(x));
  };
  const fba::Octree model = model_of(object_and_block);
  ASSERT_NE(robot.motion(free.start, free.joints[0], model), "") << "the block is not in the way at " << block.transpose();

  const Answer a = ask(robot, model);
  const std::string reason = (a.joints.empty() ? a.no_view : a.chosen).at("reason").get<std::string>();
  EXPECT_NE(reason.find("passed over"), std::string::npos) << reason;
  EXPECT_NE(reason.find("view " + std::to_string(best) + ": the straight motion there: "), std::string::npos) << reason;
  ASSERT_EQ(a.joints.size(), 1u) << reason;
  EXPECT_NE(a.chosen.at("view").get<int>(), best);
  EXPECT_EQ(robot.motion(a.start, a.joints[0], model), "");
}
