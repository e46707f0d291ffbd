// The stop path's rules: every way out interrupts what runs, puts every actuator in its safe
// state, reports calls that did not return by name (and leaves them behind), catches whatever a
// component throws, and counts what restarts lost.
#include <gtest/gtest.h>

#include <unistd.h>

#include <atomic>
#include <limits>
#include <stop_token>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <fba/component.hpp>
#include <fba/task.hpp>

#include "fixture_components.hpp"

using fba::ExecutorKind;
using fba::Outcome;
using fba::test::load;

namespace {

std::atomic<int> g_stuck_entered{0};
std::atomic<int> g_interrupt_entered{0};
std::atomic<int> g_constructions{0};
std::atomic<int> g_safe_states{0};

// Blocks in process() for good: interrupt() does not help.
class Stuck final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::filter("test.stuck", "Never returns from process(), whatever it is told.").add(kIn, kOut);
  }
  static constexpr fba::In<std::int64_t> kIn{"in", "anything"};
  static constexpr fba::Out<std::int64_t> kOut{"out", "nothing"};
  explicit Stuck(fba::Context&) {}
  void process() override {
    g_stuck_entered.fetch_add(1);
    for (;;) pause();
  }
};

// An actuator whose safe_state() never returns.
class HangingSafeState final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::actuator("test.hanging_safe_state", "Its safe_state() never returns.").add(kIn);
  }
  static constexpr fba::In<std::int64_t> kIn{"in", "anything"};
  explicit HangingSafeState(fba::Context&) {}
  void process() override {}
  void safe_state() override {
    for (;;) pause();
  }
};

// Counts its safe states, so a test sees them when no run result exists.
class CountedActuator final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::actuator("test.counted_actuator", "Counts calls of safe_state().").add(kIn);
  }
  static constexpr fba::OptionalIn<std::int64_t> kIn{"in", "anything"};
  explicit CountedActuator(fba::Context&) {}
  void process() override {}
  void safe_state() override { g_safe_states.fetch_add(1); }
};

// Blocks in process(), whatever it is told, until an actuator reached its safe state: stuck for
// good if the safe states wait for it.
class StuckUntilSafe final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::filter("test.stuck_until_safe", "Returns from process() only once a safe state was reached.").add(kIn, kOut);
  }
  static constexpr fba::In<std::int64_t> kIn{"in", "anything"};
  static constexpr fba::Out<std::int64_t> kOut{"out", "nothing"};
  explicit StuckUntilSafe(fba::Context&) {}
  void process() override {
    const int seen = g_safe_states.load();
    g_stuck_entered.fetch_add(1);
    while (g_safe_states.load() == seen) pause_briefly();
  }
  static void pause_briefly() { std::this_thread::sleep_for(std::chrono::milliseconds(1)); }
};

// Throws an int (not a std::exception) from the call its parameter names.
class IntThrower final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::actuator("test.int_thrower", "Throws 42 from one call.").add(kIn, kFrom);
  }
  static constexpr fba::In<std::int64_t> kIn{"in", "anything"};
  static constexpr fba::Param<std::string> kFrom{
      "from", "process", "process, end_of_stream, safe_state, constructor, or restart (process, then the constructor)"};
  explicit IntThrower(fba::Context& ctx) : from_(ctx(kFrom)) {
    const int n = g_constructions.fetch_add(1);
    if (from_ == "constructor" || (from_ == "restart" && n > 0)) throw 7;
  }
  void process() override {
    if (from_ == "process") throw 42;
    if (from_ == "restart") throw std::runtime_error("first failure");
  }
  void end_of_stream() override {
    if (from_ == "end_of_stream") throw 42;
  }
  void safe_state() override {
    if (from_ == "safe_state") throw 42;
  }

 private:
  std::string from_;
};

// Blocks in process() until interrupted; its interrupt() then throws.
class ThrowingInterrupt final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::actuator("test.throwing_interrupt", "interrupt() releases process() and throws 5.").add(kIn).blocking();
  }
  static constexpr fba::In<std::int64_t> kIn{"in", "anything"};
  explicit ThrowingInterrupt(fba::Context&) {}
  void process() override {
    g_interrupt_entered.fetch_add(1);
    interrupted_.wait();
  }
  void interrupt() override {
    interrupted_.raise();
    throw 5;
  }

 private:
  fba::test::Flag interrupted_;
};

// Fails every invocation, on a thread of its own: restarts run while the stop interrupts it.
class AlwaysFails final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::filter("test.always_fails", "Throws from every process().").add(kIn, kOut).blocking();
  }
  static constexpr fba::In<std::int64_t> kIn{"in", "anything"};
  static constexpr fba::Out<std::int64_t> kOut{"out", "nothing"};
  explicit AlwaysFails(fba::Context&) { g_constructions.fetch_add(1); }
  void process() override { throw std::runtime_error("always"); }
  void interrupt() override {}  // process() never waits
};

// A driver-like actuator: its interrupt() cuts waits on the device and takes a while, and a
// safe_state() that starts before interrupt() returned would have its own waits cut (it says so).
std::atomic<int> g_interrupt_then_safe_calls{0};

class InterruptThenSafe final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::actuator("test.interrupt_then_safe", "safe_state() fails unless its interrupt() returned first.")
        .add(kIn)
        .blocking();
  }
  static constexpr fba::OptionalIn<std::int64_t> kIn{"in", "anything"};
  explicit InterruptThenSafe(fba::Context&) {}
  void process() override { g_interrupt_then_safe_calls.fetch_add(1); }
  void interrupt() override {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // widens the window; no bound is checked
    interrupted_ = true;
  }
  void safe_state() override {
    if (!interrupted_) throw std::runtime_error("safe_state() began before interrupt() returned");
  }

 private:
  std::atomic<bool> interrupted_{false};
};

// An actuator whose safe_state() fails if it begins while process() runs: the stop must wait for
// the call even when a producer notified the node during it (the node is then RunningNotified).
std::atomic<int> g_overlap_checked_calls{0};

class OverlapChecked final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::actuator("test.overlap_checked", "safe_state() fails if it begins during process().").add(kIn);
  }
  static constexpr fba::In<std::int64_t> kIn{"in", "anything"};
  explicit OverlapChecked(fba::Context&) {}
  void process() override {
    in_process_ = true;
    g_overlap_checked_calls.fetch_add(1);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the producer notifies meanwhile; no bound is checked
    in_process_ = false;
  }
  void safe_state() override {
    if (in_process_) throw std::runtime_error("safe_state() began while process() was running");
  }

 private:
  std::atomic<bool> in_process_{false};
};

// Declares that its safe state may run beside process() (a quick stop on its own bus message):
// process() waits, whatever interrupt says, until safe_state() ran, and records whether it saw
// that happen while it was still inside its call. Were the stop to wait for process() to return,
// process() would wait out its bound and see nothing.
std::atomic<int> g_concurrent_safe_entered{0};
std::atomic<bool> g_concurrent_safe_seen_in_process{false};

class ConcurrentSafeState final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::actuator("test.concurrent_safe_state", "Its safe state runs beside a process() that waits for it.")
        .add(kIn)
        .concurrent_safe_state();
  }
  static constexpr fba::In<std::int64_t> kIn{"in", "anything"};
  explicit ConcurrentSafeState(fba::Context&) {}
  void process() override {
    g_concurrent_safe_entered.fetch_add(1);
    if (safe_.wait_for(std::chrono::seconds(20))) g_concurrent_safe_seen_in_process.store(true);
  }
  void safe_state() override { safe_.raise(); }

 private:
  fba::test::Flag safe_;
};

// Its constructor waits on the device (here: for the stop) for as long as a hand's activation
// may take; a stop cuts it short through the context's stop token.
std::atomic<int> g_slow_constructions{0};
std::atomic<bool> g_slow_construction_saw_stop{false};

class SlowConstructor final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::actuator("test.slow_constructor", "Its constructor waits for the stop, up to 60 s.").add(kIn);
  }
  static constexpr fba::OptionalIn<std::int64_t> kIn{"in", "anything"};
  explicit SlowConstructor(fba::Context& ctx) {
    g_slow_constructions.fetch_add(1);
    std::mutex mutex;
    std::condition_variable_any cv;
    std::unique_lock lock(mutex);
    const std::stop_token stop = ctx.stop_token();
    cv.wait_for(lock, stop, std::chrono::seconds(60), [] { return false; });
    g_slow_construction_saw_stop.store(stop.stop_requested());
    if (stop.stop_requested()) throw std::runtime_error("activation stopped");
  }
  void process() override {}
};

// Its device never answers: the constructor says so with a DeviceError.
class DeadDevice final : public fba::Component {
 public:
  static fba::Spec spec() { return fba::Spec::actuator("test.dead_device", "Its device never answers.").add(kIn); }
  static constexpr fba::OptionalIn<std::int64_t> kIn{"in", "anything"};
  explicit DeadDevice(fba::Context&) { throw fba::DeviceError("/dev/ttyX: no answer from slave 9 within 0.5 s"); }
  void process() override {}
};

// Free-running, produces nothing, never finishes.
class Idle final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::sensor("test.idle", "Runs and produces nothing.").add(kOut).trigger({fba::TriggerPolicy::Free, 0});
  }
  static constexpr fba::Out<std::int64_t> kOut{"out", "nothing"};
  explicit Idle(fba::Context&) {}
  void process() override { std::this_thread::yield(); }
};

}  // namespace

FBA_COMPONENT(Stuck);
FBA_COMPONENT(StuckUntilSafe);
FBA_COMPONENT(HangingSafeState);
FBA_COMPONENT(CountedActuator);
FBA_COMPONENT(IntThrower);
FBA_COMPONENT(ThrowingInterrupt);
FBA_COMPONENT(AlwaysFails);
FBA_COMPONENT(Idle);
FBA_COMPONENT(InterruptThenSafe);
FBA_COMPONENT(OverlapChecked);
FBA_COMPONENT(ConcurrentSafeState);
FBA_COMPONENT(SlowConstructor);
FBA_COMPONENT(DeadDevice);

namespace {

fba::RunOptions options(ExecutorKind e, double grace_s = 0.1) {
  fba::RunOptions o;
  o.executor = e;
  o.stop_grace_s = grace_s;
  return o;
}

using fba::test::has_event;

const fba::SafeStateResult* safe_state_of(const fba::RunResult& r, const std::string& name) {
  for (const auto& s : r.safe_states)
    if (s.component == name) return &s;
  return nullptr;
}

// Stops the task from another thread once `counter` went past `seen`.
std::thread stop_when(fba::Task& task, std::atomic<int>& counter, int seen) {
  return std::thread([&task, &counter, seen] {
    while (counter.load() <= seen) std::this_thread::yield();
    task.request_stop(Outcome::Interrupted, "stopped by the test");
  });
}

// Runs the task and stops it from another thread once `counter` moved past its value now.
fba::RunResult run_and_stop_when(const std::string& yaml, std::atomic<int>& counter, const fba::RunOptions& o) {
  fba::Task task(load(yaml), o);
  auto stopper = stop_when(task, counter, counter.load());
  auto r = task.run();
  stopper.join();
  return r;
}

// One actuator of `type` fed by a counter that never ends.
std::string counter_into(const std::string& type) {
  return "components:\n  src: { type: examples.counter, params: { count: 1000000000 } }\n  act: { type: " + type +
         " }\nconnections: [ src.out -> act.in ]\n";
}

class Shutdown : public ::testing::TestWithParam<ExecutorKind> {};

TEST_P(Shutdown, AComponentStuckInProcessIsNamedLeftBehindAndTheSafeStatesStillRun) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 1000000000 } }
  stuck: { type: test.stuck }
  sink: { type: examples.sink }
connections: [ src.out -> stuck.in, src.out -> sink.in ]
)"),
                 options(GetParam()));
  auto stopper = stop_when(task, g_stuck_entered, g_stuck_entered.load());
  const auto r = task.run();
  stopper.join();
  // Stopped as a signal stops a run: it stays interrupted, and the reason names the stuck call.
  EXPECT_EQ(r.outcome, Outcome::Interrupted);
  EXPECT_EQ(r.exit_code(), 130);
  ASSERT_EQ(r.stuck.size(), 1u);
  EXPECT_EQ(r.stuck[0].component, "stuck");
  EXPECT_EQ(r.stuck[0].type, "test.stuck");
  EXPECT_EQ(r.stuck[0].call, "process()");
  EXPECT_NE(r.reason.find("component 'stuck' (test.stuck) did not return from process()"), std::string::npos)
      << r.reason;
  EXPECT_NE(r.reason.find("stopped by the test"), std::string::npos) << r.reason;
  ASSERT_NE(safe_state_of(r, "sink"), nullptr);
  EXPECT_EQ(safe_state_of(r, "sink")->status, "reached");
  EXPECT_TRUE(has_event(r, "sink", "safe_state"));
  const std::string summary = fba::summary_json(r, fba::TaskConfig{});
  EXPECT_NE(summary.find("\"call\": \"process()\""), std::string::npos) << summary;
}  // the task's destructor leaves the stuck component alone

TEST_P(Shutdown, ActuatorsGoSafeWithoutWaitingForAStuckComponentToReturn) {
  // The stuck filter returns only after an actuator's safe state: were the safe states to wait for
  // every thread, it would still be stuck when the grace ends, and be reported so.
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 1000000000 } }
  stuck: { type: test.stuck_until_safe }
  act: { type: test.counted_actuator }
connections: [ src.out -> stuck.in, src.out -> act.in ]
)"),
                 options(GetParam(), 30));
  auto stopper = stop_when(task, g_stuck_entered, g_stuck_entered.load());
  const auto r = task.run();
  stopper.join();
  EXPECT_TRUE(r.stuck.empty()) << r.reason;
  EXPECT_EQ(r.outcome, Outcome::Interrupted) << r.reason;
  ASSERT_NE(safe_state_of(r, "act"), nullptr);
  EXPECT_EQ(safe_state_of(r, "act")->status, "reached");
}

// A blocking actuator is interrupted at the stop; its safe state waits for that call to return,
// so the interrupt cannot cut the safe state's own waits on the device.
TEST_P(Shutdown, AnActuatorGoesSafeOnlyAfterItsInterruptReturned) {
  const auto r = run_and_stop_when(counter_into("test.interrupt_then_safe"), g_interrupt_then_safe_calls, options(GetParam(), 30));
  ASSERT_NE(safe_state_of(r, "act"), nullptr);
  EXPECT_EQ(safe_state_of(r, "act")->status, "reached") << safe_state_of(r, "act")->message;
}

// The stop found the node "not Running" while it ran a call it had been notified during, and
// started safe_state() beside process() (a data race that ThreadSanitizer caught in CI).
TEST_P(Shutdown, AnActuatorNotifiedDuringItsCallGoesSafeOnlyAfterTheCall) {
  for (int run = 0; run < 3; ++run) {
    const auto r = run_and_stop_when(counter_into("test.overlap_checked"), g_overlap_checked_calls, options(GetParam(), 30));
    ASSERT_NE(safe_state_of(r, "act"), nullptr);
    EXPECT_EQ(safe_state_of(r, "act")->status, "reached") << safe_state_of(r, "act")->message;
  }
}

// An actuator whose spec declares concurrent_safe_state() gets its safe state at once, while its
// process() still runs, instead of after the call returns (the issue: SIGTERM reached a sleeping
// sink's safe state only after the grace).
TEST_P(Shutdown, AnActuatorWithAConcurrentSafeStateGetsItDuringItsCall) {
  g_concurrent_safe_seen_in_process = false;
  const auto r = run_and_stop_when(counter_into("test.concurrent_safe_state"), g_concurrent_safe_entered, options(GetParam(), 60));
  EXPECT_TRUE(g_concurrent_safe_seen_in_process.load());
  ASSERT_NE(safe_state_of(r, "act"), nullptr);
  EXPECT_EQ(safe_state_of(r, "act")->status, "reached");
  EXPECT_TRUE(r.stuck.empty()) << r.reason;
}

// A stop while a constructor waits on its device reaches that constructor (Context::stop_token),
// leaves the later components unconstructed, and the run ends interrupted with the safe states of
// those constructed, its time counted from the first constructor.
TEST(Shutdown, AStopDuringConstructionCutsTheConstructorShortAndTakesTheSafeStates) {
  g_slow_construction_saw_stop = false;
  const int safe_before = g_safe_states.load();
  const int constructions = g_slow_constructions.load();
  std::stop_source stop;
  fba::RunOptions o = options(ExecutorKind::Threaded, 30);
  o.stop = stop.get_token();
  std::thread stopper([&] {
    while (g_slow_constructions.load() == constructions) std::this_thread::yield();
    stop.request_stop();
  });
  fba::Task task(load(R"(
components:
  first: { type: test.counted_actuator }
  slow: { type: test.slow_constructor }
  last: { type: test.counted_actuator }
)"),
                 o);
  stopper.join();
  EXPECT_TRUE(g_slow_construction_saw_stop.load());
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::Interrupted) << r.reason;
  EXPECT_NE(r.reason.find("while constructing component 'slow' (test.slow_constructor)"), std::string::npos) << r.reason;
  ASSERT_NE(safe_state_of(r, "first"), nullptr);
  EXPECT_EQ(safe_state_of(r, "first")->status, "reached");
  ASSERT_NE(safe_state_of(r, "slow"), nullptr);
  EXPECT_EQ(safe_state_of(r, "slow")->status, "not constructed");
  ASSERT_NE(safe_state_of(r, "last"), nullptr);
  EXPECT_EQ(safe_state_of(r, "last")->status, "not constructed");
  EXPECT_EQ(g_safe_states.load(), safe_before + 1);
  EXPECT_GT(r.construct_s, 0.0);
  EXPECT_GE(r.wall_s, r.construct_s);
}

// A device that fails to start is a runtime error naming the component and its device, not a
// mistake in the task (exit 3, not 2); the actuators built before it still go safe.
TEST(Shutdown, ADeviceThatFailsToStartIsARuntimeErrorAndEarlierActuatorsGoSafe) {
  const int safe_before = g_safe_states.load();
  try {
    fba::Task task(load(R"(
components:
  first: { type: test.counted_actuator }
  hand: { type: test.dead_device }
)"),
                   options(ExecutorKind::Threaded));
    FAIL() << "the device's failure was not reported";
  } catch (const fba::ConstructionError& e) {
    EXPECT_EQ(e.outcome(), Outcome::RuntimeError);
    ASSERT_FALSE(e.diagnostics().empty());
    EXPECT_NE(e.diagnostics()[0].message.find("component 'hand' (test.dead_device) could not start its device: /dev/ttyX: "
                                              "no answer from slave 9 within 0.5 s"),
              std::string::npos)
        << e.diagnostics()[0].message;
    ASSERT_EQ(e.safe_states().size(), 2u);
    EXPECT_EQ(e.safe_states()[0].status, "reached");
    EXPECT_EQ(e.safe_states()[1].status, "not constructed");
  }
  EXPECT_EQ(g_safe_states.load(), safe_before + 1);
}

// A grace too long for the clock (about 9.2e9 s and more overflowed the nanoseconds) still waits
// for the safe states instead of acting as no grace at all.
TEST_P(Shutdown, AStopGraceBeyondTheClocksRangeStillWaitsForTheSafeStates) {
  for (const double grace : {1e10, 1e300, std::numeric_limits<double>::infinity()}) {
    const auto r = run_and_stop_when(R"(
components:
  src: { type: examples.counter, params: { count: 1000000000 } }
  stuck: { type: test.stuck_until_safe }
  act: { type: test.counted_actuator }
connections: [ src.out -> stuck.in, src.out -> act.in ]
)",
                                     g_stuck_entered, options(GetParam(), grace));
    ASSERT_NE(safe_state_of(r, "act"), nullptr) << grace;
    EXPECT_EQ(safe_state_of(r, "act")->status, "reached") << grace;
    EXPECT_TRUE(r.stuck.empty()) << grace << ": " << r.reason;
  }
}

TEST_P(Shutdown, ASafeStateThatNeverReturnsIsNamedAndTheOthersStillRun) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 3 } }
  hang: { type: test.hanging_safe_state }
  sink: { type: examples.sink }
connections: [ src.out -> hang.in, src.out -> sink.in ]
)"),
                 options(GetParam()));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::RuntimeError);
  ASSERT_EQ(r.stuck.size(), 1u);
  EXPECT_EQ(r.stuck[0].component, "hang");
  EXPECT_EQ(r.stuck[0].call, "safe_state()");
  EXPECT_NE(r.reason.find("component 'hang' (test.hanging_safe_state) did not return from safe_state()"),
            std::string::npos)
      << r.reason;
  ASSERT_NE(safe_state_of(r, "hang"), nullptr);
  EXPECT_EQ(safe_state_of(r, "hang")->status, "did not return");
  ASSERT_NE(safe_state_of(r, "sink"), nullptr);
  EXPECT_EQ(safe_state_of(r, "sink")->status, "reached");
}

TEST_P(Shutdown, ANonExceptionFromProcessOrEndOfStreamNamesTheComponentAndTheCall) {
  for (const std::string call : {"process", "end_of_stream"}) {
    fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 3 } }
  t: { type: test.int_thrower, params: { from: )" +
                        call + R"( } }
connections: [ src.out -> t.in ]
)"),
                   options(GetParam()));
    const auto r = task.run();
    EXPECT_EQ(r.outcome, Outcome::RuntimeError);
    EXPECT_EQ(
        r.reason,
        "component 't' (test.int_thrower) threw a non-exception (not derived from std::exception) from " + call + "()");
    ASSERT_NE(safe_state_of(r, "t"), nullptr);
    EXPECT_EQ(safe_state_of(r, "t")->status, "reached");
  }
}

TEST_P(Shutdown, ANonExceptionFromSafeStateFailsTheRunWithItsName) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 3 } }
  t: { type: test.int_thrower, params: { from: safe_state } }
connections: [ src.out -> t.in ]
)"),
                 options(GetParam()));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::RuntimeError);
  EXPECT_NE(r.reason.find("component 't' could not reach a safe state: threw a non-exception (not derived from "
                          "std::exception) from safe_state()"),
            std::string::npos)
      << r.reason;
  ASSERT_NE(safe_state_of(r, "t"), nullptr);
  EXPECT_EQ(safe_state_of(r, "t")->status, "failed");
}

TEST(Shutdown, AnInterruptThatThrowsIsReportedAndTheStopCompletes) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 1000000000 } }
  dev: { type: test.throwing_interrupt }
connections: [ src.out -> dev.in ]
)"),
                 options(ExecutorKind::Threaded));
  auto stopper = stop_when(task, g_interrupt_entered, g_interrupt_entered.load());
  const auto r = task.run();
  stopper.join();
  EXPECT_EQ(r.outcome, Outcome::Interrupted);
  EXPECT_TRUE(r.stuck.empty());
  EXPECT_TRUE(has_event(r, "dev", "error", "threw a non-exception (not derived from std::exception) from interrupt()"));
}

TEST(Shutdown, AConstructorThrowingANonExceptionIsAConfigurationErrorAndEarlierActuatorsGoSafe) {
  g_constructions = 0;
  const int safe_before = g_safe_states.load();
  try {
    fba::Task task(load(R"(
components:
  first: { type: test.counted_actuator }
  t: { type: test.int_thrower, params: { from: constructor } }
  src: { type: examples.counter }
connections: [ src.out -> t.in ]
)"),
                   options(ExecutorKind::Threaded));
    FAIL() << "the constructor's throw was not reported";
  } catch (const fba::ConfigError& e) {
    ASSERT_FALSE(e.diagnostics().empty());
    EXPECT_NE(
        e.diagnostics()[0].message.find(
            "component 't' (test.int_thrower) refused its configuration: it threw a non-exception (not derived from "
            "std::exception) from its constructor"),
        std::string::npos)
        << e.diagnostics()[0].message;
  }
  EXPECT_EQ(g_safe_states.load(), safe_before + 1);
}

TEST_P(Shutdown, ARestartWhoseConstructorThrowsANonExceptionStopsWithItsName) {
  g_constructions = 0;
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 3 } }
  t: { type: test.int_thrower, params: { from: restart }, on_error: restart }
connections: [ src.out -> t.in ]
)"),
                 options(GetParam()));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::RuntimeError);
  EXPECT_EQ(r.reason,
            "component 't' (test.int_thrower) could not be restarted: threw a non-exception (not derived from "
            "std::exception) "
            "from its constructor");
}

TEST_P(Shutdown, ARestartThatRecoveredSucceedsAndCountsTheLostSamples) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 12 } }
  bad: { type: examples.faulty, params: { fail_after: 5 }, on_error: { policy: restart, max_restarts: 2 } }
  m: { type: test.merge }
  sink: { type: examples.sink }
connections: [ src.out -> bad.in, bad.out -> m.a, m.out -> sink.in ]
)"),
                 options(GetParam()));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::Success) << r.reason;
  ASSERT_EQ(r.components[1].name, "bad");
  EXPECT_EQ(r.components[1].restarts, 2u);
  EXPECT_EQ(r.components[1].lost_to_restarts, 2u);  // the 6th and the 12th sample
  EXPECT_EQ(r.lost_to_restarts, 2u);
  EXPECT_EQ(r.components[3].samples_in, 10u);
  const std::string summary = fba::summary_json(r, fba::TaskConfig{});
  EXPECT_NE(summary.find("\"lost_to_restarts\": 2"), std::string::npos) << summary;
}

// The stop interrupts a component while its own thread replaces it after a failure: the
// component pointer is shared under a lock (ThreadSanitizer reports the race otherwise).
TEST(Shutdown, InterruptingAComponentThatIsRestartingIsRaceFree) {
  for (int i = 0; i < 3; ++i) {
    fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 1000000000 } }
  flaky: { type: test.always_fails, on_error: { policy: restart, max_restarts: 1000000 } }
connections: [ src.out -> flaky.in ]
)"),
                   options(ExecutorKind::Threaded, 30));
    auto stopper = stop_when(task, g_constructions, g_constructions.load() + 20);
    const auto r = task.run();
    stopper.join();
    EXPECT_EQ(r.outcome, Outcome::Interrupted) << r.reason;
    EXPECT_TRUE(r.stuck.empty());
  }
}

TEST(Shutdown, AStallWarnsThatTheNextTickIsFarAway) {
  auto o = options(ExecutorKind::Threaded);
  o.stall_warning_s = 0.05;
  o.timeout_s = 2;
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 10, rate: 1e-9 } }
  sink: { type: examples.sink }
connections: [ src.out -> sink.in ]
)"),
                 o);
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::RuntimeError);
  EXPECT_TRUE(has_event(r, "fba", "stall_warning", "the next tick of periodic 'src' is 1e+09 s away"));
  EXPECT_TRUE(has_event(r, "fba", "stall_warning", "before anything can happen"));
}

TEST(Shutdown, AStallWarnsThatAFreeRunningSensorProducesNothing) {
  auto o = options(ExecutorKind::Threaded);
  o.stall_warning_s = 0.05;
  o.timeout_s = 2;
  fba::Task task(load(R"(
components:
  src: { type: test.idle }
  sink: { type: examples.sink }
connections: [ src.out -> sink.in ]
)"),
                 o);
  const auto r = task.run();
  EXPECT_TRUE(has_event(r, "fba", "stall_warning", "the free-running sensor 'src' runs but produces nothing"));
}

INSTANTIATE_TEST_SUITE_P(Executors, Shutdown, ::testing::Values(ExecutorKind::Threaded, ExecutorKind::Deterministic),
                         [](const auto& info) {
                           return info.param == ExecutorKind::Threaded ? "Threaded" : "Deterministic";
                         });

}  // namespace
