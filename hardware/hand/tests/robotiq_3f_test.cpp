// hw.robotiq_3f through the component harness, against the gripper emulator on a pseudo-terminal:
// libmodbus's real serial code on both ends. Activation, grasps that hold and grasps that do not,
// and each fault ending in a report that names the device and the reason, never a hang.
#include "fba/emulators/robotiq_3f.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <iostream>
#include <fba/task.hpp>
#include <fba/testing.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/hand_command.hpp>
#include <fba/types/joint_trajectory.hpp>
#include <fba/types/grasp_execution.hpp>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <thread>

#include "support/emulated_hand.hpp"
#include "support/built_plugins.hpp"
#include "support/events.hpp"
#include "support/temp_dir.hpp"

using fba::emulators::Robotiq3fEmulator;
using fba::emulators::Robotiq3fOptions;
using fba::testing::ComponentHarness;

namespace {

using fba::test::built_plugins;
using fba::test::named;

using fba::test::EmulatedHand;

// Generous answer times: the emulator's thread may wait for a core on a loaded machine.
fba::testing::Params params(const std::string& device, fba::testing::Params more = {}) {
  fba::testing::Params p{
      {"device", device}, {"response_timeout", 2.0}, {"retries", 1}, {"poll_period", 0.01}, {"hold_time", 0.2}};
  for (auto& [k, v] : more) p[k] = v;
  return p;
}

// hw.robotiq_3f on `hand`'s line with the tests' parameters and `more`, the inputs `optional`
// connected: every test's driver, so that each reads as what it checks.
ComponentHarness driver(EmulatedHand& hand, fba::testing::Params more = {}, const std::vector<std::string>& optional = {}) {
  return ComponentHarness(built_plugins(), "hw.robotiq_3f", params(hand.device(), std::move(more)), optional);
}

// A grasp of the emulator's default object (0.06 m across, centred): 0.1 m open, fingers 0.03 m apart.
fba::Grasp grasp(double aperture = 0.1, double spread = 0.03) {
  fba::Grasp g;
  g.contacts[0].position = {0.03, 0, 0.05};
  g.contacts[1].position = {-0.026, 0.015, 0.05};
  g.contacts[2].position = {-0.026, -0.015, 0.05};
  g.aperture = aperture;
  g.spread = spread;
  return g;
}

// Takes the grasp `g` to its end and gives its one result; the test fails, with a default result,
// when the run processes other than one sample or gives other than one result.
fba::GraspExecution result_of(ComponentHarness& h, const fba::Grasp& g) {
  h.push("grasp", g);
  EXPECT_EQ(h.run(), 1);
  const auto results = h.values<fba::GraspExecution>("result");
  EXPECT_EQ(results.size(), 1u);
  return results.size() == 1 ? results[0] : fba::GraspExecution{};
}

// Takes the grasp `g` and gives the driver's failure ("" for none): for the faults, which end it.
std::string failure_of(ComponentHarness& h, const fba::Grasp& g) {
  h.push("grasp", g);
  h.run();
  return h.failure();
}

// Why safe_state() could not reach the hand; a safe state that returns is a test failure.
std::string safe_state_error(ComponentHarness& h) {
  try {
    h.safe_state();
  } catch (const std::exception& e) {
    return e.what();
  }
  ADD_FAILURE() << "safe_state() reached the gripper";
  return {};
}

// Runs `action` once the emulator's state satisfies `when` (polled), from a thread of its own.
class When {
 public:
  When(Robotiq3fEmulator& emu, std::function<bool(const Robotiq3fEmulator::State&)> when, std::function<void()> action)
      : thread_([&emu, when = std::move(when), action = std::move(action), this] {
          while (!cancel_ && !when(emu.state())) std::this_thread::sleep_for(std::chrono::milliseconds(1));
          if (!cancel_) action();
        }) {}
  ~When() {
    cancel_ = true;
    thread_.join();
  }

 private:
  std::atomic<bool> cancel_{false};
  std::thread thread_;
};

bool closing(const Robotiq3fEmulator::State& s) { return s.go && s.axes[0].request == 255 && s.axes[0].position > 1; }

}  // namespace

TEST(Robotiq3fSpec, PortsAndEventsAreSimHands) {
  const auto real = built_plugins().find("hw.robotiq_3f");
  ASSERT_TRUE(real);
  const auto sim = built_plugins().find("sim.hand");
  if (!sim) GTEST_SKIP() << "sim.hand is not built here (no MuJoCo, or a ThreadSanitizer build): nothing to compare with";
  auto ports = [](const std::vector<fba::PortSpec>& list) {
    std::vector<std::tuple<std::string, std::string, bool>> out;
    for (const auto& p : list) out.emplace_back(p.name, p.type->name, p.required);
    return out;
  };
  auto events = [](const fba::Spec& s) {
    std::vector<std::string> out;
    for (const auto& e : s.events()) out.push_back(e.name);
    return out;
  };
  EXPECT_EQ(ports(real->spec.inputs()), ports(sim->spec.inputs()));
  EXPECT_EQ(ports(real->spec.outputs()), ports(sim->spec.outputs()));
  EXPECT_EQ(events(real->spec), events(sim->spec));
}

TEST(Robotiq3f, ActivatesWhenTheTaskStarts) {
  EmulatedHand hand;
  auto h = driver(hand);
  const auto s = hand.emulator().state();
  EXPECT_TRUE(s.activated);
  EXPECT_EQ(s.imc, 3);
  EXPECT_EQ(s.mode, 0);  // auto runs in basic mode
}

TEST(Robotiq3f, GraspThatTouchesTheObjectWithEveryFingerIsHeld) {
  EmulatedHand hand;
  auto h = driver(hand);
  const auto result = result_of(h, grasp());
  ASSERT_EQ(h.failure(), "");
  EXPECT_TRUE(result.held) << result.reason;
  ASSERT_EQ(result.contacts.size(), 3u);
  EXPECT_EQ(result.contacts[0].link, "finger_a");
  EXPECT_EQ(result.contacts[0].position, grasp().contacts[0].position);
  EXPECT_GE(result.hold_s, 0.2);
  ASSERT_EQ(named(h.events(), "held").size(), 1u);
  const auto payload = nlohmann::json::parse(named(h.events(), "held")[0].payload);
  EXPECT_EQ(payload["fingers"][0]["object"], "stopped by contact while closing");
  // The fingers stopped on the object, not at the request: thumb 0.03 m from the centre.
  const auto s = hand.emulator().state();
  EXPECT_NEAR(s.axes[0].position, 255 * (1 - 0.03 / 0.0775), 1.0);
  EXPECT_EQ(s.axes[0].request, 255);
  // The spread set the scissor (individual scissor control): 0.03 of 0.12 m.
  EXPECT_EQ(s.axes[3].request, std::lround(255 * (1 - 0.03 / 0.12)));
}

TEST(Robotiq3f, GraspWithNothingBetweenTheFingersIsNotHeldAndSaysWhy) {
  auto options = EmulatedHand::quick();
  options.object = false;
  EmulatedHand hand(options);
  auto h = driver(hand);
  const auto result = result_of(h, grasp());
  ASSERT_EQ(h.failure(), "");
  EXPECT_FALSE(result.held);
  EXPECT_NE(result.reason.find("no contact: the fingers closed without touching anything"), std::string::npos)
      << result.reason;
  EXPECT_TRUE(result.contacts.empty());
  EXPECT_EQ(named(h.events(), "dropped").size(), 1u);
}

TEST(Robotiq3f, SpreadWiderThanTheObjectMissesWithFingersBAndC) {
  EmulatedHand hand;
  auto h = driver(hand);
  const auto result = result_of(h, grasp(0.1, 0.1));  // B and C 0.1 m apart pass beside a 0.06 m object
  EXPECT_FALSE(result.held);
  EXPECT_NE(result.reason.find("no contact on B, C"), std::string::npos) << result.reason;
  ASSERT_EQ(result.contacts.size(), 1u);
  EXPECT_EQ(result.contacts[0].link, "finger_a");
}

TEST(Robotiq3f, AnObjectLongAlongTheSpreadMeetsFingersBAndCWhereARoundOneDoesNot) {
  Robotiq3fOptions options = EmulatedHand::quick();
  options.object_length = 0.19;  // a bottle held across, B and C along its height
  EmulatedHand hand(options);
  auto h = driver(hand);
  const auto result = result_of(h, grasp(0.1, 0.1));  // the spread that passes beside the 0.06 m cylinder above
  ASSERT_EQ(h.failure(), "");
  EXPECT_TRUE(result.held) << result.reason;
  EXPECT_EQ(result.contacts.size(), 3u);
}

TEST(Robotiq3f, ObjectSlippingOutDuringTheHoldIsDropped) {
  EmulatedHand hand;
  // A long hold: the object slips out during it however slowly this machine runs.
  auto h = driver(hand, {{"hold_time", 60.0}});
  // The object slips out once the driver holds: two status answers after every finger touched, the
  // first of which ended the close, so the second was the hold's.
  std::uint64_t touched_at = 0;
  When slip(
      hand.emulator(),
      [&touched_at](const auto& s) {
        const bool touching = s.axes[0].contact == 2 && s.axes[1].contact == 2 && s.axes[2].contact == 2;
        if (touching && touched_at == 0) touched_at = s.requests;
        return touched_at != 0 && s.requests >= touched_at + 2;
      },
      [&] { hand.emulator().remove_object(); });
  const auto result = result_of(h, grasp());
  EXPECT_FALSE(result.held);
  EXPECT_NE(result.reason.find("dropped: finger"), std::string::npos) << result.reason;
  EXPECT_NE(result.reason.find("lost its contact"), std::string::npos) << result.reason;
  EXPECT_EQ(named(h.events(), "dropped").size(), 1u);
}

TEST(Robotiq3f, ScissorModePinchesBetweenFingersBAndC) {
  EmulatedHand hand;
  auto h = driver(hand, {{"mode", std::string("scissor")}});
  EXPECT_EQ(hand.emulator().state().mode, 3);
  const auto result = result_of(h, grasp());
  EXPECT_TRUE(result.held) << result.reason;
  ASSERT_EQ(result.contacts.size(), 1u);
  EXPECT_EQ(result.contacts[0].link, "scissor");
}

TEST(Robotiq3f, SafeStateStopsThenOpens) {
  EmulatedHand hand;
  auto h = driver(hand);
  h.push("grasp", grasp());
  ASSERT_EQ(h.run(), 1);
  h.safe_state();
  const auto s = hand.emulator().state();
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_EQ(s.axes[axis].request, 0);
    EXPECT_EQ(s.axes[axis].position, 0);
  }
}

// hw.robotiq_3f declares concurrent_safe_state(): the runtime calls safe_state() beside a process()
// still running. The line carries one request at a time: the safe state takes it between two of
// process()'s requests, so the stop and the open reach the hand while the fingers are still closing
// (no interrupt() first), and process() ends there.
TEST(Robotiq3f, SafeStateStopsAndOpensTheHandWhileAGraspIsStillClosing) {
  auto options = EmulatedHand::quick();
  options.speed_scale = 0.01;  // a close of most of a minute
  EmulatedHand hand(options);
  auto h = driver(hand, {{"motion_timeout", 120.0}, {"safe_state_timeout", 60.0}});
  h.push("grasp", grasp(0.155));  // fully open already: the pregrasp does not move the fingers
  std::atomic<bool> returned{false};
  std::jthread grasping([&] {
    h.run();
    returned = true;
  });
  while (!closing(hand.emulator().state()) && !returned) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  ASSERT_FALSE(returned) << h.failure();
  EXPECT_NO_THROW(h.safe_state());
  grasping.join();
  EXPECT_NE(h.failure().find("closing"), std::string::npos) << h.failure();
  EXPECT_NE(h.failure().find("the safe state has the line"), std::string::npos) << h.failure();
  EXPECT_TRUE(named(h.events(), "held").empty());
  EXPECT_TRUE(named(h.events(), "dropped").empty());
  // The order the hand heard the commands in: the close, then the stop and the open, with the
  // fingers still closing when the stop came.
  const auto commands = hand.emulator().commands();
  std::size_t close = 0;
  while (close < commands.size() && !(commands[close].go() && commands[close].request_a() == 255)) ++close;
  ASSERT_LT(close, commands.size()) << "no close command";
  std::size_t stop = close + 1;
  while (stop < commands.size() && commands[stop].go()) ++stop;
  ASSERT_LT(stop, commands.size()) << "no stop after the close";
  const auto& then = commands[stop].before;
  EXPECT_TRUE(then.go);
  EXPECT_EQ(then.axes[0].contact, 0) << "finger A had stopped";
  EXPECT_LT(then.axes[0].position, 255);
  ASSERT_LT(stop + 1, commands.size()) << "no open after the stop";
  EXPECT_TRUE(commands[stop + 1].go());
  EXPECT_EQ(commands[stop + 1].request_a(), 0);
  EXPECT_EQ(stop + 2, commands.size()) << "a command after the safe state's";
}

// --- Faults: each ends in a report naming the device and the reason, and safe_state() returns.

TEST(Robotiq3fFaults, GripperThatStopsAnsweringIsATimeoutNamingTheDevice) {
  EmulatedHand hand;
  // A long hold: the fault comes before the grasp could end, however slowly this machine runs.
  auto h = driver(hand, {{"hold_time", 60.0}});
  When silence(hand.emulator(), closing, [&] { hand.emulator().silence(); });
  const std::string failure = failure_of(h, grasp());
  EXPECT_NE(failure.find(hand.device()), std::string::npos) << failure;
  EXPECT_NE(failure.find("no answer within 2 s (Modbus timeout"), std::string::npos) << failure;
  EXPECT_NE(failure.find("2 tries"), std::string::npos) << failure;
  // The hand cannot be reached: safe_state() says so, in bounded time, rather than waiting.
  const std::string why = safe_state_error(h);
  EXPECT_NE(why.find(hand.device()), std::string::npos) << why;
  EXPECT_NE(why.find("safe state (stop)"), std::string::npos) << why;
}

TEST(Robotiq3fFaults, LineThatDisappearsMidMotionIsReportedAtOnce) {
  EmulatedHand hand;
  // A long hold: the fault comes before the grasp could end, however slowly this machine runs.
  auto h = driver(hand, {{"hold_time", 60.0}});
  When pull(hand.emulator(), closing, [&] { hand.emulator().disconnect(); });
  const std::string failure = failure_of(h, grasp());
  EXPECT_NE(failure.find(hand.device()), std::string::npos) << failure;
  EXPECT_NE(failure.find("the serial line is gone"), std::string::npos) << failure;
  const std::string why = safe_state_error(h);
  EXPECT_NE(why.find("the serial line is gone"), std::string::npos) << why;
}

TEST(Robotiq3fFaults, AnswersWithBadCrcsFailTheGraspThenTheSafeStateIsReached) {
  EmulatedHand hand;
  auto h = driver(hand);
  hand.emulator().corrupt_replies(-1);
  const std::string failure = failure_of(h, grasp());
  EXPECT_NE(failure.find(hand.device()), std::string::npos) << failure;
  EXPECT_NE(failure.find("CRC was wrong"), std::string::npos) << failure;
  hand.emulator().corrupt_replies(0);  // the noise stops: the hand stops and opens
  h.safe_state();
  const auto s = hand.emulator().state();
  EXPECT_TRUE(s.go);
  EXPECT_EQ(s.axes[0].request, 0);
}

TEST(Robotiq3fFaults, OneBurstOfGarbageIsRetriedAndTheGraspHolds) {
  EmulatedHand hand;
  auto h = driver(hand);
  hand.emulator().inject_garbage();
  const auto result = result_of(h, grasp());
  ASSERT_EQ(h.failure(), "");
  EXPECT_TRUE(result.held) << result.reason;
}

TEST(Robotiq3fFaults, FaultCodeFromTheGripperNamesTheFaultAndTheHandStops) {
  EmulatedHand hand;
  // A long hold: the fault comes before the grasp could end, however slowly this machine runs.
  auto h = driver(hand, {{"hold_time", 60.0}});
  When fault(hand.emulator(), closing, [&] { hand.emulator().inject_fault(0x0D); });
  const std::string failure = failure_of(h, grasp());
  EXPECT_NE(failure.find(hand.device()), std::string::npos) << failure;
  EXPECT_NE(failure.find("fault 0x0D activation fault"), std::string::npos) << failure;
  h.safe_state();  // a fault that needs a reset: stopped, not opened
  EXPECT_FALSE(hand.emulator().state().go);
}

TEST(Robotiq3fFaults, GraspOutsideTheHandsRangeIsRefusedBeforeAnythingIsSent) {
  EmulatedHand hand;
  for (const auto& [bad, why] : std::vector<std::pair<fba::Grasp, std::string>>{
           {grasp(0.5, 0.03), "aperture must be in (0, 0.155 m]"},
           {grasp(0.1, 0.2), "spread must be in [0, 0.12 m]"},
           {grasp(std::numeric_limits<double>::quiet_NaN(), 0.03), "aperture must be in"},
           {grasp(0.1, -0.01), "spread must be in"}}) {
    auto h = driver(hand);
    const auto before = hand.emulator().state().requests;
    const std::string failure = failure_of(h, bad);
    EXPECT_NE(failure.find(hand.device()), std::string::npos) << failure;
    EXPECT_NE(failure.find("refused before sending"), std::string::npos) << failure;
    EXPECT_NE(failure.find(why), std::string::npos) << failure;
    EXPECT_EQ(hand.emulator().state().requests, before);
  }
}

// A device that fails to start is a device error (a runtime error, exit 3 from fba-run), not the
// task's configuration error, and it names the device.
TEST(Robotiq3fFaults, GripperOnAnotherSlaveIdFailsTheStartNamingTheDevice) {
  EmulatedHand hand;
  try {
    auto h = driver(hand, {{"slave_id", 10}});
    FAIL() << "started without a gripper on slave 10";
  } catch (const fba::ConstructionError& e) {
    EXPECT_EQ(e.outcome(), fba::Outcome::RuntimeError) << e.what();
    EXPECT_NE(std::string(e.what()).find("could not start its device"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("(slave 10)"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no answer"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("it never answered, so nothing was sent to stop it"), std::string::npos)
        << e.what();
  }
}

TEST(Robotiq3fFaults, MissingSerialLineFailsTheStartNamingIt) {
  fba::test::TempDir dir;
  const std::string device = dir.file("ttyUSB9");
  try {
    ComponentHarness h(built_plugins(), "hw.robotiq_3f", params(device));
    FAIL() << "started on a serial line that does not exist";
  } catch (const fba::ConstructionError& e) {
    EXPECT_EQ(e.outcome(), fba::Outcome::RuntimeError) << e.what();
    EXPECT_NE(std::string(e.what()).find(device), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot open the serial line"), std::string::npos) << e.what();
  }
}

// The start's other failures: each a device error naming the device, and the gripper, which hears
// the line, reset (rACT = 0) after it: the last command it saw.
TEST(Robotiq3fFaults, AGripperThatNeverActivatesReportsAFaultOrAnswersGarbledIsResetAndADeviceError) {
  auto start_failure = [](EmulatedHand& hand, fba::testing::Params more = {}) {
    try {
      auto h = driver(hand, std::move(more));
    } catch (const fba::ConstructionError& e) {
      EXPECT_EQ(e.outcome(), fba::Outcome::RuntimeError) << e.what();
      EXPECT_NE(std::string(e.what()).find("could not start its device: Robotiq 3-Finger gripper on " + hand.device()),
                std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("reset (rACT = 0)"), std::string::npos) << e.what();
      const auto seen = hand.emulator().commands();
      EXPECT_FALSE(seen.empty());
      if (!seen.empty()) EXPECT_EQ((seen.back().registers[0] >> 8) & 0x01, 0) << "the last command was not a reset";
      return std::string(e.what());
    }
    ADD_FAILURE() << "the gripper started";
    return std::string();
  };
  // The figures (measured, not asserted): from the failure to the reset the gripper heard.
  using Clock = std::chrono::steady_clock;
  auto figure = [](const std::string& what, Clock::duration d) {
    std::cout << "measured: " << what << " to the reset heard: " << std::chrono::duration<double, std::milli>(d).count()
              << " ms\n";
  };
  {
    Robotiq3fOptions o = EmulatedHand::quick();
    o.activates = false;
    EmulatedHand hand(o);
    EXPECT_NE(start_failure(hand, {{"activation_timeout", 0.3}}).find("activation: not done within 0.3 s"),
              std::string::npos);
    const auto seen = hand.emulator().commands();
    if (seen.size() >= 2)
      figure("a gripper that never activates, activation_timeout (0.3 s) ended", seen.back().when - seen[seen.size() - 2].when -
                                                                                    std::chrono::milliseconds(300));
  }
  {
    Robotiq3fOptions o = EmulatedHand::quick();
    o.activation_s = 60;  // the fault comes first
    EmulatedHand hand(o);
    std::atomic<Clock::rep> injected{0};
    {
      When fault(hand.emulator(), [](const Robotiq3fEmulator::State& s) { return s.imc == 1; }, [&] {
        hand.emulator().inject_fault(0x0D);
        injected = Clock::now().time_since_epoch().count();
      });
      EXPECT_NE(start_failure(hand).find("fault 0x0D activation fault"), std::string::npos);
    }
    EXPECT_EQ(hand.emulator().state().fault, 0) << "the reset clears it";
    figure("a fault code during activation (polled every 0.01 s), from the fault",
           hand.emulator().commands().back().when - Clock::time_point(Clock::duration(injected.load())));
  }
  {
    EmulatedHand hand;
    hand.emulator().corrupt_replies(-1);
    EXPECT_NE(start_failure(hand).find("the answer's CRC was wrong"), std::string::npos);
    const auto seen = hand.emulator().commands();
    figure("answers with bad CRCs, from the first request (found after its 2 tries)", seen.back().when - seen.front().when);
  }
}

namespace {

// A reach plan's hand command: open to `opening` with the fingers `spread` apart, or close with
// `force` newtons, at `time` on the trajectory.
fba::HandCommand command(fba::HandCommand::Action action, double time, double force = 30,
                         fba::HandCommand::Mode mode = fba::HandCommand::Mode::Basic) {
  fba::HandCommand c;
  c.action = action;
  c.mode = mode;
  c.opening = 0.1;
  c.spread = 0.03;
  c.force = force;
  c.time = time;
  return c;
}

fba::JointTrajectory trajectory_of(double seconds) {
  fba::JointTrajectory t;
  t.names = {"j"};
  t.points = {{0.0, {0.0}, {0.0}}, {seconds, {0.0}, {0.0}}};
  return t;
}

constexpr std::int64_t kSecond = 1'000'000'000;
using Action = fba::HandCommand::Action;

// The emulator's gripper holds whatever it closes on at 0.07 m.
Robotiq3fOptions stalling() {
  Robotiq3fOptions o = EmulatedHand::quick();
  o.stall_aperture = 0.07;
  return o;
}

}  // namespace

// The commands of a reach plan at their times on the trajectory's clock (which starts when the
// trajectory arrives): each runs once the task's clock has reached its time, in order; the open
// maps the opening and spread to the fingers' and the scissor's positions, the close its force
// onto the gripper's 15..60 N, and the close ends held with every finger stalled on the object.
TEST(Robotiq3fCommands, RunInOrderAtTheirTimesOnTheTrajectoryAndACloseEndsHeld) {
  EmulatedHand hand(stalling());
  auto h = driver(hand, {}, {"commands", "trajectory"});
  const auto before = hand.emulator().commands().size();
  h.push("trajectory", trajectory_of(3.0));
  h.push("commands", command(Action::Open, 0.0));
  h.push("commands", command(Action::Close, 1.0, 30));
  h.push("commands", command(Action::Open, 2.0));
  ASSERT_TRUE(h.step());  // the trajectory, and the open at 0 s: now
  ASSERT_TRUE(h.failure().empty()) << h.failure();
  h.set_time(1 * kSecond);
  ASSERT_TRUE(h.step());  // the close at 1 s
  ASSERT_TRUE(h.failure().empty()) << h.failure();
  ASSERT_EQ(named(h.events(), "held").size(), 1u) << (h.events().empty() ? "" : h.events().back().payload);
  h.set_time(2 * kSecond);
  ASSERT_TRUE(h.step());  // the open at 2 s: the release
  ASSERT_TRUE(h.failure().empty()) << h.failure();
  EXPECT_TRUE(named(h.events(), "dropped").empty());

  // What reached the gripper, in order: open, close, open.
  std::vector<Robotiq3fEmulator::CommandSeen> moves;
  const auto seen = hand.emulator().commands();
  for (std::size_t i = before; i < seen.size(); ++i)
    if (seen[i].go()) moves.push_back(seen[i]);
  ASSERT_EQ(moves.size(), 3u);
  auto byte = [](const Robotiq3fEmulator::CommandSeen& c, int k) {
    return (k % 2 == 0) ? c.registers[k / 2] >> 8 : c.registers[k / 2] & 0xFF;
  };
  const int open = static_cast<int>(std::lround(255 * (1 - 0.1 / 0.155)));  // 0.1 m of the 0.155 m stroke
  for (int finger = 0; finger < 3; ++finger) {
    EXPECT_EQ(byte(moves[0], 3 + 3 * finger), open) << "finger " << finger;
    EXPECT_EQ(byte(moves[1], 3 + 3 * finger), 255) << "finger " << finger;
    EXPECT_EQ(byte(moves[1], 5 + 3 * finger), std::lround(255 * (30 - 15) / 45.0)) << "finger " << finger;  // 30 N
    EXPECT_EQ(byte(moves[2], 3 + 3 * finger), open) << "finger " << finger;
  }
  EXPECT_EQ(byte(moves[0], 12), std::lround(255 * (1 - 0.03 / 0.12)));  // the scissor: B and C 0.03 m apart
  EXPECT_EQ(byte(moves[0], 1) & 0x08, 0x08);                             // individual scissor control
  // Held: the close's result names every finger in contact.
  const auto held = nlohmann::json::parse(named(h.events(), "held")[0].payload);
  EXPECT_TRUE(held["held"].get<bool>());
  EXPECT_EQ(held["contacts"].size(), 3u);
  EXPECT_EQ(hand.emulator().state().axes[0].request, open);  // released at the end
}

// A command waits for its time: the task's clock has not reached it, the close does not go out,
// and a stop ends the wait at once with nothing sent.
TEST(Robotiq3fCommands, ACommandWaitsForItsTimeAndAStopEndsTheWaitWithNothingSent) {
  EmulatedHand hand(stalling());
  auto h = driver(hand, {}, {"commands", "trajectory"});
  h.push("trajectory", trajectory_of(1000.0));
  h.push("commands", command(Action::Close, 900.0));
  const auto before = hand.emulator().commands().size();
  std::atomic<bool> returned{false};
  std::thread run([&] {
    h.step();
    returned = true;
  });
  // However long the test looks, the close is 900 s away: nothing reaches the gripper meanwhile.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_FALSE(returned);
  EXPECT_EQ(hand.emulator().commands().size(), before);
  h.interrupt();  // as the runtime does at a stop: the wait ends at once
  run.join();
  EXPECT_TRUE(returned);
  EXPECT_EQ(hand.emulator().commands().size(), before) << "a command went out before its time";
  EXPECT_TRUE(named(h.events(), "held").empty());
}

TEST(Robotiq3fCommands, AModeCommandChangesTheGripperModeAndAWeakCloseUsesItsLeastForce) {
  EmulatedHand hand(stalling());
  auto h = driver(hand, {}, {"commands"});
  h.push("commands", command(Action::Open, 0.0, 0, fba::HandCommand::Mode::Pinch));
  h.push("commands", command(Action::Close, 0.5, 10, fba::HandCommand::Mode::Pinch));  // no trajectory: as they come
  h.run();
  ASSERT_TRUE(h.failure().empty()) << h.failure();
  EXPECT_EQ(hand.emulator().state().mode, 1);  // pinch
  const auto seen = hand.emulator().commands();
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back().registers[2] & 0xFF, 0);  // finger A's force: 10 N is below the least, 15 N
  EXPECT_EQ(named(h.events(), "held").size(), 1u);
}

TEST(Robotiq3fCommands, ACommandTheHandCannotMakeOrBeforeItsTrajectoryFailsNamingTheDeviceWithNothingSent) {
  EmulatedHand hand(stalling());
  {
    auto h = driver(hand, {}, {"commands", "trajectory"});
    const auto before = hand.emulator().state().requests;
    h.push("commands", command(Action::Open, 0.0));
    h.run();
    EXPECT_NE(h.failure().find(hand.device()), std::string::npos) << h.failure();
    EXPECT_NE(h.failure().find("before any trajectory"), std::string::npos) << h.failure();
    EXPECT_EQ(hand.emulator().state().requests, before);
  }
  {
    auto h = driver(hand, {}, {"commands"});
    const auto before = hand.emulator().state().requests;
    auto wide = command(Action::Open, 0.0);
    wide.opening = 0.2;
    h.push("commands", wide);
    h.run();
    EXPECT_NE(h.failure().find("hand command (open at 0 s on the trajectory) refused before sending: the opening must "
                               "be in (0, 0.155 m]"),
              std::string::npos)
        << h.failure();
    EXPECT_EQ(hand.emulator().state().requests, before);
  }
}

// With commands connected, a grasp is not executed by itself: it names the planned contacts that
// a close reports.
TEST(Robotiq3fCommands, AGraspAloneMovesNothingWhenCommandsDriveTheHand) {
  EmulatedHand hand(stalling());
  auto h = driver(hand, {}, {"commands"});
  const auto before = hand.emulator().commands().size();
  h.push("grasp", grasp());
  h.run();
  EXPECT_EQ(hand.emulator().commands().size(), before);
  h.push("commands", command(Action::Open, 0.0));
  h.push("commands", command(Action::Close, 0.0));
  h.run();
  ASSERT_EQ(named(h.events(), "held").size(), 1u);
  const auto held = nlohmann::json::parse(named(h.events(), "held")[0].payload);
  EXPECT_NEAR(held["contacts"][0]["position"][0].get<double>(), 0.03, 1e-12);  // the grasp's thumb contact
}
