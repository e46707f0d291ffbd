// The real drivers (hw.canopen_arm over SLCAN, hw.robotiq_3f over Modbus RTU) against their
// emulators on pseudo-terminals, the whole way a robot runs them:
// * tasks/grasp.yaml --profile emulated, the drivers starting the emulator programs themselves,
//   runs the loop to a held object; Ctrl-C while the hand activates stops at once;
// * a reach plan's sequence (a timed trajectory and the hand's commands at their times on it):
//   every drive takes its set-point on the same SYNC, in step along the trajectory (the arm
//   emulator's record per SYNC), the hand opens before the approach and closes on the object at the
//   grasp, held, and the arm arrives at the trajectory's end;
// * each fault ends the run as a runtime error (exit 3, never 2) naming the device, with its safe
//   state reached: a drive that stops taking its set-points mid-trajectory, a drive in fault at
//   start-up, a gripper that never activates or answers to another slave id. The time from each
//   failure to the safe state is printed (measured, not asserted: a loaded machine must pass).
#include <gtest/gtest.h>

#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include <fba/component.hpp>
#include <fba/registry.hpp>
#include <fba/task.hpp>
#include <fba/task_config.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/hand_command.hpp>
#include <fba/types/joint_trajectory.hpp>

#include "support/emulated_hand.hpp"
#include "support/build_paths.hpp"
#include "support/built_plugins.hpp"
#include "support/data_sets.hpp"
#include "support/canopen_frames.hpp"
#include "support/child_process.hpp"
#include "support/emulated_canopen_arm.hpp"
#include "support/joint_trajectories.hpp"
#include "support/temp_dir.hpp"
#include "support/fba_run.hpp"

namespace {

using fba::test::Child;
using Clock = std::chrono::steady_clock;
using HandCommand = fba::HandCommand;

constexpr double kCounts = 100'000;  // the profiles' counts per radian
const std::vector<std::string> kJoints{"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                       "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};

// A reach plan as motion.reach_planner times it, from where the emulator's drives stand (0): the
// hand opens at 0 while the arm stands still for a second, the approach, the close at the grasp and
// a second for it, the lift, the hold.
struct Plan {
  static constexpr double kHandS = 1.0, kApproachS = 1.5, kLiftS = 1.0, kHoldS = 0.5;
  static constexpr double kApproachStart = kHandS, kClose = kHandS + kApproachS, kLiftStart = kClose + kHandS;
  static fba::JointTrajectory trajectory() {
    fba::test::TrajectoryBuilder b(kJoints, std::vector<double>(6, 0.0));
    b.hold(kHandS).move_to({0.3, -0.4, 0.5, -0.3, 0.4, 0.2}, kApproachS).hold(kHandS);
    b.move_to({0.3, -0.6, 0.5, -0.2, 0.4, 0.2}, kLiftS).hold(kHoldS);
    return b.trajectory();
  }
  static HandCommand command(HandCommand::Action action, double time) {
    HandCommand c;
    c.action = action;
    c.opening = 0.1;
    c.spread = 0.03;
    c.force = action == HandCommand::Action::Close ? 30 : 0;
    c.time = time;
    return c;
  }
};

// What motion.reach_planner sends, once: the grasp (for the hand's report), the trajectory, the
// hand's commands in order.
class ReachPlanSource final : public fba::Component {
 public:
  static constexpr fba::Out<fba::Grasp> kGrasp{"grasp", "the grasp the plan takes"};
  static constexpr fba::Out<fba::JointTrajectory> kTrajectory{"trajectory", "the arm's trajectory"};
  static constexpr fba::Out<HandCommand> kHand{"hand", "the hand's commands"};
  static fba::Spec spec() {
    return fba::Spec::sensor("test.reach_plan", "Sends one reach plan, as motion.reach_planner would.")
        .add(kGrasp, kTrajectory, kHand);
  }
  explicit ReachPlanSource(fba::Context& ctx) : ctx_(ctx) { ctx.set_trigger({fba::TriggerPolicy::Periodic, 0.5}); }
  void process() override {
    if (sent_) return;  // stays, as a planner does
    sent_ = true;
    fba::Grasp g;
    g.aperture = 0.1;
    g.spread = 0.03;
    ctx_(kGrasp).emit(g);
    ctx_(kTrajectory).emit(Plan::trajectory());
    ctx_(kHand).emit(Plan::command(HandCommand::Action::Open, 0));
    ctx_(kHand).emit(Plan::command(HandCommand::Action::Close, Plan::kClose));
  }

 private:
  fba::Context& ctx_;
  bool sent_ = false;
};
FBA_COMPONENT(ReachPlanSource);

const fba::Registry& registry() {
  static const fba::Registry r = fba::test::built_plugins_and_own("grasp_emulated_test");
  return r;
}

std::string reach_task(const std::string& arm, const std::string& hand) {
  return "task: reach_emulated\nexecutor: threaded\ncomponents:\n"
         "  plan: { type: test.reach_plan }\n"
         "  arm:\n    type: hw.canopen_arm\n    params:\n"
         "      device: " + arm + "\n"
         "      node_ids: [1, 2, 3, 4, 5, 6]\n"
         "      counts_per_rad: [100000, 100000, 100000, 100000, 100000, 100000]\n"
         "      initial_camera_pose: false\n      sdo_timeout_ms: 1000\n      heartbeat_timeout_ms: 1000\n"
         "  hand:\n    type: hw.robotiq_3f\n    params:\n"
         "      device: " + hand + "\n"
         "      response_timeout: 2.0\n      retries: 1\n      poll_period: 0.01\n      hold_time: 0.2\n"
         "connections:\n"
         "  - plan.grasp -> hand.grasp\n  - plan.trajectory -> arm.trajectory\n"
         "  - plan.trajectory -> hand.trajectory\n  - plan.hand -> hand.commands\n"
         "on:\n  hand.dropped: stop_failure\n  arm.unreachable: stop_failure\n  arm.arrived: stop_success\n";
}

fba::emulators::Robotiq3fOptions stalling_hand() {
  auto o = fba::test::EmulatedHand::quick();
  o.stall_aperture = 0.07;
  return o;
}

// Where a SYNC's set-points stand on the trajectory: the time whose positions they are (each
// joint's set-point in counts on the straight line between two waypoints, all at the same share of
// it), and how far the farthest set-point is from there, in counts.
std::pair<double, double> on_trajectory(const fba::JointTrajectory& t, const fba::emulators::SyncSetPoints& r) {
  std::vector<double> sp(6);
  for (const auto& [node, counts] : r.set_points) sp[static_cast<std::size_t>(node - 1)] = counts;
  double best_time = 0, best_error = 1e18;
  for (std::size_t k = 0; k + 1 < t.points.size(); ++k) {
    const auto &a = t.points[k].positions, &b = t.points[k + 1].positions;
    double num = 0, den = 0;
    for (std::size_t j = 0; j < 6; ++j) {
      num += (sp[j] - a[j] * kCounts) * (b[j] - a[j]) * kCounts;
      den += (b[j] - a[j]) * (b[j] - a[j]) * kCounts * kCounts;
    }
    const double share = den > 0 ? std::clamp(num / den, 0.0, 1.0) : 0.0;
    double error = 0;
    for (std::size_t j = 0; j < 6; ++j) error = std::max(error, std::abs(sp[j] - (a[j] + share * (b[j] - a[j])) * kCounts));
    if (error < best_error) {
      best_error = error;
      best_time = t.points[k].time + share * (t.points[k + 1].time - t.points[k].time);
    }
  }
  return {best_time, best_error};
}

double ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

const fba::SafeStateResult* safe_state_of(const std::vector<fba::SafeStateResult>& all, const std::string& component) {
  for (const auto& s : all)
    if (s.component == component) return &s;
  return nullptr;
}

}  // namespace

TEST(GraspEmulated, TheDriversStartTheirEmulatorsAndRunTheLoopToAHeldObject) {
  const fba::test::TempDir temp;
  const std::string arm_link = (temp.path() / "arm").string(), hand_link = (temp.path() / "hand").string();
  fba::LoadOptions load;
  load.profile = "emulated";
  load.overrides.push_back({"arm_bus=slcan:" + arm_link});
  load.overrides.push_back({"hand_device=" + hand_link});
  // Nothing is at either device: each driver starts its emulator program (the profile's).
  load.overrides.push_back({"hand_emulator=fba-robotiq-3f-emulator --activation-s 0.05 --stall-aperture 0.07"});
  // The task as shipped: its object (the mustard bottle) and its views.
  fba::RunOptions options;
  options.timeout_s = 600;  // a hang detector only: the run takes seconds of emulated motion
  fba::RunResult r;
  {
    fba::Task task(fba::load_task(fba::test::tasks_dir() + "/grasp.yaml", fba::test::built_plugins(), load), options);
    EXPECT_TRUE(std::filesystem::is_symlink(arm_link));
    EXPECT_TRUE(std::filesystem::is_symlink(hand_link));
    r = task.run();
  }
  ASSERT_TRUE(r.final_event) << r.reason;
  EXPECT_EQ(r.final_event->source, "hand") << r.reason;
  EXPECT_EQ(r.final_event->name, "held") << r.final_event->payload;
  std::size_t arrivals = 0;
  bool selected = false;
  for (const auto& e : r.events) {
    arrivals += e.source == "arm" && e.name == "arrived";
    selected = selected || (e.source == "synthesis" && e.name == "grasp_selected");
  }
  EXPECT_GE(arrivals, 3u);  // the drives reached the initial views
  EXPECT_TRUE(selected);
  // Both drivers were told to go safe at the stop, and said so.
  for (const char* device : {"arm", "hand"}) {
    const auto* s = safe_state_of(r.safe_states, device);
    ASSERT_TRUE(s) << device;
    EXPECT_EQ(s->status, "reached") << device << ": " << s->message;
  }
  // The emulators were stopped with the task, their links gone with them.
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::symlink_status(arm_link)));
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::symlink_status(hand_link)));
}

// Ctrl-C while the hand activates (its emulator never finishes activating): the activation gives
// up at once rather than at activation_timeout, the arm constructed before it goes to its safe
// state, and fba-run exits 130 with the summary saying where the run stopped.
TEST(GraspEmulated, CtrlCWhileTheHandActivatesStopsAtOnceWithTheSafeStatesInTheSummary) {
  const fba::test::TempDir temp;
  const std::string arm_link = (temp.path() / "arm").string(), hand_link = (temp.path() / "hand").string();
  Child arm({fba::test::program("fba-canopen-arm-emulator"), "--link", arm_link});
  ASSERT_NE(arm.read_until("(link " + arm_link + ")").find("SLCAN adapter on"), std::string::npos) << arm.read_until("");
  Child hand({fba::test::program("fba-robotiq-3f-emulator"), "--link", hand_link, "--never-activate"});
  ASSERT_NE(hand.read_until("(link " + hand_link + ")").find("Modbus RTU slave 9"), std::string::npos);

  const auto out = temp.path() / "out";
  fba::test::Child run(fba::test::fba_run_command({fba::test::tasks_dir() + "/grasp.yaml", "--profile", "emulated", "--set",
                          "arm_bus=slcan:" + arm_link, "--set", "hand_device=" + hand_link, "--output-dir",
                          out.string()}));
  ASSERT_TRUE(run.wait_for_output(": activating (")) << run.output();
  run.signal(SIGINT);
  const auto r = run.wait();
  EXPECT_EQ(r.status, 130) << r.output;
  EXPECT_NE(r.output.find("activation: interrupted (the task is stopping)"), std::string::npos) << r.output;
  const auto summary = nlohmann::json::parse(fba::test::read_file(out / "summary.json"), nullptr, false);
  ASSERT_TRUE(summary.is_object()) << r.output;
  EXPECT_EQ(summary.value("phase", ""), "constructing") << summary.dump(2);
  EXPECT_GT(summary.value("wall_time_s", 0.0), 0) << summary.dump(2);
  const auto& safe = summary["safe_states"];
  EXPECT_EQ(safe["hand"]["status"], "not constructed") << summary.dump(2);
  EXPECT_EQ(safe["arm"]["status"], "reached") << summary.dump(2);  // constructed before the hand
}

// A reach plan on the real drivers: the trajectory followed by all six drives together, the hand's
// commands in order at their times on it, the object held, the arm arrived at the trajectory's end.
TEST(GraspEmulatedReach, TheDrivesFollowThePlanInStepAndTheHandClosesAtTheGraspAndHolds) {
  const fba::test::TempDir dir;
  fba::test::EmulatedCanopenArm arm;
  fba::test::EmulatedHand hand(stalling_hand());
  fba::RunOptions options;
  options.timeout_s = 600;  // a hang detector only
  fba::Task task(fba::load_task_text(reach_task(arm.device(), hand.device()), "reach.yaml", dir.path(), registry()), options);
  const auto r = task.run();
  ASSERT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  ASSERT_TRUE(r.final_event);
  EXPECT_EQ(r.final_event->source, "arm");
  EXPECT_EQ(r.final_event->name, "arrived");
  bool held = false;
  for (const auto& e : r.events) held = held || (e.source == "hand" && e.name == "held");
  EXPECT_TRUE(held);

  // In step: on every SYNC, every drive took a set-point, all six the trajectory's positions at one
  // time (to the count), and those times go forward.
  const auto trajectory = Plan::trajectory();
  std::vector<fba::emulators::SyncSetPoints> cyclic;
  for (const auto& s : arm->set_points())
    if (s.mode == 8) cyclic.push_back(s);
  ASSERT_GE(cyclic.size(), 100u);  // 5 s of trajectory, a SYNC every 20 ms
  std::vector<double> times;
  for (const auto& s : cyclic) {
    ASSERT_EQ(s.set_points.size(), 6u) << "SYNC " << s.sync << ": a drive took no set-point";
    const auto [time, error] = on_trajectory(trajectory, s);
    EXPECT_LE(error, 1.0) << "SYNC " << s.sync << ": the drives' set-points are not the trajectory's at one time";
    if (!times.empty()) EXPECT_GE(time, times.back() - 1e-6) << "SYNC " << s.sync;
    times.push_back(time);
  }
  const auto& last = trajectory.points.back().positions;
  for (int node = 1; node <= 6; ++node) {
    EXPECT_NEAR(cyclic.back().set_points[static_cast<std::size_t>(node - 1)].second, last[node - 1] * kCounts, 1.0);
    EXPECT_NEAR(arm->position(node), last[node - 1] * kCounts, 1.0) << "node " << node << " arrived elsewhere";
  }
  // The hand: open, then close, in that order; the open before the approach began, the close once
  // the approach had begun and before the lift did (ordered by when each device heard it).
  std::vector<fba::emulators::Robotiq3fEmulator::CommandSeen> moves;
  for (const auto& c : hand.emulator().commands())
    if (c.go()) moves.push_back(c);
  ASSERT_GE(moves.size(), 2u);
  EXPECT_LT(moves[0].request_a(), 255);
  EXPECT_EQ(moves[1].request_a(), 255);
  auto first_sync_past = [&](double t) {
    for (std::size_t i = 0; i < cyclic.size(); ++i)
      if (times[i] > t) return cyclic[i].when;
    return Clock::time_point::max();
  };
  EXPECT_LT(moves[0].when, first_sync_past(Plan::kApproachStart + 0.02)) << "the hand opened after the approach began";
  EXPECT_GT(moves[1].when, first_sync_past(Plan::kApproachStart + 0.02)) << "the hand closed before the approach";
  EXPECT_LT(moves[1].when, first_sync_past(Plan::kLiftStart + 0.02)) << "the hand closed after the lift began";
  for (const auto* device : {"arm", "hand"}) {
    const auto* s = safe_state_of(r.safe_states, device);
    ASSERT_TRUE(s) << device;
    EXPECT_EQ(s->status, "reached") << device << ": " << s->message;
  }
}

// One drive stops taking its set-points mid-trajectory: every joint is quick-stopped on that SYNC,
// the run ends as a runtime error (exit 3) naming the drive, and both safe states are reached
// (the drives quick-stopped, the hand opened).
TEST(GraspEmulatedReach, ADriveThatStopsTakingItsSetPointsEndsTheRunWithEveryJointStoppedAndTheHandOpened) {
  const fba::test::TempDir dir;
  fba::test::EmulatedCanopenArm arm;
  fba::test::EmulatedHand hand(stalling_hand());
  std::atomic<bool> done{false};
  std::thread fault([&] {  // well into the approach, however slowly the machine runs
    while (!done) {
      std::size_t cyclic = 0;
      for (const auto& s : arm->set_points()) cyclic += s.mode == 8;
      if (cyclic >= 60) {
        arm->ignore_set_points(3);
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  fba::RunOptions options;
  options.timeout_s = 600;
  fba::Task task(fba::load_task_text(reach_task(arm.device(), hand.device()), "reach.yaml", dir.path(), registry()), options);
  const auto r = task.run();
  done = true;
  fault.join();
  EXPECT_EQ(r.outcome, fba::Outcome::RuntimeError) << r.reason;
  EXPECT_EQ(r.exit_code(), 3);
  EXPECT_NE(r.reason.find("hw.canopen_arm on " + arm.device()), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("joint 'elbow_joint' (node 3): does not follow its set-point"), std::string::npos) << r.reason;
  for (int node : {1, 2, 4, 5, 6}) EXPECT_TRUE(arm.quick_stopped(node)) << "node " << node;
  for (const auto* device : {"arm", "hand"}) {
    const auto* s = safe_state_of(r.safe_states, device);
    ASSERT_TRUE(s) << device;
    EXPECT_EQ(s->status, "reached") << device << ": " << s->message;
  }
  const auto commands = hand.emulator().commands();
  ASSERT_FALSE(commands.empty());
  EXPECT_TRUE(commands.back().go());
  EXPECT_EQ(commands.back().request_a(), 0) << "the hand's last command was not to open";
  // The figures: from the SYNC the drive missed to the last quick stop the drives heard, and to the
  // hand's open.
  Clock::time_point missed{};
  for (const auto& s : arm->set_points())
    if (s.mode == 8 && s.set_points.size() < 6) {
      missed = s.when;
      break;
    }
  ASSERT_NE(missed, Clock::time_point{});
  const auto heard = arm->heard();
  const auto at = arm->heard_at();
  Clock::time_point stopped{};
  for (int node = 1; node <= 6; ++node) {
    const long i = fba::test::last_quick_stop(heard, node);
    ASSERT_GE(i, 0) << "node " << node;
    stopped = std::max(stopped, at[static_cast<std::size_t>(i)]);
  }
  EXPECT_GT(stopped, missed);
  std::cout << "measured: a set-point missed (SYNC) to every drive's quick stop heard: " << ms(stopped - missed)
            << " ms; to the hand's open: " << ms(commands.back().when - missed) << " ms\n";
}

namespace {

// fba-run on tasks/grasp.yaml --profile emulated at the emulators given (none started by the
// drivers), to its end.
fba::test::Result run_emulated(const std::string& arm_device, const std::string& hand_device,
                               const std::filesystem::path& out) {
  return fba::test::fba_run({fba::test::tasks_dir() + "/grasp.yaml", "--profile", "emulated", "--set",
                             "arm_bus=" + arm_device, "--set", "hand_device=" + hand_device, "--set", "arm_emulator=",
                             "--set", "hand_emulator=", "--output-dir", out.string()});
}

nlohmann::json summary_of(const std::filesystem::path& out) {
  return nlohmann::json::parse(fba::test::read_file(out / "summary.json"), nullptr, false);
}

}  // namespace

// A drive already in fault at start-up: fba-run exits 3 (a runtime error, not the task's
// configuration error), naming the drive and its error code; the fault is not reset and no drive
// is enabled (each was sent its quick stop).
TEST(GraspEmulatedStartUp, ADriveInFaultExits3NamingItAndItsErrorCodeWithNoDriveEnabled) {
  const fba::test::TempDir dir;
  fba::emulators::CanopenArmOptions o;
  o.fault_at_start = {{3, 0x7121}};
  fba::test::EmulatedCanopenArm arm(o);
  fba::test::EmulatedHand hand;
  const auto r = run_emulated(arm.device(), hand.device(), dir.path() / "out");
  EXPECT_EQ(r.status, 3) << r.output;
  EXPECT_NE(r.output.find("could not start its device: hw.canopen_arm on " + arm.device()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("joint 'elbow_joint' (node 3): the drive is in fault at start-up, error code 0x7121 (motor blocked)"),
            std::string::npos)
      << r.output;
  EXPECT_TRUE(arm.in_fault(3));
  for (int node = 1; node <= 6; ++node) EXPECT_FALSE(arm.enabled(node)) << "node " << node;
  const auto summary = summary_of(dir.path() / "out");
  ASSERT_TRUE(summary.is_object()) << r.output;
  EXPECT_EQ(summary["safe_states"]["hand"]["status"], "not constructed") << summary.dump(2);
  // The figure: from the request that read the error code to the last quick stop heard.
  const auto heard = arm->heard();
  const auto at = arm->heard_at();
  long read = -1;
  for (long i = 0; i < static_cast<long>(heard.size()); ++i) {
    const auto& f = heard[static_cast<std::size_t>(i)];
    if (f.id == 0x603 && f.data[0] == 0x40 && f.data[1] == 0x3F && f.data[2] == 0x60) read = i;
  }
  ASSERT_GE(read, 0);
  Clock::time_point stopped{};
  for (int node = 1; node <= 6; ++node) {
    const long i = fba::test::last_quick_stop(heard, node);
    ASSERT_GT(i, read) << "node " << node;
    stopped = std::max(stopped, at[static_cast<std::size_t>(i)]);
  }
  std::cout << "measured: a drive in fault at start-up, its error code read to every drive's quick stop heard: "
            << ms(stopped - at[static_cast<std::size_t>(read)]) << " ms\n";
}

// The hand fails to start after the arm did: exit 3 naming the gripper, the gripper reset when it
// hears the line, and the arm's safe state reached (its drives quick-stopped).
TEST(GraspEmulatedStartUp, AGripperThatNeverActivatesOrIsOnAnotherSlaveIdExits3WithTheArmQuickStopped) {
  for (const bool activates : {false, true}) {
    const fba::test::TempDir dir;
    fba::test::EmulatedCanopenArm arm;
    auto o = fba::test::EmulatedHand::quick();
    o.activates = activates;
    if (activates) o.slave_id = 10;  // the driver asks slave 9: nobody answers
    fba::test::EmulatedHand hand(o);
    const auto out = dir.path() / "out";
    const auto r = fba::test::fba_run({fba::test::tasks_dir() + "/grasp.yaml", "--profile", "emulated", "--set",
                                       "arm_bus=" + arm.device(), "--set", "hand_device=" + hand.device(), "--set",
                                       "arm_emulator=", "--set", "hand_emulator=", "--set", "hand.activation_timeout=1",
                                       "--output-dir", out.string()});
    EXPECT_EQ(r.status, 3) << r.output;
    EXPECT_NE(r.output.find("could not start its device: Robotiq 3-Finger gripper on " + hand.device()), std::string::npos)
        << r.output;
    const auto summary = summary_of(out);
    ASSERT_TRUE(summary.is_object()) << r.output;
    EXPECT_EQ(summary["safe_states"]["arm"]["status"], "reached") << summary.dump(2);
    for (int node = 1; node <= 6; ++node) EXPECT_TRUE(arm.quick_stopped(node)) << "node " << node;
    const auto commands = hand.emulator().commands();
    if (!activates) {
      EXPECT_NE(r.output.find("activation: not done within 1 s"), std::string::npos) << r.output;
      EXPECT_NE(r.output.find("the gripper was reset (rACT = 0): stopped"), std::string::npos) << r.output;
      ASSERT_GE(commands.size(), 2u);
      EXPECT_EQ((commands.back().registers[0] >> 8) & 0x01, 0) << "the last command was not a reset";
      // The figure: activation given up (its command + the 1 s timeout) to the reset heard.
      const auto activation = commands[commands.size() - 2].when;
      std::cout << "measured: a gripper that never activates, activation_timeout ended to its reset heard: "
                << ms(commands.back().when - activation) - 1000.0 << " ms\n";
    } else {
      EXPECT_NE(r.output.find("(slave 9)"), std::string::npos) << r.output;
      EXPECT_NE(r.output.find("no answer"), std::string::npos) << r.output;
      EXPECT_TRUE(commands.empty()) << "slave 10 heard a command for slave 9";
    }
  }
}
