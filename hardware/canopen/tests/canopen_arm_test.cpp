// The CANopen arm (six CiA 402 joints driven as one) against the emulator, over both transports:
// synchronised moves in joint units, limits checked before anything is sent, and every fault
// ending in a quick stop of the joints that can still hear, with the joint and the reason named.
#include <cmath>
#include <functional>
#include <initializer_list>
#include <iostream>
#include <optional>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "emulated_arm.hpp"
#include "fba/canopen/arm.hpp"
#include "support/canopen_frames.hpp"
#include "support/contains.hpp"

using namespace std::chrono_literals;
using namespace fba::canopen;
using fba::test::Transport;

namespace {

constexpr double kCounts = 10'000;  // counts per radian

using fba::test::contains;

class CanopenArmTest : public ::testing::TestWithParam<Transport> {
 protected:
  void SetUp() override {
    fba::emulators::CanopenArmOptions options;
    options.nodes = {1, 2, 3, 4, 5, 6};
    options.heartbeat_ms = 20;
    emulated_.emplace(GetParam(), options);
    // Generous: on a loaded machine an answer through the pseudo-terminal was seen to take over 1 s
    // (1 run in about 400 with ten jobs on two cores). The silent joint costs two of these.
    master_.emplace(emulated_->host(), MasterOptions{.sdo_timeout = 3s});
    std::vector<ArmJoint> joints;
    for (int n = 1; n <= 6; ++n)
      joints.push_back(
          {"joint" + std::to_string(n), n, kCounts, 1000 * n, -2.5, 2.5, 20.0});  // 20 rad/s: short test moves
    // A consumer timeout far above the 20 ms heartbeat: a loaded machine cannot fake a loss.
    arm_.emplace(*master_, joints, ArmOptions{.heartbeat_ms = 20, .heartbeat_timeout = 3s});
    arm_->start();
  }
  fba::emulators::CanopenArmEmulator& emulator() { return emulated_->emulator(); }
  bool quick_stopped(int node) { return (emulator().statusword(node) & 0x6F) == 0x07; }
  // Every joint but the failed one's shows "quick stop active".
  void expect_quick_stopped_but(int failed) {
    for (int node = 1; node <= 6; ++node)
      if (node != failed) EXPECT_TRUE(quick_stopped(node)) << "node " << node;
  }
  // What the arm stopped with while `action` ran: ArmStopped's node and message.
  struct Stop {
    int node = -1;
    std::string why;
  };
  static Stop stop_of(const std::function<void()>& action) {
    try {
      action();
    } catch (const ArmStopped& e) {
      return {e.node, e.what()};
    }
    ADD_FAILURE() << "the arm did not stop";
    return {};
  }
  // `action` stops the arm naming `node`, with each of `says` in the message.
  static void expect_stop(const std::function<void()>& action, int node, std::initializer_list<std::string> says) {
    const Stop stop = stop_of(action);
    EXPECT_EQ(stop.node, node);
    for (const auto& part : says) EXPECT_TRUE(contains(stop.why, part)) << stop.why;
  }

  std::optional<fba::test::EmulatedArm> emulated_;
  std::optional<Master> master_;
  std::optional<CanopenArm> arm_;
};

}  // namespace

INSTANTIATE_TEST_SUITE_P(Transports, CanopenArmTest, ::testing::Values(Transport::slcan_pty, Transport::socketpair),
                         fba::test::transport_name);

TEST_P(CanopenArmTest, EveryJointReachesItsTargetInJointUnits) {
  const std::vector<double> targets{0.5, -0.3, 1.0, 0.0, 0.2, -1.0};
  arm_->move_and_wait(targets, 1.0, 10s);
  const auto at = arm_->positions();
  for (std::size_t i = 0; i < targets.size(); ++i) EXPECT_NEAR(at[i], targets[i], 1 / kCounts) << "joint " << i + 1;
  EXPECT_EQ(emulator().position(3), 1000 * 3 + 10'000);  // the zero offset and the scale reach the drive
}

TEST_P(CanopenArmTest, JointsMoveTogetherTheLongestAtTheScaledMaximumVelocity) {
  // The joints start at -0.1 * n rad (drive position 0, zero offset 1000 * n counts): these
  // targets are 1.0, 0.5, 0.25, 0, 0 and 1.0 rad away, a move of 0.1 s at 20 rad/s * 0.5.
  arm_->move_to({0.9, 0.3, -0.05, -0.4, -0.5, -1.6}, 0.5);
  auto velocity = [&](int node) { return static_cast<double>(master_->read<std::uint32_t>(node, 0x6081, 0)); };
  EXPECT_NEAR(velocity(1), 100'000, 1);  // 20 rad/s * 0.5 * 10,000 counts/rad
  EXPECT_NEAR(velocity(6), 100'000, 1);
  EXPECT_NEAR(velocity(2), 50'000, 1);  // half the distance in the same time
  EXPECT_NEAR(velocity(3), 25'000, 1);
}

TEST_P(CanopenArmTest, EveryJointTakesItsSetPointOnTheSameSync) {
  const auto syncs = emulator().syncs_seen();
  arm_->move_to({0.5, 0.5, 0.5, 0.5, 0.5, 0.5}, 0.01);
  // Started together: at the same instant every joint has covered the same share of its way.
  const auto s = arm_->sample(1s);
  EXPECT_EQ(emulator().syncs_seen(), syncs + 3);  // bit 4 up with the targets, then down; the sample
  const double share = (s.positions[0] + 0.1) / 0.6;
  for (int n = 2; n <= 6; ++n)
    EXPECT_NEAR((s.positions[n - 1] + 0.1 * n) / (0.5 + 0.1 * n), share, 0.002) << "joint " << n;
}

TEST_P(CanopenArmTest, ACommandBeyondTheLimitsIsRefusedWithNothingSent) {
  const std::vector<std::vector<double>> refused{
      {0, 0, 2.6, 0, 0, 0}, {0, 0, 0, NAN, 0, 0}, {0, 0, 0, 0, 0, -INFINITY}, {0, 0, 0}};
  for (const auto& targets : refused) EXPECT_THROW(arm_->move_to(targets), LimitError);
  try {
    arm_->move_to({0, 0, 2.6, 0, 0, 0});
  } catch (const LimitError& e) {
    EXPECT_TRUE(contains(e.what(), "joint 'joint3' (node 3): target 2.6 is outside its limits [-2.5, 2.5]"))
        << e.what();
    EXPECT_TRUE(contains(e.what(), "no command was sent")) << e.what();
  }
  EXPECT_THROW(arm_->move_to({0, 0, 0, 0, 0, 0}, 1.5), LimitError);
  for (int node = 1; node <= 6; ++node) EXPECT_EQ(master_->read<std::int32_t>(node, 0x607A, 0), 0) << "node " << node;
  EXPECT_EQ(master_->read<std::int32_t>(3, 0x607D, 2), 3000 + 25'000);  // the drive's own limit, in counts
}

TEST_P(CanopenArmTest, AnEmcyOnOneJointQuickStopsTheOthersAndNamesIt) {
  arm_->move_to({2, 2, 2, 2, 2, 2}, 0.001);  // 100 s: the fault comes first
  emulator().inject_fault(4, 0x7121);
  expect_stop([&] { arm_->move_and_wait({2, 2, 2, 2, 2, 2}, 0.001, 60s); }, 4, {"node 4", "every joint was sent quick stop"});
  expect_quick_stopped_but(4);
}

TEST_P(CanopenArmTest, AJointFallingSilentQuickStopsTheOthers) {
  arm_->move_to({2, 2, 2, 2, 2, 2}, 0.001);
  emulator().silence(2);
  const auto until_reached = [&] {
    while (!arm_->reached()) master_->spin_for(5ms);
  };
  expect_stop(until_reached, 2, {"node 2", "quick stop failed on 1 of 6 joints: joint 'joint2' (node 2)"});
  expect_quick_stopped_but(2);
}

TEST_P(CanopenArmTest, TheLineVanishingStopsTheArmWithAClearError) {
  arm_->move_to({2, 2, 2, 2, 2, 2}, 0.001);
  emulator().disconnect();
  expect_stop([&] { arm_->move_and_wait({2, 2, 2, 2, 2, 2}, 0.001, 60s); }, 0,
              {master_->bus().name(), "quick stop failed on 6 of 6 joints"});
}

TEST_P(CanopenArmTest, AccelerationsAreScaledLikeVelocitiesSoTheJointsStayInStep) {
  // As above: distances 1.0, 0.5, 0.25 rad; the default acceleration is ten times the velocity.
  const double seconds = arm_->move_to({0.9, 0.3, -0.05, -0.4, -0.5, -1.6}, 0.5);
  auto acceleration = [&](int node) { return static_cast<double>(master_->read<std::uint32_t>(node, 0x6083, 0)); };
  EXPECT_NEAR(acceleration(1), 2'000'000, 1);  // 200 rad/s^2 * 10,000 counts/rad, for the longest
  EXPECT_NEAR(acceleration(2), 1'000'000, 1);
  EXPECT_NEAR(acceleration(3), 500'000, 1);
  EXPECT_EQ(master_->read<std::uint32_t>(3, 0x6084, 0), master_->read<std::uint32_t>(3, 0x6083, 0));
  EXPECT_NEAR(seconds, 1.0 / 10 + 10.0 / 200, 1e-9);  // cruise 1 rad at 10 rad/s, plus one ramp of 0.05 s
}

TEST_P(CanopenArmTest, ASampleIsEveryDrivesPdosAnsweringOneSync) {
  const auto before = arm_->sample(1s);
  for (int n = 1; n <= 6; ++n) EXPECT_NEAR(before.positions[n - 1], -0.1 * n, 1e-12);  // drive 0, zero 1000 n
  EXPECT_TRUE(before.reached);
  const auto syncs = emulator().syncs_seen();
  arm_->move_to({2, 2, 2, 2, 2, 2}, 0.01);  // a slow move: seconds
  const auto moving = arm_->sample(1s);
  EXPECT_EQ(emulator().syncs_seen(), syncs + 3);  // the move's two, and the sample's, whose answers came
  EXPECT_FALSE(moving.reached);
  for (int n = 1; n <= 6; ++n) EXPECT_GT(moving.velocities[n - 1], 0) << "joint " << n;
  ArmSample last;
  do last = arm_->sample(1s);
  while (!last.reached && last.positions[0] < -0.09);  // until joint 1 has visibly moved
  EXPECT_GT(last.positions[0], -0.1);
  const auto now = arm_->positions();  // through SDO, a little later
  for (int n = 1; n <= 6; ++n) EXPECT_GE(now[n - 1], last.positions[n - 1]) << "joint " << n;
}

// Each drive is its own SDO server: every quick stop is sent before any answer is awaited, so a
// silent drive costs one SDO timeout for the whole arm, not one before each drive behind it.
TEST_P(CanopenArmTest, AQuickStopReachesEveryDriveBeforeAnyAnswerIsAwaitedAndNamesTheOneThatDidNotConfirm) {
  arm_->move_to({2, 2, 2, 2, 2, 2}, 0.001);  // 100 s
  emulator().silence(2);
  while (!emulator().silent(2)) std::this_thread::sleep_for(1ms);
  const auto failures = arm_->quick_stop_all();
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_TRUE(contains(failures[0], "joint 'joint2' (node 2)")) << failures[0];
  EXPECT_TRUE(contains(failures[0], "no answer")) << failures[0];
  expect_quick_stopped_but(2);
  // In the order the drives heard it: every quick stop came before the master gave up on node 2.
  fba::test::expect_quick_stops_before_giving_up(emulator(), 2);
}

TEST_P(CanopenArmTest, AnInterruptFromAnotherThreadEndsAWaitAndTheJointsStillGetQuickStop) {
  arm_->move_to({2, 2, 2, 2, 2, 2}, 0.001);  // 100 s
  // A jthread: joined however the test ends.
  std::jthread stopper([&] {
    std::this_thread::sleep_for(20ms);
    master_->interrupt();
  });
  const Stop stop = stop_of([&] { arm_->move_and_wait({2, 2, 2, 2, 2, 2}, 0.001, 60s); });
  EXPECT_TRUE(contains(stop.why, "interrupted")) << stop.why;
  stopper.join();
  // The interrupted master sends nothing more, but the stop: the quick stops go out and are confirmed.
  EXPECT_THROW(arm_->move_to({1, 1, 1, 1, 1, 1}), ArmStopped);
  EXPECT_TRUE(arm_->quick_stop_all().empty());
  for (int node = 1; node <= 6; ++node) EXPECT_TRUE(quick_stopped(node)) << "node " << node;
}

TEST(CanopenArmConfiguration, ImpossibleJointsAreRefused) {
  auto [a, b] = fba::can::socketpair_bus();
  Master master(*a);
  const ArmJoint ok{"j", 1, 1000, 0, -1, 1, 1};
  EXPECT_THROW(CanopenArm(master, {}), std::invalid_argument);
  EXPECT_THROW(CanopenArm(master, {ok, ok}), std::invalid_argument);  // node 1 twice
  ArmJoint bad = ok;
  bad.lower = 2;
  EXPECT_THROW(CanopenArm(master, {bad}), std::invalid_argument);
  bad = ok;
  bad.counts_per_unit = 0;
  EXPECT_THROW(CanopenArm(master, {bad}), std::invalid_argument);
  bad = ok;
  bad.max_velocity = 0;
  EXPECT_THROW(CanopenArm(master, {bad}), std::invalid_argument);
  bad = ok;
  bad.node = 128;
  EXPECT_THROW(CanopenArm(master, {bad}), std::invalid_argument);
}

// Start-up, each failure its own emulator: the arm refuses what is not a healthy CiA 402 drive,
// naming the joint, its node and why, before any drive is enabled.
class CanopenArmStartUp : public ::testing::TestWithParam<Transport> {
 protected:
  // Six drives as `options` has them (20 ms heartbeats), the master, and the arm (not started).
  void make(fba::emulators::CanopenArmOptions options, ArmOptions arm = {}) {
    options.nodes = {1, 2, 3, 4, 5, 6};
    options.heartbeat_ms = 20;
    emulated_.emplace(GetParam(), options);
    master_.emplace(emulated_->host(), MasterOptions{.sdo_timeout = 3s});
    std::vector<ArmJoint> joints;
    for (int n = 1; n <= 6; ++n) joints.push_back({"joint" + std::to_string(n), n, kCounts, 0, -2.5, 2.5, 20.0});
    arm.heartbeat_ms = 20;
    arm.heartbeat_timeout = 3s;
    arm_.emplace(*master_, joints, arm);
  }
  fba::emulators::CanopenArmEmulator& emulator() { return emulated_->emulator(); }
  std::string start_failure() {
    try {
      arm_->start();
    } catch (const ArmStopped& e) {
      return e.what();
    }
    return "";
  }

  std::optional<fba::test::EmulatedArm> emulated_;
  std::optional<Master> master_;
  std::optional<CanopenArm> arm_;
};

INSTANTIATE_TEST_SUITE_P(Transports, CanopenArmStartUp, ::testing::Values(Transport::slcan_pty, Transport::socketpair),
                         fba::test::transport_name);

// The order the drives heard: the communication reset of every node first, then (per node) the
// mode of operation before the controlword that enables operation.
TEST_P(CanopenArmStartUp, ResetsCommunicationThenSetsTheModeBeforeEnablingEachDrive) {
  make({});
  arm_->start();
  const auto heard = emulator().heard();
  long first_sdo = -1;
  for (long i = 0; i < static_cast<long>(heard.size()) && first_sdo < 0; ++i)
    if ((heard[static_cast<std::size_t>(i)].id & 0x780) == 0x600) first_sdo = i;
  ASSERT_GE(first_sdo, 0);
  for (int node = 1; node <= 6; ++node) {
    long reset = -1, mode = -1, enable = -1;
    for (long i = 0; i < static_cast<long>(heard.size()); ++i) {
      const auto& f = heard[static_cast<std::size_t>(i)];
      if (f.id == 0x000 && f.dlc == 2 && f.data[0] == 0x82 && f.data[1] == node && reset < 0) reset = i;
      if (f.id == 0x600u + node && f.data[0] == 0x2F && f.data[1] == 0x60 && f.data[2] == 0x60 && mode < 0) mode = i;
      if (f.id == 0x600u + node && f.data[0] == 0x2B && f.data[1] == 0x40 && f.data[2] == 0x60 && f.data[4] == 0x0F &&
          enable < 0)
        enable = i;
    }
    EXPECT_GE(reset, 0) << "node " << node;
    EXPECT_LT(reset, first_sdo) << "node " << node << ": an SDO went out before every node was reset";
    EXPECT_GE(mode, 0) << "node " << node;
    EXPECT_GE(enable, 0) << "node " << node;
    EXPECT_LT(mode, enable) << "node " << node << ": enabled before its mode of operation was set";
    EXPECT_EQ(emulator().statusword(node) & 0x6F, 0x27) << "node " << node;
  }
}

TEST_P(CanopenArmStartUp, ADriveInFaultIsRefusedNamingItsErrorCodeAndNotReset) {
  fba::emulators::CanopenArmOptions options;
  options.fault_at_start = {{3, 0x7121}};
  make(options);
  const std::string why = start_failure();
  EXPECT_TRUE(contains(why, "joint 'joint3' (node 3): the drive is in fault at start-up, error code 0x7121 (motor blocked)"))
      << why;
  EXPECT_TRUE(contains(why, "it is not reset unless allowed (reset_faults_at_start)")) << why;
  EXPECT_EQ(emulator().statusword(3) & 0x4F, 0x08) << "the fault was reset";
  for (int node = 1; node <= 6; ++node)
    EXPECT_NE(emulator().statusword(node) & 0x6F, 0x27) << "node " << node << " was enabled";
}

TEST_P(CanopenArmStartUp, ADriveInFaultIsResetWhenAllowedWithItsErrorCodeTold) {
  fba::emulators::CanopenArmOptions options;
  options.fault_at_start = {{3, 0x7121}};
  std::vector<std::string> notices;
  make(options, ArmOptions{.reset_faults = true, .notice = [&](const std::string& s) { notices.push_back(s); }});
  arm_->start();
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_TRUE(contains(notices[0], "joint 'joint3' (node 3): the drive is in fault at start-up, error code 0x7121")) << notices[0];
  EXPECT_TRUE(contains(notices[0], "resetting it")) << notices[0];
  for (int node = 1; node <= 6; ++node) EXPECT_EQ(emulator().statusword(node) & 0x6F, 0x27) << "node " << node;
}

TEST_P(CanopenArmStartUp, ANodeThatIsNotACia402DriveIsRefused) {
  fba::emulators::CanopenArmOptions options;
  options.device_type = {{5, 0x00040191}};  // CiA 401: generic I/O
  make(options);
  const std::string why = start_failure();
  EXPECT_TRUE(contains(why, "joint 'joint5' (node 5): device type 0x00040191 (0x1000) is device profile 401, not a CiA 402 drive"))
      << why;
  for (int node = 1; node <= 6; ++node)
    EXPECT_NE(emulator().statusword(node) & 0x6F, 0x27) << "node " << node << " was enabled";
}

TEST_P(CanopenArmStartUp, ANodeThatNeverBootsIsNamed) {
  fba::emulators::CanopenArmOptions options;
  options.silent = {2};
  make(options, ArmOptions{.enable_timeout = 500ms});
  const std::string why = start_failure();
  EXPECT_TRUE(contains(why, "no boot-up message within 500 ms of an NMT reset communication from joint 'joint2' (node 2)"))
      << why;
  EXPECT_TRUE(contains(why, "quick stop failed on 1 of 6 joints")) << why;
}

// Cyclic synchronous position: every drive takes its set-point on the same SYNC, and the drives'
// set-points, as the emulator recorded them per SYNC, stay in step along the way.
TEST_P(CanopenArmTest, InCyclicSynchronousPositionEveryDriveTakesItsSetPointOnEverySyncInStep) {
  arm_->begin_cyclic();
  std::vector<double> start(6);
  for (int n = 1; n <= 6; ++n) start[n - 1] = -0.1 * n;  // drive position 0, zero offset 1000 n
  const std::vector<double> goal{0.5, 0.2, 0.3, -0.9, 0.1, -0.2};
  const auto before = emulator().syncs_seen();
  constexpr int kSteps = 20;
  for (int k = 1; k <= kSteps; ++k) {
    std::vector<double> q(6);
    for (int j = 0; j < 6; ++j) q[j] = start[j] + (goal[j] - start[j]) * k / kSteps;
    const ArmSample s = arm_->cycle(q, 1s);
    ASSERT_EQ(s.positions.size(), 6u);
  }
  EXPECT_EQ(emulator().syncs_seen(), before + kSteps);  // one SYNC a cycle
  std::vector<fba::emulators::SyncSetPoints> taken;
  for (const auto& r : emulator().set_points())
    if (r.sync > before) taken.push_back(r);
  ASSERT_EQ(taken.size(), static_cast<std::size_t>(kSteps));
  for (const auto& r : taken) {
    EXPECT_EQ(r.mode, 8);
    ASSERT_EQ(r.set_points.size(), 6u) << "SYNC " << r.sync << ": a drive took no set-point";
    // Every drive at the same share of its way, to the count.
    const double share = (r.set_points[0].second - 1000.0 - start[0] * kCounts) / ((goal[0] - start[0]) * kCounts);
    for (const auto& [node, counts] : r.set_points) {
      const double expected = (start[node - 1] + (goal[node - 1] - start[node - 1]) * share) * kCounts + 1000.0 * node;
      EXPECT_NEAR(counts, expected, 1.0) << "SYNC " << r.sync << ", node " << node;
    }
  }
  arm_->end_cyclic();
  // Back in profile position, where they stand: a move works as before.
  arm_->move_and_wait(goal, 1.0, 10s);
  EXPECT_EQ(master_->read<std::int8_t>(1, 0x6061, 0), 1);
}

// One drive does not follow its set-points: on the SYNC where it shows it, every joint is
// quick-stopped, naming it, and no drive is given another set-point.
TEST_P(CanopenArmTest, ADriveThatDoesNotFollowItsSetPointsStopsEveryJointOnThatSync) {
  arm_->begin_cyclic();
  std::vector<double> q(6);
  for (int n = 1; n <= 6; ++n) q[n - 1] = -0.1 * n;
  for (int k = 0; k < 3; ++k) arm_->cycle(q, 1s);
  emulator().ignore_set_points(4);
  const auto move_on = [&] {
    for (int k = 0; k < 1000; ++k) {  // the bound only catches a hang
      for (double& x : q) x += 0.001;
      arm_->cycle(q, 1s);
    }
  };
  expect_stop(move_on, 4, {"joint 'joint4' (node 4): does not follow its set-point", "every joint was sent quick stop"});
  expect_quick_stopped_but(4);
  // After the last SYNC, only the quick stops went out: no set-point (RPDO), no further SYNC.
  const auto heard = emulator().heard();
  long last_sync = -1;
  for (long i = 0; i < static_cast<long>(heard.size()); ++i)
    if (heard[static_cast<std::size_t>(i)].id == 0x080) last_sync = i;
  for (long i = last_sync + 1; i < static_cast<long>(heard.size()); ++i) {
    const auto& f = heard[static_cast<std::size_t>(i)];
    EXPECT_FALSE((f.id & 0x780) == 0x200) << "a set-point to node " << (f.id & 0x7F) << " after the failure";
  }
  for (int node = 1; node <= 6; ++node) EXPECT_GT(fba::test::last_quick_stop(heard, node), last_sync) << "node " << node;
}

// Profile position: a drive that does not acknowledge its set-point stops the arm within one SDO
// timeout of the set-points' SYNC; the master asks for the acknowledges by SYNC, each answered by
// the drives' PDOs, not by polling the drive's statusword through SDO.
TEST_P(CanopenArmTest, ASetPointNotAcknowledgedStopsEveryJointWithoutPollingTheDriveBySdo) {
  emulator().ignore_set_points(2);
  const auto before = emulator().heard().size();
  expect_stop([&] { arm_->move_to({1, 1, 1, 1, 1, 1}, 0.01); }, 2,
              {"joint 'joint2' (node 2): did not acknowledge its set-point within 3000 ms", "every joint was sent quick stop"});
  expect_quick_stopped_but(2);
  const auto heard = emulator().heard();
  ASSERT_LT(before, heard.size());
  long set_points = -1;  // the RPDO with bit 4 to node 2
  for (long i = static_cast<long>(before); i < static_cast<long>(heard.size()) && set_points < 0; ++i)
    if (heard[static_cast<std::size_t>(i)].id == 0x202 && (heard[static_cast<std::size_t>(i)].data[0] & 0x10)) set_points = i;
  ASSERT_GE(set_points, 0);
  const long stopped = fba::test::last_quick_stop(heard, 2);
  std::size_t statusword_reads = 0, syncs = 0;
  for (long i = set_points; i < stopped; ++i) {
    const auto& f = heard[static_cast<std::size_t>(i)];
    statusword_reads += f.id == 0x602 && f.data[0] == 0x40 && f.data[1] == 0x41 && f.data[2] == 0x60;
    syncs += f.id == 0x080;
  }
  EXPECT_EQ(statusword_reads, 0u);
  // About one SYNC a SYNC period (20 ms) over the 3 s: nothing like 750 frames a second.
  EXPECT_LE(syncs, 3000u / 20u + 2u);
  // The figure (measured, not asserted): from the set-points' SYNC to node 2's quick stop heard,
  // beyond the SDO timeout that detects the missing acknowledge.
  const auto at = emulator().heard_at();
  std::cout << "measured: a set-point not acknowledged, detected (its SYNC + the 3000 ms SDO timeout) to the quick "
               "stops heard: "
            << std::chrono::duration<double, std::milli>(at[static_cast<std::size_t>(stopped)] -
                                                         at[static_cast<std::size_t>(set_points)])
                       .count() -
                   3000.0
            << " ms\n";
}
