// sim.arm through the component harness (its clock is the task's), and in a small task where
// sim.camera renders the YCB mesh from the arm's camera pose.
#include <gtest/gtest.h>

#include <cmath>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <fba/task.hpp>
#include <fba/task_config.hpp>
#include <fba/testing.hpp>
#include <fba/types/frame.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/joint_trajectory.hpp>
#include <fba/types/pose.hpp>

#include "arm_model.hpp"
#ifdef FBA_ARM_COLLISION
#include "fba/motion/robot_collision.hpp"
#endif
#include "support/wrist_camera_arm.hpp"
#include "support/built_plugins.hpp"
#include "support/events.hpp"
#include "support/temp_dir.hpp"
#include "support/data_sets.hpp"
#include "support/joint_trajectories.hpp"

using fba::testing::ComponentHarness;

namespace {

using fba::test::built_plugins;
using fba::test::named;

const std::string kMesh = fba::test::ycb_mesh("YcbMustardBottle");
constexpr std::int64_t kPeriodNs = 20'000'000;  // the default rate, 50 Hz

using fba::test::wrist_camera_arm;

// A camera pose `distance` from the origin at an elevation and azimuth (degrees), looking at the
// origin with the image's x axis horizontal.
fba::Pose looking_at_origin(double elevation, double azimuth, double distance) {
  const double e = elevation * M_PI / 180, a = azimuth * M_PI / 180;
  const Eigen::Vector3d c(distance * std::cos(e) * std::cos(a), distance * std::cos(e) * std::sin(a), distance * std::sin(e));
  const Eigen::Vector3d z = -c.normalized(), x = z.cross(Eigen::Vector3d::UnitZ()).normalized(), y = z.cross(x);
  fba::Pose p;
  p.world_from_frame.linear() << x, y, z;
  p.world_from_frame.translation() = c;
  return p;
}

// One period of the task's clock, and the invocation it triggers.
// A joint target that names one joint.
fba::JointState one_joint(const std::string& name, double position) {
  fba::JointState target;
  target.names = {name};
  target.positions = {position};
  return target;
}

void tick(ComponentHarness& h) {
  h.tick();
  h.run();
}

// Ticks until the arm reports arrival or `max_ticks` pass.
void tick_until_arrived(ComponentHarness& h, int max_ticks = 2000) {
  for (int i = 0; i < max_ticks && named(h.events(), "arrived").empty(); ++i) tick(h);
}

// Where the object is in a rendered frame: the centroid of its bright pixels, and their count.
std::pair<cv::Point2d, double> object_in(const fba::Frame& f) {
  cv::Mat grey;
  cv::cvtColor(f.image, grey, cv::COLOR_BGR2GRAY);
  const cv::Moments m = cv::moments(grey > 60, true);
  return {m.m00 > 0 ? cv::Point2d(m.m10 / m.m00, m.m01 / m.m00) : cv::Point2d(-1, -1), m.m00};
}

}  // namespace

TEST(SimArm, PublishesWhereItStartsAtTheFirstTick) {
  ComponentHarness h(built_plugins(), "sim.arm");
  tick(h);
  const auto states = h.values<fba::JointState>("joint_state");
  ASSERT_EQ(states.size(), 1u);
  EXPECT_EQ(states[0].names, wrist_camera_arm().joint_names());
  EXPECT_NEAR(states[0].positions[1], -2.1223, 1e-12);
  const auto poses = h.values<fba::Pose>("camera_pose");
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_NEAR(poses[0].world_from_frame.translation().norm(), 0.35, 0.005);
  tick(h);
  EXPECT_EQ(h.packets("joint_state").size(), 1u);  // standing still: nothing new to say
}

TEST(SimArm, MovesToACameraPoseInTaskTimeWithinTheVelocityLimitsAndReportsArrival) {
  ComponentHarness h(built_plugins(), "sim.arm", {{"speed_scale", 0.5}}, {"target"});
  tick(h);
  const fba::Pose target = looking_at_origin(45, 90, 0.4);  // from the object's left
  h.push<fba::Pose>("target", target);
  const std::int64_t start = h.now_ns() + kPeriodNs;
  tick_until_arrived(h);
  const auto arrived = named(h.events(), "arrived");
  ASSERT_EQ(arrived.size(), 1u);
  EXPECT_TRUE(named(h.events(), "unreachable").empty());

  // The camera pose where the motion ended is the target.
  const auto poses = h.values<fba::Pose>("camera_pose");
  ASSERT_EQ(poses.size(), 2u);  // the start, then the arrival
  EXPECT_LT((poses[1].world_from_frame.translation() - target.world_from_frame.translation()).norm(), 1e-4);
  EXPECT_LT(fba::arm::angle_between(poses[1].world_from_frame, target.world_from_frame), 1e-3);
  const auto payload = nlohmann::json::parse(arrived[0].payload);
  EXPECT_NEAR(payload["pose"]["position"][1].get<double>(), target.world_from_frame.translation().y(), 1e-4);
  EXPECT_EQ(payload["joints"].size(), 6u);

  // Joint states along the way: one per tick, within half the URDF's velocity limits, ending at rest.
  const auto states = h.values<fba::JointState>("joint_state");
  ASSERT_GT(states.size(), 10u);
  for (std::size_t i = 1; i < states.size(); ++i) {
    EXPECT_GT(states[i].stamp, states[i - 1].stamp);
    for (std::size_t j = 0; j < 6; ++j) EXPECT_LE(std::abs(states[i].velocities[j]), 0.5 * wrist_camera_arm().limits()[j].velocity + 1e-9);
  }
  const auto& last = states.back();
  EXPECT_EQ(Eigen::Map<const Eigen::VectorXd>(last.velocities.data(), 6).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_NEAR(poses[1].stamp, last.stamp, 1e-12);
  EXPECT_GT(last.stamp, static_cast<double>(start) * 1e-9 + 0.1);  // moving took task time
  EXPECT_LE(last.stamp, static_cast<double>(h.now_ns()) * 1e-9);
}

TEST(SimArm, AnUnreachableTargetIsRefusedWithAnEventNamingItAndTheArmStays) {
  ComponentHarness h(built_plugins(), "sim.arm", {}, {"target"});
  tick(h);
  fba::Pose far;
  far.world_from_frame.translation() << 2.0, 0.0, 0.5;
  h.push<fba::Pose>("target", far);
  tick(h);
  const auto refused = named(h.events(), "unreachable");
  ASSERT_EQ(refused.size(), 1u);
  const auto payload = nlohmann::json::parse(refused[0].payload);
  EXPECT_EQ(payload["target"]["pose"]["position"][0].get<double>(), 2.0);
  EXPECT_NE(payload["reason"].get<std::string>().find("no joint positions reach it"), std::string::npos) << refused[0].payload;
  EXPECT_EQ(h.packets("camera_pose").size(), 1u);  // only where it started
  EXPECT_TRUE(named(h.events(), "arrived").empty());
}

TEST(SimArm, AJointTargetOutsideTheLimitsIsRefusedNamingTheJoint) {
  ComponentHarness h(built_plugins(), "sim.arm", {}, {"joint_target"});
  h.push<fba::JointState>("joint_target", one_joint("elbow_joint", 4.0));
  tick(h);
  const auto refused = named(h.events(), "unreachable");
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_NE(refused[0].payload.find("joint 'elbow_joint' at 4 rad is outside [-3.14159, 3.14159]"), std::string::npos)
      << refused[0].payload;

  h.push<fba::JointState>("joint_target", one_joint("knee", 0.0));
  tick(h);
  ASSERT_EQ(named(h.events(), "unreachable").size(), 2u);
  EXPECT_NE(named(h.events(), "unreachable")[1].payload.find("no joint 'knee'"), std::string::npos);
}

TEST(SimArm, AJointTargetByNameMovesOnlyThatJoint) {
  ComponentHarness h(built_plugins(), "sim.arm", {}, {"joint_target"});
  h.push<fba::JointState>("joint_target", one_joint("wrist_3_joint", 1.0));
  tick_until_arrived(h);
  ASSERT_EQ(named(h.events(), "arrived").size(), 1u);
  const auto last = h.values<fba::JointState>("joint_state").back();
  EXPECT_EQ(last.positions[5], 1.0);
  EXPECT_EQ(last.positions[0], -0.4148);
}

// A target that arrives during a motion waits for it to end; the arm never jumps.
TEST(SimArm, ATargetDuringAMotionStartsWhenTheMotionEnds) {
  ComponentHarness h(built_plugins(), "sim.arm", {}, {"target"});
  h.push<fba::Pose>("target", looking_at_origin(45, 90, 0.4));
  tick(h);
  tick(h);
  h.push<fba::Pose>("target", looking_at_origin(60, -90, 0.35));
  for (int i = 0; i < 4000 && named(h.events(), "arrived").size() < 2; ++i) tick(h);
  ASSERT_EQ(named(h.events(), "arrived").size(), 2u);
  const auto states = h.values<fba::JointState>("joint_state");
  for (std::size_t i = 1; i < states.size(); ++i) {
    const double dt = states[i].stamp - states[i - 1].stamp;
    for (std::size_t j = 0; j < 6; ++j)  // no step larger than the speed allows
      EXPECT_LE(std::abs(states[i].positions[j] - states[i - 1].positions[j]), 0.5 * wrist_camera_arm().limits()[j].velocity * dt + 1e-9);
  }
}

// A planner asks for several views at once: every target is reached, in the order it came (the
// exploration loop waits for each view; one dropped would stall it).
TEST(SimArm, TargetsThatComeTogetherAreAllReachedInOrder) {
  ComponentHarness h(built_plugins(), "sim.arm", {}, {"target"});
  h.push<fba::Pose>("target", looking_at_origin(45, 90, 0.4));
  tick(h);
  h.push<fba::Pose>("target", looking_at_origin(60, -90, 0.35));
  tick(h);
  h.push<fba::Pose>("target", looking_at_origin(50, 0, 0.35));
  for (int i = 0; i < 8000 && named(h.events(), "arrived").size() < 3; ++i) tick(h);
  const auto poses = h.values<fba::Pose>("camera_pose");
  ASSERT_EQ(named(h.events(), "arrived").size(), 3u);
  ASSERT_GE(poses.size(), 3u);
  const auto last3 = std::vector<fba::Pose>(poses.end() - 3, poses.end());
  const fba::Pose wanted[3] = {looking_at_origin(45, 90, 0.4), looking_at_origin(60, -90, 0.35), looking_at_origin(50, 0, 0.35)};
  for (int i = 0; i < 3; ++i)
    EXPECT_LT((last3[i].world_from_frame.translation() - wanted[i].world_from_frame.translation()).norm(), 0.005) << i;
}

// No tick comes after the end of the stream: the motion under way runs to its end, stamped in task time.
TEST(SimArm, AtTheEndOfTheStreamTheMotionUnderWayIsCompleted) {
  ComponentHarness h(built_plugins(), "sim.arm", {}, {"target"});
  h.push<fba::Pose>("target", looking_at_origin(45, 90, 0.4));
  tick(h);
  h.close("target");
  h.run();
  ASSERT_EQ(named(h.events(), "arrived").size(), 1u);
  const auto states = h.values<fba::JointState>("joint_state");
  ASSERT_GT(states.size(), 10u);
  for (std::size_t i = 2; i + 1 < states.size(); ++i) EXPECT_NEAR(states[i].stamp - states[i - 1].stamp, 0.02, 1e-9);
  EXPECT_TRUE(h.finished());
}

TEST(SimArm, SafeStateStopsTheMotionAndDropsWhatWasPending) {
  ComponentHarness h(built_plugins(), "sim.arm", {}, {"target"});
  h.push<fba::Pose>("target", looking_at_origin(45, 90, 0.4));
  tick(h);
  tick(h);
  h.safe_state();
  const std::size_t published = h.packets("joint_state").size();
  for (int i = 0; i < 200; ++i) tick(h);
  EXPECT_EQ(h.packets("joint_state").size(), published);
  EXPECT_TRUE(named(h.events(), "arrived").empty());
}

TEST(SimArm, AMissingCameraLinkIsAClearConfigurationError) {
  try {
    ComponentHarness h(built_plugins(), "sim.arm", {{"camera_link", "gripper"}});
    FAIL() << "accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("no link 'gripper' in "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("wrist_camera_arm.urdf; links: "), std::string::npos) << e.what();
  }
}

TEST(SimArm, InitialJointsOfTheWrongCountOrOutsideTheLimitsAreRefused) {
  for (const auto& [joints, expected] :
       std::vector<std::pair<std::vector<double>, std::string>>{{{0, 0, 0}, "has 3 positions; the arm from 'world' to 'camera' has 6"},
                                                                {{0, -1, 3.5, 0, 0, 0}, "joint 'elbow_joint' at 3.5 rad"}}) {
    try {
      ComponentHarness h(built_plugins(), "sim.arm", {{"initial_joints", joints}});
      ADD_FAILURE() << "accepted " << expected;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
}

// The arm moves the camera; sim.camera renders from the arm's camera pose: the object is in the
// middle of the picture wherever the arm has taken the camera to look at it.
TEST(SimArm, SimCameraRendersTheMeshFromWhereTheArmTookIt) {
  ComponentHarness arm_h(built_plugins(), "sim.arm", {}, {"target"});
  ComponentHarness camera(built_plugins(), "sim.camera", {{"mesh", kMesh}}, {"pose"});
  arm_h.push<fba::Pose>("target", looking_at_origin(30, 90, 0.45));
  tick_until_arrived(arm_h);
  for (const auto& p : arm_h.packets("camera_pose")) camera.push_packet("pose", p);
  camera.run();
  const auto frames = camera.values<fba::Frame>("frame");
  ASSERT_EQ(frames.size(), 2u);  // from where the arm started, and where it arrived
  for (const auto& f : frames) {
    const auto [centre, pixels] = object_in(f);
    EXPECT_GT(pixels, 3000);
    EXPECT_LT(std::abs(centre.x - 320), 60) << centre;
    EXPECT_LT(std::abs(centre.y - 240), 60) << centre;
  }
  const Eigen::Vector3d seen_from = frames[1].camera.centre_in_world();
  EXPECT_LT((seen_from - looking_at_origin(30, 90, 0.45).world_from_frame.translation()).norm(), 1e-4);
}

TEST(SimArm, InATaskTheCameraSeesTheObjectFromTheArmsStartingPose) {
  fba::test::TempDir dir;
  const std::string yaml = "task: arm_camera\nexecutor: deterministic\ncomponents:\n"
                           "  arm: { type: sim.arm }\n"
                           "  camera: { type: sim.camera, params: { mesh: " + kMesh + " } }\n"
                           "  sink: { type: examples.sink, params: { expected: 1 } }\n"
                           "connections:\n  - arm.camera_pose -> camera.pose\n  - camera.frame -> sink.in\n"
                           "on:\n  sink.done: stop_success\n";
  fba::Task task(fba::load_task_text(yaml, "arm_camera.yaml", dir.path(), built_plugins()));
  const auto& frames = task.tap("camera.frame");
  const auto result = task.run();
  EXPECT_EQ(result.outcome, fba::Outcome::Success) << result.reason;
  ASSERT_EQ(frames.size(), 1u);
  const auto& f = frames[0].get<fba::Frame>();
  const auto [centre, pixels] = object_in(f);
  EXPECT_GT(pixels, 3000);
  EXPECT_LT(std::abs(centre.x - 320), 60) << centre;
  EXPECT_LT(std::abs(centre.y - 240), 60) << centre;
  Eigen::VectorXd home(6);
  home << -0.4148, -2.1223, 2.2888, -2.2234, -1.3679, -0.3644;
  EXPECT_LT((f.camera.centre_in_world() - wrist_camera_arm().forward(home).translation()).norm(), 1e-9);
  bool arm_safe = false;  // the arm is an actuator: told to go safe at the end
  for (const auto& s : result.safe_states) arm_safe |= s.component == "arm" && s.status == "reached";
  EXPECT_TRUE(arm_safe);
}

namespace {

// sim.arm's default initial joints (its parameter initial_joints).
const std::vector<double> kInitialJoints{-0.4148, -2.1223, 2.2888, -2.2234, -1.3679, -0.3644};

}  // namespace

// A reach plan's trajectory: followed on the task's clock from when it arrives, joint states along
// it where the trajectory says, and 'arrived' at its end, at its last waypoint.
TEST(SimArm, FollowsATrajectoryOnTheTasksClockAndArrivesAtItsEnd) {
  ComponentHarness h(built_plugins(), "sim.arm", {}, {"trajectory"});
  tick(h);
  std::vector<double> goal = kInitialJoints;
  for (double& q : goal) q += 0.2;
  const auto trajectory =
      fba::test::straight_trajectory(wrist_camera_arm().joint_names(), kInitialJoints, goal, 1.0, 0.02, 0.2);
  h.push("trajectory", trajectory);
  tick(h);
  const std::int64_t start = h.now_ns();
  tick_until_arrived(h);
  ASSERT_EQ(named(h.events(), "arrived").size(), 1u);
  EXPECT_TRUE(named(h.events(), "unreachable").empty());
  const auto states = h.values<fba::JointState>("joint_state");
  std::size_t along = 0;
  for (const auto& p : h.packets("joint_state")) {
    const auto& js = p.get<fba::JointState>();
    if (p.header().stamp_ns < start) continue;
    ++along;
    const double t = static_cast<double>(p.header().stamp_ns - start) * 1e-9;
    // Where the trajectory is at t: between its waypoints, on the straight line.
    const std::size_t k = std::min<std::size_t>(static_cast<std::size_t>(t / 0.02), trajectory.points.size() - 2);
    const double share = std::clamp((t - trajectory.points[k].time) / 0.02, 0.0, 1.0);
    for (std::size_t j = 0; j < 6; ++j) {
      const double expected =
          trajectory.points[k].positions[j] + share * (trajectory.points[k + 1].positions[j] - trajectory.points[k].positions[j]);
      EXPECT_NEAR(js.positions[j], expected, 1e-9) << "at " << t << " s, joint " << j;
    }
  }
  EXPECT_GE(along, 60u);  // 1.2 s at 50 Hz
  const auto arrived = named(h.events(), "arrived");
  const auto joints = nlohmann::json::parse(arrived[0].payload)["joints"].get<std::vector<double>>();
  for (std::size_t j = 0; j < 6; ++j) EXPECT_NEAR(joints[j], goal[j], 1e-12);
  EXPECT_EQ(states.back().stamp, static_cast<double>(start + 1'200'000'000) * 1e-9);
}

TEST(SimArm, ATrajectoryThatDoesNotFitTheArmOrComesWhileItMovesIsRefused) {
  ComponentHarness h(built_plugins(), "sim.arm", {}, {"trajectory", "joint_target"});
  tick(h);
  const auto names = wrist_camera_arm().joint_names();
  std::vector<double> goal = kInitialJoints;
  goal[0] += 0.3;
  std::vector<double> elsewhere = kInitialJoints;
  elsewhere[4] += 0.1;
  h.push("trajectory", fba::test::straight_trajectory(names, elsewhere, goal, 1.0));
  tick(h);
  auto wrong = names;
  std::swap(wrong[0], wrong[1]);  // the same joints in another order: fine, each by name
  wrong[5] = "tool_joint";
  h.push("trajectory", fba::test::straight_trajectory(wrong, kInitialJoints, goal, 1.0));
  tick(h);
  h.push("joint_target", fba::JointState{{"wrist_3_joint"}, {0.5}, {}, 0});
  tick(h);
  h.push("trajectory", fba::test::straight_trajectory(names, kInitialJoints, goal, 1.0));
  tick(h);
  const auto refused = named(h.events(), "unreachable");
  ASSERT_EQ(refused.size(), 3u);
  EXPECT_NE(refused[0].payload.find("the trajectory starts with joint 'wrist_2_joint' at"), std::string::npos) << refused[0].payload;
  EXPECT_NE(refused[1].payload.find("joint 'tool_joint' is not one of the arm's"), std::string::npos) << refused[1].payload;
  EXPECT_NE(refused[2].payload.find("the arm is moving"), std::string::npos) << refused[2].payload;
  tick_until_arrived(h);
  EXPECT_EQ(named(h.events(), "arrived").size(), 1u);  // the joint target's move only
}

#ifdef FBA_ARM_COLLISION
// Where the exploration looks from (a band of views around the object, as tasks/grasp.yaml's
// planner places them), the arm takes a pose in which neither it, nor its camera, nor the hand on
// its flange touches the arm itself or the table; without the check, the nearest IK solution puts
// the hand into the forearm at some of those views.
TEST(SimArm, ReachesEveryViewWithTheRobotClearOfItselfAndTheTable) {
  const std::string urdf = fba::test::wrist_camera_arm_urdf();
  const fba::arm::ArmModel to_flange(urdf, "world", "flange");
  fba::motion::RobotCollision robot(to_flange, fba::motion::urdf_flange_from_palm(fba::test::wrist_camera_arm_text(), urdf, "world"));
  const Eigen::Vector3d centre(0, 0, 0.05);
  int reached_clear = 0, colliding_without = 0;
  for (bool check : {true, false}) {
    ComponentHarness h(built_plugins(), "sim.arm", {{"collision_check", check}}, {"target"});
    tick(h);
    for (double elevation : {20.0, 45.0, 70.0})
      for (double azimuth = 0; azimuth < 360; azimuth += 30) {
        fba::Pose view = looking_at_origin(elevation, azimuth, 0.3);
        view.world_from_frame.translation() += centre;
        const auto answers = [&] { return named(h.events(), "arrived").size() + named(h.events(), "unreachable").size(); };
        const std::size_t before = answers(), arrived_before = named(h.events(), "arrived").size();
        h.push<fba::Pose>("target", view);
        for (int i = 0; i < 2000 && answers() == before; ++i) tick(h);
        const auto arrived = named(h.events(), "arrived");
        if (arrived.size() == arrived_before) continue;  // unreachable: the band's far side is beyond the arm
        const auto joints = nlohmann::json::parse(arrived.back().payload)["joints"].get<std::vector<double>>();
        const std::string hit = robot.collision(Eigen::Map<const Eigen::VectorXd>(joints.data(), 6));
        if (check) {
          EXPECT_EQ(hit, "") << "view at elevation " << elevation << ", azimuth " << azimuth;
          ++reached_clear;
        } else if (!hit.empty()) {
          ++colliding_without;
        }
      }
  }
  EXPECT_GT(reached_clear, 18);      // most of the band is reached, and clear
  EXPECT_GT(colliding_without, 0);   // the check is what keeps them clear
}
#endif
