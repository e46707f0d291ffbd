// hw.robotiq_3f in a running task (the threaded executor, the hand on a thread of its own as a
// blocking actuator) against the emulator: the task ends by its rules on the hand's verdict, and a
// line that disappears mid-close stops it by its error policy with the device and the reason named
// and the safe state attempted.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fba/component.hpp>
#include <fba/registry.hpp>
#include <fba/task.hpp>
#include <fba/task_config.hpp>
#include <fba/types/grasp.hpp>
#include <memory>
#include <stop_token>
#include <thread>

#include "support/built_plugins.hpp"
#include "support/emulated_hand.hpp"
#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"

namespace {

// One grasp, as grasp synthesis would send it.
class GraspSource final : public fba::Component {
 public:
  static constexpr fba::Out<fba::Grasp> kGrasp{"grasp", "one grasp"};
  static constexpr auto kAperture = fba::Param<double>("aperture", 0.1, "metres");
  static constexpr auto kSpread = fba::Param<double>("spread", 0.03, "metres");
  static fba::Spec spec() {
    return fba::Spec::sensor("test.grasp_source", "Emits one grasp.").add(kGrasp, kAperture, kSpread);
  }
  explicit GraspSource(fba::Context& ctx) : ctx_(ctx) {}
  void process() override {
    fba::Grasp g;
    g.aperture = ctx_(kAperture);
    g.spread = ctx_(kSpread);
    ctx_(kGrasp).emit(g);
    ctx_.finish();
  }

 private:
  fba::Context& ctx_;
};
FBA_COMPONENT(GraspSource);

const fba::Registry& registry() {
  static const fba::Registry r = fba::test::built_plugins_and_own("task_test");
  return r;
}

using fba::test::EmulatedHand;

std::string task_yaml(const std::string& device, double aperture, double hold_time = 0.2) {
  return "task: grasp_real_hand\ncomponents:\n"
         "  source: { type: test.grasp_source, params: { aperture: " +
         std::to_string(aperture) +
         " } }\n"
         "  hand: { type: hw.robotiq_3f, params: { device: " +
         device +
         ", response_timeout: 2.0, retries: 1, poll_period: 0.01, hold_time: " + std::to_string(hold_time) + " } }\n"
         "connections:\n  - source.grasp -> hand.grasp\n"
         "on:\n  hand.held: stop_success\n  hand.dropped: stop_failure\n";
}

// The task of task_yaml run to its end, in a folder of its own.
fba::RunResult run_grasp(const std::string& device, double aperture, double hold_time = 0.2) {
  fba::test::TempDir dir;
  fba::Task task(fba::load_task_text(task_yaml(device, aperture, hold_time), "grasp.yaml", dir.path(), registry()));
  return task.run();
}

const fba::SafeStateResult* safe_state_of(const fba::RunResult& r, const std::string& component) {
  for (const auto& s : r.safe_states)
    if (s.component == component) return &s;
  return nullptr;
}

}  // namespace

TEST(Robotiq3fTask, TaskEndsInSuccessWhenTheHandHoldsAndTheHandEndsOpen) {
  EmulatedHand hand;
  const auto result = run_grasp(hand.device(), 0.1);
  EXPECT_EQ(result.outcome, fba::Outcome::Success) << result.reason;
  ASSERT_TRUE(result.final_event);
  EXPECT_EQ(result.final_event->name, "held");
  const auto* safe = safe_state_of(result, "hand");
  ASSERT_TRUE(safe);
  EXPECT_EQ(safe->status, "reached") << safe->message;
  EXPECT_EQ(hand.emulator().state().axes[0].request, 0);  // opened
}

TEST(Robotiq3fTask, GraspOutsideTheHandsRangeStopsTheTaskByItsErrorPolicyNamingTheDevice) {
  EmulatedHand hand;
  const auto result = run_grasp(hand.device(), 0.3);
  EXPECT_EQ(result.outcome, fba::Outcome::RuntimeError) << result.reason;
  EXPECT_NE(result.reason.find(hand.device()), std::string::npos) << result.reason;
  EXPECT_NE(result.reason.find("grasp refused before sending"), std::string::npos) << result.reason;
  const auto* safe = safe_state_of(result, "hand");
  ASSERT_TRUE(safe);
  EXPECT_EQ(safe->status, "reached") << safe->message;
}

TEST(Robotiq3fTask, LineDisappearingMidCloseStopsTheTaskNamingTheDeviceAndTheSafeStateSaysWhyNot) {
  EmulatedHand hand;
  std::atomic<bool> done{false};
  std::thread pull([&] {  // pulls the cable once the fingers are closing
    while (!done) {
      const auto s = hand.emulator().state();
      if (s.go && s.axes[0].request == 255 && s.axes[0].position > 1) {
        hand.emulator().disconnect();
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  // A long hold: the line goes before the grasp could end, however slowly this machine runs.
  const auto result = run_grasp(hand.device(), 0.1, 60);
  done = true;
  pull.join();
  EXPECT_EQ(result.outcome, fba::Outcome::RuntimeError) << result.reason;
  EXPECT_NE(result.reason.find(hand.device()), std::string::npos) << result.reason;
  EXPECT_NE(result.reason.find("the serial line is gone"), std::string::npos) << result.reason;
  const auto* safe = safe_state_of(result, "hand");
  ASSERT_TRUE(safe);
  EXPECT_EQ(safe->status, "failed");
  EXPECT_NE(safe->message.find("the serial line is gone"), std::string::npos) << safe->message;
}

// A stop (a signal, for fba-run) while the hand activates in its constructor: the activation gives
// up at once (Context::stop_token()) instead of polling until activation_timeout; the task ends
// interrupted, the hand not constructed.
TEST(Robotiq3fTask, AStopWhileTheHandActivatesEndsTheActivationAtOnce) {
  fba::test::TempDir dir;
  auto options = EmulatedHand::quick();
  options.activates = false;
  EmulatedHand hand(options);
  const auto config = fba::load_task_text(task_yaml(hand.device(), 0.1), "grasp.yaml", dir.path(), registry());
  std::stop_source stop;
  fba::RunOptions run;
  run.stop = stop.get_token();
  std::unique_ptr<fba::Task> task;
  std::atomic<bool> constructed{false};
  std::jthread construct([&] {
    task = std::make_unique<fba::Task>(config, run);
    constructed = true;
  });
  while (hand.emulator().state().imc != 1 && !constructed) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  ASSERT_FALSE(constructed) << "constructed without activating";
  stop.request_stop();
  const auto requests = hand.emulator().state().requests;
  construct.join();
  // The request on the line when the stop came may finish; no poll follows it.
  EXPECT_LE(hand.emulator().state().requests, requests + 1);
  ASSERT_TRUE(task);
  const auto result = task->run();
  EXPECT_EQ(result.outcome, fba::Outcome::Interrupted) << result.reason;
  EXPECT_NE(result.reason.find("'hand'"), std::string::npos) << result.reason;
  const auto* safe = safe_state_of(result, "hand");
  ASSERT_TRUE(safe);
  EXPECT_EQ(safe->status, "not constructed");
}
