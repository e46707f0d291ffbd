// hw.canopen_arm through the component harness against the CANopen arm emulator, which plays six
// CiA 402 drives behind an SLCAN adapter on a pseudo-terminal: the component opens the terminal by
// its path, as it would /dev/ttyUSB0, so the real serial code runs. The harness clock is the
// task's; the drives move in real time, so the tests tick until something happens (with a bound on
// the ticks that only catches a hang, never a slow machine).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <thread>

#include <nlohmann/json.hpp>

#include <fba/can/pty.hpp>
#include <fba/can/slcan_adapter.hpp>
#include <fba/emulators/canopen_arm.hpp>
#include <fba/task.hpp>
#include <fba/task_config.hpp>
#include <fba/testing.hpp>
#include <fba/component.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/joint_trajectory.hpp>
#include <fba/types/pose.hpp>

#include "arm_model.hpp"
#include "support/wrist_camera_arm.hpp"
#include "support/built_plugins.hpp"
#include "support/events.hpp"
#include "support/canopen_frames.hpp"
#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"
#include "support/contains.hpp"
#include "support/emulated_canopen_arm.hpp"
#include "support/joint_trajectories.hpp"

using fba::testing::ComponentHarness;
using namespace std::chrono_literals;

namespace {

constexpr double kCounts = 100'000;  // drive units per radian

using fba::test::built_plugins;

using fba::test::wrist_camera_arm;

using fba::test::contains;
using fba::test::named;

using Emulator = fba::test::EmulatedCanopenArm;

// The arm's six joints on the emulator at `device`, with `more` added or replacing. Generous
// timeouts: the emulator's thread may wait for a core on a loaded machine, and a timeout is not
// what these tests are about (except where one sets its own).
fba::testing::Params arm_params(const std::string& device, const fba::testing::Params& more) {
  fba::testing::Params p{{"device", device},
                         {"node_ids", std::vector<double>{1, 2, 3, 4, 5, 6}},
                         {"counts_per_rad", std::vector<double>(6, kCounts)},
                         {"heartbeat_period_ms", 20},
                         {"heartbeat_timeout_ms", 1000},
                         {"sdo_timeout_ms", 1000}};
  for (const auto& [k, v] : more) p[k] = v;
  return p;
}

class CanopenArmComponent : public ::testing::Test {
 protected:
  fba::testing::Params params(fba::testing::Params more = {}) {
    more.try_emplace("speed_scale", 1.0);
    return arm_params(emulator_.device(), more);
  }
  void make(fba::testing::Params more = {}) {
    harness_.emplace(built_plugins(), "hw.canopen_arm", params(std::move(more)),
                     std::vector<std::string>{"target", "joint_target", "trajectory"});
  }
  ComponentHarness& h() { return *harness_; }
  // One period of the task's clock and its invocation; the drives get a millisecond to move.
  void tick() {
    h().tick();
    h().run();
    std::this_thread::sleep_for(1ms);
  }
  // Ticks until `done` or the component fails; the bound only catches a hang.
  template <class F>
  void tick_until(F done) {
    for (int i = 0; i < 100'000 && !done() && h().failure().empty(); ++i) tick();
  }
  void tick_until_arrived(std::size_t n = 1) {
    tick_until([&] { return named(h().events(), "arrived").size() >= n; });
  }
  void tick_until_failed() {
    tick_until([] { return false; });
  }
  // A long move of every joint (about 5 s at speed_scale 0.2), so that a fault comes in the middle of it.
  void start_long_move() {
    h().push("joint_target", fba::JointState{{}, {3, -3, 3, -3, 3, -3}, {}, 0});
    tick();
    tick_until([&] { return std::abs(emulator_->position(1)) > 0.05 * kCounts; });
    ASSERT_TRUE(h().failure().empty()) << h().failure();
    ASSERT_TRUE(named(h().events(), "arrived").empty());
  }

  Emulator emulator_;  // before the harness: the component's line goes first
  std::optional<ComponentHarness> harness_;
};

fba::Pose pose_of(const std::vector<double>& joints) {
  fba::Pose p;
  p.world_from_frame = wrist_camera_arm().forward(Eigen::Map<const Eigen::VectorXd>(joints.data(), 6));
  return p;
}

}  // namespace

TEST(CanopenArmSpec, HasExactlyTheInputsOutputsAndEventsOfSimArm) {
  const auto real = built_plugins().find("hw.canopen_arm"), sim = built_plugins().find("sim.arm");
  ASSERT_TRUE(real && sim);
  const fba::Spec &a = real->spec, &b = sim->spec;
  EXPECT_EQ(a.kind(), b.kind());
  auto same_ports = [](const std::vector<fba::PortSpec>& x, const std::vector<fba::PortSpec>& y) {
    ASSERT_EQ(x.size(), y.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      EXPECT_EQ(x[i].name, y[i].name);
      EXPECT_EQ(x[i].type, y[i].type) << x[i].name;
      EXPECT_EQ(x[i].required, y[i].required) << x[i].name;
      EXPECT_EQ(x[i].same_as, y[i].same_as) << x[i].name;
      EXPECT_EQ(x[i].doc, y[i].doc) << x[i].name;
    }
  };
  same_ports(a.inputs(), b.inputs());
  same_ports(a.outputs(), b.outputs());
  ASSERT_EQ(a.events().size(), b.events().size());
  for (std::size_t i = 0; i < a.events().size(); ++i) {
    EXPECT_EQ(a.events()[i].name, b.events()[i].name);
    EXPECT_EQ(a.events()[i].doc, b.events()[i].doc);
  }
  EXPECT_EQ(a.inputs().size(), 3u);  // target, joint_target, trajectory: the comparison compared something
  EXPECT_EQ(a.events().size(), 2u);  // arrived, unreachable
}

TEST_F(CanopenArmComponent, EnablesEveryDriveAndPublishesWhereItStands) {
  make();
  tick();
  ASSERT_TRUE(h().failure().empty()) << h().failure();
  for (int node = 1; node <= 6; ++node) EXPECT_TRUE(emulator_.enabled(node)) << "node " << node;
  const auto states = h().values<fba::JointState>("joint_state");
  ASSERT_EQ(states.size(), 1u);
  EXPECT_EQ(states[0].names, wrist_camera_arm().joint_names());
  EXPECT_EQ(states[0].positions, std::vector<double>(6, 0.0));  // the emulator's drives start at 0
  ASSERT_EQ(h().values<fba::Pose>("camera_pose").size(), 1u);
  EXPECT_TRUE(h().values<fba::Pose>("camera_pose")[0].world_from_frame.isApprox(
      pose_of(std::vector<double>(6, 0.0)).world_from_frame));
}

TEST_F(CanopenArmComponent, MovesToAReachableCameraPoseAndArrivesWithTheJointStatesMatching) {
  make({{"speed_scale", 0.3}});  // a move of a second or two: several joint states on the way
  tick();
  const fba::Pose target = pose_of({0.3, -0.5, 0.6, -0.4, 0.5, 0.2});
  h().push("target", target);
  tick_until_arrived();
  ASSERT_TRUE(h().failure().empty()) << h().failure();
  ASSERT_EQ(named(h().events(), "arrived").size(), 1u);
  EXPECT_TRUE(named(h().events(), "unreachable").empty());

  const auto states = h().values<fba::JointState>("joint_state");
  ASSERT_GT(states.size(), 2u) << "joint states while moving, not only at the ends";
  const auto& last = states.back();
  // The last state is the drives' actual positions, and the arrival's joints are the same.
  for (int node = 1; node <= 6; ++node)
    EXPECT_NEAR(last.positions[node - 1], emulator_->position(node) / kCounts, 1e-9) << "node " << node;
  const auto arrived = nlohmann::json::parse(named(h().events(), "arrived")[0].payload);
  EXPECT_EQ(arrived["joints"].get<std::vector<double>>(), last.positions);
  // Where the camera is: the target, within IK's tolerance and the encoders' resolution.
  const auto poses = h().values<fba::Pose>("camera_pose");
  ASSERT_EQ(poses.size(), 2u);  // where it started, where it arrived
  EXPECT_LT((poses[1].world_from_frame.translation() - target.world_from_frame.translation()).norm(), 1e-3);
  EXPECT_LT(fba::arm::angle_between(poses[1].world_from_frame, target.world_from_frame), 1e-2);
  EXPECT_TRUE(poses[1].world_from_frame.isApprox(pose_of(last.positions).world_from_frame, 1e-9));
  // Synchronised: in every state along the way, the joints that move far have covered the same
  // share of their distance (the drives sample their positions on the same SYNC).
  for (std::size_t k = 1; k + 1 < states.size(); ++k) {
    std::optional<double> share;
    for (std::size_t j = 0; j < 6; ++j) {
      if (std::abs(last.positions[j]) < 0.05) continue;
      const double s = states[k].positions[j] / last.positions[j];  // every joint started at 0
      EXPECT_GE(s, -1e-9) << "state " << k << ", joint " << j;
      EXPECT_LE(s, 1 + 1e-9) << "state " << k << ", joint " << j;
      if (share)
        EXPECT_NEAR(s, *share, 0.02) << "state " << k << ", joint " << j;
      else
        share = s;
    }
  }
}

TEST_F(CanopenArmComponent, AJointTargetOutsideTheLimitsIsRefusedBeforeAnyFrameIsSent) {
  make();
  tick();
  std::vector<std::uint64_t> before;
  for (int node = 1; node <= 6; ++node) before.push_back(emulator_->sdo_downloads(node));
  h().push("joint_target", fba::JointState{{"elbow_joint"}, {3.5}, {}, 0});
  tick();
  for (int i = 0; i < 5; ++i) tick();
  ASSERT_TRUE(h().failure().empty()) << h().failure();
  const auto refused = named(h().events(), "unreachable");
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_TRUE(contains(refused[0].payload, "joint 'elbow_joint' at 3.5 rad is outside [-3.14159, 3.14159]"))
      << refused[0].payload;
  for (int node = 1; node <= 6; ++node) {
    EXPECT_EQ(emulator_->sdo_downloads(node), before[node - 1]) << "node " << node << " was sent a command";
    EXPECT_EQ(emulator_->position(node), 0) << "node " << node;
  }
  // An unreachable pose too, and the arm still takes the next good target.
  fba::Pose far = pose_of(std::vector<double>(6, 0.0));
  far.world_from_frame.translation() = Eigen::Vector3d(5, 0, 0);
  h().push("target", far);
  h().push("joint_target", fba::JointState{{"elbow_joint"}, {0.5}, {}, 0});
  tick_until_arrived();
  EXPECT_EQ(named(h().events(), "unreachable").size(), 2u);
  EXPECT_EQ(emulator_->position(3), std::lround(0.5 * kCounts));
}

TEST_F(CanopenArmComponent, AnEmcyFromADriveStopsEveryJointAndTheTaskNamingTheJointAndTheCode) {
  make({{"speed_scale", 0.2}});
  tick();
  start_long_move();
  emulator_->inject_fault(4, 0x2310);
  tick_until_failed();
  const std::string why = h().failure();
  EXPECT_TRUE(contains(why, emulator_.device())) << why;
  EXPECT_TRUE(contains(why, "joint 'wrist_1_joint'")) << why;
  EXPECT_TRUE(contains(why, "node 4")) << why;
  EXPECT_TRUE(contains(why, "EMCY 0x2310 (continuous over-current)")) << why;
  EXPECT_TRUE(contains(why, "every joint was sent quick stop")) << why;
  for (int node : {1, 2, 3, 5, 6}) EXPECT_TRUE(emulator_.quick_stopped(node)) << "node " << node;
}

TEST_F(CanopenArmComponent, ADriveThatStopsAnsweringStopsEveryOtherJointNamingIt) {
  make({{"speed_scale", 0.2}, {"heartbeat_timeout_ms", 400}, {"sdo_timeout_ms", 2000}});
  tick();
  start_long_move();
  emulator_->silence(2);
  tick_until_failed();
  const std::string why = h().failure();
  EXPECT_TRUE(contains(why, "joint 'shoulder_lift_joint'")) << why;
  EXPECT_TRUE(contains(why, "node 2: heartbeat lost")) << why;
  EXPECT_TRUE(contains(why, "quick stop failed on 1 of 6 joints")) << why;  // node 2 cannot hear it
  for (int node : {1, 3, 4, 5, 6}) EXPECT_TRUE(emulator_.quick_stopped(node)) << "node " << node;
}

TEST_F(CanopenArmComponent, ADriveRebootingMidMotionStopsTheArmNamingIt) {
  make({{"speed_scale", 0.2}});
  tick();
  start_long_move();
  emulator_->reboot(5);  // a power glitch: its configuration is gone, it is pre-operational again
  tick_until_failed();
  const std::string why = h().failure();
  EXPECT_TRUE(contains(why, "joint 'wrist_2_joint': node 5: rebooted unasked")) << why;
  for (int node : {1, 2, 3, 4, 6}) EXPECT_TRUE(emulator_.quick_stopped(node)) << "node " << node;
}

// No tick comes after the end of the stream: the move under way and those waiting run to their end.
TEST_F(CanopenArmComponent, AtTheEndOfTheStreamTheMovesUnderWayAndPendingAreCompleted) {
  make();
  tick();
  h().push("joint_target", fba::JointState{{"wrist_3_joint"}, {0.3}, {}, 0});
  tick();
  h().push("joint_target", fba::JointState{{"wrist_3_joint"}, {-0.2}, {}, 0});
  tick();  // taken in: it waits for the first move's end
  h().close("joint_target");
  h().close("target");
  h().close("trajectory");
  h().run();
  EXPECT_TRUE(h().failure().empty()) << h().failure();
  EXPECT_EQ(named(h().events(), "arrived").size(), 2u);
  EXPECT_EQ(emulator_->position(6), std::lround(-0.2 * kCounts));
  EXPECT_TRUE(h().finished());
}

TEST_F(CanopenArmComponent, TheSerialLineVanishingMidMotionEndsWithAClearReportNeverAHang) {
  make({{"speed_scale", 0.2}});
  tick();
  start_long_move();
  emulator_->disconnect();
  tick_until_failed();
  const std::string why = h().failure();
  EXPECT_TRUE(contains(why, emulator_.device())) << why;
  EXPECT_TRUE(contains(why, "quick stop failed on 6 of 6 joints")) << why;
  // The safe state cannot be reached on a dead line: said, not hung.
  try {
    h().safe_state();
    FAIL() << "a quick stop went out on a closed line";
  } catch (const std::exception& e) {
    EXPECT_TRUE(contains(e.what(), "quick stop failed on 6 of 6 joints")) << e.what();
  }
}

TEST_F(CanopenArmComponent, LineNoiseIsToleratedWhileItStaysBelowTheLimit) {
  make();
  tick();
  h().push("joint_target", fba::JointState{{}, {0.4, -0.3, 0.2, -0.1, 0.3, 0.5}, {}, 0});
  tick();
  emulator_->inject_garbage();
  tick_until_arrived();
  ASSERT_TRUE(h().failure().empty()) << h().failure();
  for (int node = 1; node <= 6; ++node) EXPECT_TRUE(emulator_.enabled(node)) << "node " << node;
  EXPECT_EQ(emulator_->position(6), std::lround(0.5 * kCounts));
}

TEST_F(CanopenArmComponent, PersistentLineNoiseStopsTheArm) {
  make({{"speed_scale", 0.2}, {"noise_limit", 10}});
  tick();
  start_long_move();
  for (int i = 0; i < 5; ++i) emulator_->inject_garbage();  // 8 bad lines each, within the second
  tick_until_failed();
  const std::string why = h().failure();
  EXPECT_TRUE(contains(why, "the line is too noisy to trust")) << why;
  EXPECT_TRUE(contains(why, "noise_limit 10")) << why;
  EXPECT_TRUE(contains(why, "every joint was sent quick stop")) << why;
  for (int node = 1; node <= 6; ++node) EXPECT_TRUE(emulator_.quick_stopped(node)) << "node " << node;
}

TEST_F(CanopenArmComponent, SafeStateQuickStopsEveryJointMidMotion) {
  make({{"speed_scale", 0.2}});
  tick();
  start_long_move();
  h().interrupt();  // as the runtime does at a stop: the driver's waits end, it sends nothing more
  tick();
  EXPECT_TRUE(h().failure().empty()) << h().failure();
  h().safe_state();
  for (int node = 1; node <= 6; ++node) EXPECT_TRUE(emulator_.quick_stopped(node)) << "node " << node;
}

// hw.canopen_arm declares concurrent_safe_state(): the runtime calls safe_state() beside a call
// still running. The quick stop goes out while end_of_stream() is still following a long move (no
// interrupt() first), the drives stop short of their targets, and that call then ends.
TEST_F(CanopenArmComponent, SafeStateQuickStopsEveryJointWhileAnotherCallIsStillFollowingAMove) {
  make({{"speed_scale", 0.01}});  // a move of about 30 s
  tick();
  h().push("joint_target", fba::JointState{{}, {1, -1, 1, -1, 1, -1}, {}, 0});
  tick();
  h().close("joint_target");
  h().close("target");
  h().close("trajectory");
  const auto syncs = emulator_->syncs_seen();
  std::atomic<bool> returned{false};
  std::jthread follow([&] {
    h().run();  // end_of_stream(): follows the move to its end
    returned = true;
  });
  // It samples the drives on every tick of the move: the call is under way.
  while (emulator_->syncs_seen() < syncs + 2 && !returned) std::this_thread::sleep_for(1ms);
  ASSERT_FALSE(returned) << h().failure();
  EXPECT_NO_THROW(h().safe_state());
  for (int node = 1; node <= 6; ++node) {
    EXPECT_TRUE(emulator_.quick_stopped(node)) << "node " << node;
    EXPECT_LT(std::abs(emulator_->position(node)), kCounts) << "node " << node << " finished its move first";
  }
  follow.join();  // the safe state ended the call too
  EXPECT_TRUE(named(h().events(), "arrived").empty());
}

// One drive gone quiet: every other drive is sent its quick stop before any answer is awaited, and
// the safe state fails after one SDO timeout, naming the drive that did not confirm.
TEST_F(CanopenArmComponent, ASilentDriveFailsTheSafeStateNamingItAfterEveryOtherDriveWasQuickStopped) {
  make({{"speed_scale", 0.2}});
  tick();
  start_long_move();
  emulator_->silence(2);
  while (!emulator_->silent(2)) std::this_thread::sleep_for(1ms);
  std::string why;
  try {
    h().safe_state();
  } catch (const std::exception& e) {
    why = e.what();
  }
  EXPECT_TRUE(contains(why, emulator_.device())) << why;
  EXPECT_TRUE(contains(why, "quick stop failed on 1 of 6 joints")) << why;
  EXPECT_TRUE(contains(why, "joint 'shoulder_lift_joint' (node 2): node 2: no answer")) << why;
  EXPECT_TRUE(contains(why, "the other 5 confirmed")) << why;
  for (int node : {1, 3, 4, 5, 6}) EXPECT_TRUE(emulator_.quick_stopped(node)) << "node " << node;
  fba::test::expect_quick_stops_before_giving_up(*emulator_, 2);
}

TEST_F(CanopenArmComponent, AConfigurationThatDoesNotFitTheArmIsRefusedNamingTheParameter) {
  try {
    make({{"node_ids", std::vector<double>{1, 2, 3}}});
    FAIL() << "three node ids for six joints";
  } catch (const std::exception& e) {
    EXPECT_TRUE(contains(e.what(), "parameter 'node_ids' has 3 values")) << e.what();
    EXPECT_TRUE(contains(e.what(), "has 6 joints")) << e.what();
  }
  try {
    make({{"device", std::string("/dev/ttyUSB0")}});
    FAIL() << "a device without slcan:";
  } catch (const std::exception& e) {
    EXPECT_TRUE(contains(e.what(), "is neither slcan:DEVICE")) << e.what();
  }
  try {
    make({{"rate", 0.5}});  // a tick every 2 s, a heartbeat timeout of 1 s
    FAIL() << "ticks further apart than the heartbeat timeout";
  } catch (const std::exception& e) {
    EXPECT_TRUE(contains(e.what(), "is not shorter than heartbeat_timeout_ms 1000")) << e.what();
  }
  try {
    make({{"bitrate", 300000}});
    FAIL() << "a bitrate SLCAN does not have";
  } catch (const std::exception& e) {
    EXPECT_TRUE(contains(e.what(), "bitrate")) << e.what();
  }
}

// In a task under the threaded executor: the runtime's own threads call process(), interrupt()
// and safe_state().
class CanopenArmInATask : public ::testing::Test {
 protected:
  fba::TaskConfig task(const std::string& extra = "") {
    const std::string yaml =
        "task: real_arm\nexecutor: threaded\ncomponents:\n"
        "  arm:\n    type: hw.canopen_arm\n    params:\n"
        "      device: " +
        emulator_.device() +
        "\n"
        "      node_ids: [1, 2, 3, 4, 5, 6]\n"
        "      counts_per_rad: [100000, 100000, 100000, 100000, 100000, 100000]\n"
        "      heartbeat_period_ms: 20\n      heartbeat_timeout_ms: 1000\n"
        "      sdo_timeout_ms: 1000\n" +
        extra;
    return fba::load_task_text(yaml, "real_arm.yaml", dir_.path(), built_plugins());
  }
  void wait_until_enabled() {
    for (int i = 0; i < 100'000 && !(emulator_.enabled(1) && emulator_.enabled(6)); ++i)
      std::this_thread::sleep_for(1ms);
  }

  fba::test::TempDir dir_;
  Emulator emulator_;
};

TEST_F(CanopenArmInATask, ADriveFaultStopsTheTaskAsARuntimeErrorNamingTheDriveAndTheArmIsQuickStopped) {
  fba::Task t(task());
  fba::RunResult result;
  std::jthread run([&] { result = t.run(); });
  wait_until_enabled();
  emulator_->inject_fault(3, 0x7121);
  run.join();
  EXPECT_EQ(result.outcome, fba::Outcome::RuntimeError) << result.reason;
  EXPECT_TRUE(contains(result.reason, "joint 'elbow_joint': node 3: EMCY 0x7121")) << result.reason;
  ASSERT_EQ(result.safe_states.size(), 1u);
  EXPECT_EQ(result.safe_states[0].status, "reached") << result.safe_states[0].message;
  for (int node : {1, 2, 4, 5, 6}) EXPECT_TRUE(emulator_.quick_stopped(node)) << "node " << node;
}

TEST_F(CanopenArmInATask, AStopFromOutsideInterruptsTheDriverAndQuickStopsEveryJoint) {
  fba::Task t(task());
  fba::RunResult result;
  std::jthread run([&] { result = t.run(); });
  wait_until_enabled();
  t.request_stop(fba::Outcome::Interrupted, "the test stops the task");  // as a signal does
  run.join();
  EXPECT_EQ(result.outcome, fba::Outcome::Interrupted) << result.reason;
  EXPECT_TRUE(result.stuck.empty());
  ASSERT_EQ(result.safe_states.size(), 1u);
  EXPECT_EQ(result.safe_states[0].status, "reached") << result.safe_states[0].message;
  for (int node = 1; node <= 6; ++node) EXPECT_TRUE(emulator_.quick_stopped(node)) << "node " << node;
}

namespace {

// The trajectories below start where the emulator's drives stand, at 0.
const std::vector<double> kZero(6, 0.0);

// The set-points the drives took in cyclic synchronous position since SYNC number `after`.
std::vector<fba::emulators::SyncSetPoints> cyclic_set_points(fba::emulators::CanopenArmEmulator& e, std::uint64_t after) {
  std::vector<fba::emulators::SyncSetPoints> out;
  for (const auto& r : e.set_points())
    if (r.sync > after && r.mode == 8) out.push_back(r);
  return out;
}

}  // namespace

// A reach plan's trajectory on the real driver: every drive takes its set-point on the same SYNC,
// all at the same share of their way on each (the emulator's record per SYNC), and the arm arrives
// where the trajectory ends, with joint states all along.
TEST_F(CanopenArmComponent, FollowsATrajectoryWithEveryDriveTakingItsSetPointOnTheSameSyncInStep) {
  make();
  tick();
  const std::vector<double> goal{0.3, -0.2, 0.25, -0.15, 0.2, 0.1};
  const auto syncs = emulator_->syncs_seen();
  h().push("trajectory", fba::test::straight_trajectory(wrist_camera_arm().joint_names(), kZero, goal, 1.0, 0.02, 0.2));
  tick_until_arrived();
  ASSERT_TRUE(h().failure().empty()) << h().failure();
  EXPECT_TRUE(named(h().events(), "unreachable").empty());
  ASSERT_EQ(named(h().events(), "arrived").size(), 1u);
  // Arrived within 1 mrad of the end (the drives' last set-point); they finish its last step.
  auto at_goal = [&] {
    for (int node = 1; node <= 6; ++node)
      if (std::abs(emulator_->position(node) - goal[node - 1] * kCounts) > 1.0) return false;
    return true;
  };
  for (int i = 0; i < 100'000 && !at_goal(); ++i) std::this_thread::sleep_for(1ms);  // the bound only catches a hang
  for (int node = 1; node <= 6; ++node) {
    EXPECT_NEAR(emulator_->position(node), goal[node - 1] * kCounts, 1.0) << "node " << node;
    EXPECT_TRUE(emulator_.enabled(node)) << "node " << node;
  }
  const auto taken = cyclic_set_points(*emulator_, syncs);
  ASSERT_GE(taken.size(), 60u);  // 1.2 s of trajectory at a SYNC every 20 ms of the task's clock
  double previous = 0;
  for (const auto& r : taken) {
    ASSERT_EQ(r.set_points.size(), 6u) << "SYNC " << r.sync << ": a drive took no set-point";
    const double share = r.set_points[0].second / (goal[0] * kCounts);
    for (const auto& [node, counts] : r.set_points)
      EXPECT_NEAR(counts / (goal[node - 1] * kCounts), share, 1e-4) << "SYNC " << r.sync << ", node " << node;
    EXPECT_GE(share, previous - 1e-4) << "SYNC " << r.sync;
    previous = share;
  }
  EXPECT_NEAR(previous, 1.0, 1e-4);
  // Joint states all along; the arrival where the drives stand.
  const auto states = h().values<fba::JointState>("joint_state");
  ASSERT_GE(states.size(), taken.size());
  const auto arrived = nlohmann::json::parse(named(h().events(), "arrived")[0].payload);
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(arrived["joints"][j].get<double>(), goal[j], 1e-3) << "joint " << j;
  // Back in profile position: a joint target moves the arm as before.
  h().push("joint_target", fba::JointState{{"wrist_3_joint"}, {0.0}, {}, 0});
  tick_until_arrived(2);
  EXPECT_EQ(emulator_->position(6), 0);
}

TEST_F(CanopenArmComponent, ATrajectoryThatDoesNotFitTheArmIsRefusedWithNothingSent) {
  make();
  tick();
  const auto names = wrist_camera_arm().joint_names();
  const std::vector<double> goal{0.3, -0.2, 0.25, -0.15, 0.2, 0.1};
  std::vector<std::pair<fba::JointTrajectory, std::string>> cases;
  auto other_names = names;
  other_names[2] = "knee_joint";
  cases.push_back({fba::test::straight_trajectory(other_names, kZero, goal, 1.0), "joint 'knee_joint' is not one of the arm's"});
  auto five = names;
  five.pop_back();
  cases.push_back({fba::test::straight_trajectory(five, std::vector<double>(5, 0.0), std::vector<double>(5, 0.1), 1.0),
                   "the trajectory has no joint 'wrist_3_joint'"});
  cases.push_back({fba::test::straight_trajectory(names, kZero, {0, 0, 3.5, 0, 0, 0}, 5.0),
                   ": joint 'elbow_joint' at 3.15"});
  cases.push_back({fba::test::straight_trajectory(names, kZero, {3, 0, 0, 0, 0, 0}, 0.1), "beyond its limit of"});
  cases.push_back({fba::test::straight_trajectory(names, {0.5, 0, 0, 0, 0, 0}, goal, 1.0),
                   "the trajectory starts with joint 'shoulder_pan_joint' at 0.5 rad, but the arm stands at 0 rad"});
  std::vector<std::uint64_t> before;
  for (int node = 1; node <= 6; ++node) before.push_back(emulator_->sdo_downloads(node));
  const auto syncs = emulator_->syncs_seen();
  for (const auto& [trajectory, why] : cases) {
    h().push("trajectory", trajectory);
    tick();
  }
  ASSERT_TRUE(h().failure().empty()) << h().failure();
  const auto refused = named(h().events(), "unreachable");
  ASSERT_EQ(refused.size(), cases.size());
  for (std::size_t i = 0; i < cases.size(); ++i)
    EXPECT_TRUE(contains(refused[i].payload, cases[i].second)) << refused[i].payload;
  for (int node = 1; node <= 6; ++node) {
    EXPECT_EQ(emulator_->sdo_downloads(node), before[node - 1]) << "node " << node << " was sent a command";
    EXPECT_EQ(emulator_->position(node), 0) << "node " << node;
  }
  EXPECT_TRUE(cyclic_set_points(*emulator_, syncs).empty());
}

TEST_F(CanopenArmComponent, ATrajectoryThatComesWhileTheArmMovesIsRefused) {
  make({{"speed_scale", 0.2}});
  tick();
  start_long_move();
  h().push("trajectory", fba::test::straight_trajectory(wrist_camera_arm().joint_names(), kZero, kZero, 0.2));
  tick();
  ASSERT_TRUE(h().failure().empty()) << h().failure();
  const auto refused = named(h().events(), "unreachable");
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_TRUE(contains(refused[0].payload, "the arm is moving")) << refused[0].payload;
}

// A drive that stops taking its set-points mid-trajectory: every joint is quick-stopped on the SYNC
// where it shows, naming it, and no other drive took a set-point the failing one did not take
// after that SYNC (at most that one SYNC's).
TEST_F(CanopenArmComponent, ADriveThatStopsTakingItsSetPointsMidTrajectoryStopsEveryJointOnThatSync) {
  make();
  tick();
  const auto syncs = emulator_->syncs_seen();
  h().push("trajectory", fba::test::straight_trajectory(wrist_camera_arm().joint_names(), kZero,
                                                        {1.0, -1.0, 1.0, -1.0, 1.0, -1.0}, 20.0));
  tick();
  tick_until([&] { return cyclic_set_points(*emulator_, syncs).size() >= 5; });
  emulator_->ignore_set_points(3);
  tick_until_failed();
  const std::string why = h().failure();
  EXPECT_TRUE(contains(why, emulator_.device())) << why;
  EXPECT_TRUE(contains(why, "joint 'elbow_joint' (node 3): does not follow its set-point")) << why;
  EXPECT_TRUE(contains(why, "every joint was sent quick stop")) << why;
  for (int node : {1, 2, 4, 5, 6}) EXPECT_TRUE(emulator_.quick_stopped(node)) << "node " << node;
  const auto taken = cyclic_set_points(*emulator_, syncs);
  ASSERT_FALSE(taken.empty());
  for (std::size_t i = 0; i + 1 < taken.size(); ++i)
    EXPECT_EQ(taken[i].set_points.size(), 6u) << "SYNC " << taken[i].sync << ": the others moved on alone before the last";
  EXPECT_EQ(taken.back().set_points.size(), 5u);  // the SYNC it missed, and the arm stopped on it
  EXPECT_TRUE(named(h().events(), "arrived").empty());
}

// Start-up in the constructor: a device that fails ends the construction as a device error (a
// runtime error, exit 3), naming the drive, with no drive left enabled.
class CanopenArmStartUp : public ::testing::Test {
 protected:
  std::string construct(const fba::emulators::CanopenArmOptions& options, fba::testing::Params more = {}) {
    emulator_.emplace(options);
    more.try_emplace("enable_timeout_ms", 1000);
    try {
      ComponentHarness h(built_plugins(), "hw.canopen_arm", arm_params(emulator_->device(), more));
    } catch (const fba::ConstructionError& e) {
      EXPECT_EQ(e.outcome(), fba::Outcome::RuntimeError) << e.what();
      return e.what();
    }
    return "";
  }
  // The figure (measured, not asserted): from the last frame `detected_at` matches (what the
  // failure was found by; `wait_ms` later for a wait that ran out) to every drive's quick stop heard.
  template <class F>
  void print_figure(const std::string& what, F detected_at, double wait_ms = 0) {
    const auto heard = (*emulator_)->heard();
    const auto at = (*emulator_)->heard_at();
    long from = -1;
    for (long i = 0; i < static_cast<long>(heard.size()); ++i)
      if (detected_at(heard[static_cast<std::size_t>(i)])) from = i;
    std::chrono::steady_clock::time_point stopped{};
    for (int node = 1; node <= 6; ++node)
      if (const long i = fba::test::last_quick_stop(heard, node); i >= 0) stopped = std::max(stopped, at[static_cast<std::size_t>(i)]);
    if (from < 0 || stopped == std::chrono::steady_clock::time_point{}) return;
    std::cout << "measured: " << what << " to every quick stop heard: "
              << std::chrono::duration<double, std::milli>(stopped - at[static_cast<std::size_t>(from)]).count() - wait_ms
              << " ms\n";
  }
  std::optional<Emulator> emulator_;
};

TEST_F(CanopenArmStartUp, ADriveInFaultIsRefusedAsADeviceErrorNamingItsErrorCode) {
  fba::emulators::CanopenArmOptions options;
  options.fault_at_start = {{4, 0x7121}};
  const std::string why = construct(options);
  EXPECT_TRUE(contains(why, "could not start its device")) << why;
  EXPECT_TRUE(contains(why, "hw.canopen_arm on " + emulator_->device())) << why;
  EXPECT_TRUE(contains(why, "joint 'wrist_1_joint' (node 4): the drive is in fault at start-up, error code 0x7121 (motor blocked)"))
      << why;
  EXPECT_TRUE(emulator_->in_fault(4)) << "reset without leave";
  for (int node = 1; node <= 6; ++node) EXPECT_FALSE(emulator_->enabled(node)) << "node " << node;
}

// Drives that power on away from zero: the first joint state is where they stand, published
// with the camera pose left out (initial_camera_pose off, as the grasp task's profiles have it).
TEST(CanopenArmStartPosition, TheFirstJointStateIsWhereTheDrivesStandAndNoCameraPoseWhenItIsOff) {
  fba::emulators::CanopenArmOptions options;
  const std::vector<double> stand{-0.4148, -2.1223, 2.2888, -2.2234, -1.3679, -0.3644};
  for (int node = 1; node <= 6; ++node)
    options.position_at_start[node] = static_cast<std::int32_t>(std::lround(stand[static_cast<std::size_t>(node - 1)] * kCounts));
  Emulator emulator(options);
  ComponentHarness h(built_plugins(), "hw.canopen_arm", arm_params(emulator.device(), {{"initial_camera_pose", false}}),
                     std::vector<std::string>{"target", "joint_target", "trajectory"});
  h.tick();
  h.run();
  ASSERT_TRUE(h.failure().empty()) << h.failure();
  const auto states = h.values<fba::JointState>("joint_state");
  ASSERT_EQ(states.size(), 1u);
  for (std::size_t j = 0; j < 6; ++j) EXPECT_NEAR(states[0].positions[j], stand[j], 1.0 / kCounts) << "joint " << j;
  EXPECT_TRUE(h.values<fba::Pose>("camera_pose").empty());
}

TEST_F(CanopenArmStartUp, ADriveInFaultIsResetWhenTheTaskAllowsIt) {
  fba::emulators::CanopenArmOptions options;
  options.fault_at_start = {{4, 0x7121}};
  EXPECT_EQ(construct(options, {{"reset_faults_at_start", true}}), "");
  for (int node = 1; node <= 6; ++node) EXPECT_TRUE(emulator_->enabled(node)) << "node " << node;
}

TEST_F(CanopenArmStartUp, ANodeThatIsNotACia402DriveOrDoesNotBootIsADeviceError) {
  fba::emulators::CanopenArmOptions other;
  other.device_type = {{2, 0x00020191}};
  std::string why = construct(other);
  EXPECT_TRUE(contains(why, "joint 'shoulder_lift_joint' (node 2): device type 0x00020191 (0x1000) is device profile 401"))
      << why;
  print_figure("not a CiA 402 drive, 0x1000's read", [](const fba::can::Frame& f) {
    return f.id == 0x602 && f.data[0] == 0x40 && f.data[1] == 0x00 && f.data[2] == 0x10;
  });
  fba::emulators::CanopenArmOptions silent;
  silent.silent = {6};
  why = construct(silent);
  EXPECT_TRUE(contains(why, "could not start its device")) << why;
  EXPECT_TRUE(contains(why, "no boot-up message within 1000 ms of an NMT reset communication from joint 'wrist_3_joint' (node 6)"))
      << why;
  print_figure("a node that does not boot, its NMT reset (+ the 1000 ms boot-up wait)",
               [](const fba::can::Frame& f) { return f.id == 0 && f.data[0] == 0x82 && f.data[1] == 6; }, 1000);
}

TEST_F(CanopenArmStartUp, AnAdapterThatDoesNotAnswerIsADeviceError) {
  fba::can::Pty nobody = fba::can::open_pty();  // a terminal with nothing behind it
  try {
    ComponentHarness h(built_plugins(), "hw.canopen_arm",
                       {{"device", "slcan:" + nobody.slave_path},
                        {"node_ids", std::vector<double>{1, 2, 3, 4, 5, 6}},
                        {"counts_per_rad", std::vector<double>(6, kCounts)}});
    FAIL() << "started without an adapter";
  } catch (const fba::ConstructionError& e) {
    EXPECT_EQ(e.outcome(), fba::Outcome::RuntimeError) << e.what();
    EXPECT_TRUE(contains(e.what(), "could not start its device: hw.canopen_arm on slcan:" + nobody.slave_path)) << e.what();
  }
}

// The emulated profile's way: given an emulator, the driver starts it when its bus is not there (no
// second terminal) and stops it when the driver goes; the program ends on that SIGTERM and takes
// its link with it.
TEST(CanopenArmEmulatorProgram, TheDriverStartsItsEmulatorWhenTheBusIsNotThereAndStopsItAtTheEnd) {
  fba::test::TempDir dir;
  const std::string link = dir.file("arm");
  {
    ComponentHarness h(built_plugins(), "hw.canopen_arm",
                       {{"device", "slcan:" + link},
                        {"emulator", std::string("fba-canopen-arm-emulator --heartbeat-ms 20")},
                        {"node_ids", std::vector<double>{1, 2, 3, 4, 5, 6}},
                        {"counts_per_rad", std::vector<double>(6, kCounts)},
                        {"heartbeat_timeout_ms", 1000},
                        {"sdo_timeout_ms", 1000}},
                       {"joint_target"});
    EXPECT_TRUE(std::filesystem::is_symlink(link));
    h.tick();
    h.run();
    h.push("joint_target", fba::JointState{{"wrist_3_joint"}, {0.05}, {}, 0});
    for (int i = 0; i < 100'000 && named(h.events(), "arrived").empty() && h.failure().empty(); ++i) {
      h.tick();
      h.run();
      std::this_thread::sleep_for(1ms);
    }
    EXPECT_EQ(h.failure(), "");
    EXPECT_EQ(named(h.events(), "arrived").size(), 1u);
  }
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::symlink_status(link)));
}
