// The runtime's rules, each checked under both executors where both apply.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include <fba/task.hpp>
#include <nlohmann/json.hpp>

#include "fixture_components.hpp"

using fba::ExecutorKind;
using fba::Outcome;
using fba::test::ints;
using fba::test::load;
using fba::test::with;

namespace {

using fba::test::has_event;

std::string chain(int count, int hops, const std::string& buffer = "lossless", int capacity = 16) {
  std::string y = "components:\n  src: { type: examples.counter, params: { count: " + std::to_string(count) + " } }\n";
  for (int i = 0; i < hops; ++i) y += "  p" + std::to_string(i) + ": { type: examples.passthrough }\n";
  y += "  sink: { type: examples.sink, params: { expected: " + std::to_string(count) + " } }\nconnections:\n";
  std::string prev = "src";
  for (int i = 0; i <= hops; ++i) {
    const std::string next = i < hops ? "p" + std::to_string(i) : "sink";
    y += "  - { from: " + prev + ".out, to: " + next + ".in, buffer: " + buffer + ", capacity: " + std::to_string(capacity) + " }\n";
    prev = next;
  }
  return y + "on:\n  sink.done: stop_success\n  sink.gap: stop_failure\n";
}

class RuntimeBoth : public ::testing::TestWithParam<ExecutorKind> {};

}  // namespace

INSTANTIATE_TEST_SUITE_P(Executors, RuntimeBoth, ::testing::Values(ExecutorKind::Threaded, ExecutorKind::Deterministic),
                         [](const auto& info) { return std::string(fba::to_string(info.param)); });

TEST_P(RuntimeBoth, LosslessChainDeliversEverySampleInOrder) {
  fba::Task task(load(chain(20000, 10, "lossless", 4)), with(GetParam()));
  const auto& seen = task.tap("p9.out");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  ASSERT_EQ(seen.size(), 20000u);
  for (std::size_t i = 0; i < seen.size(); ++i) {
    ASSERT_EQ(seen[i].get<std::int64_t>(), static_cast<std::int64_t>(i));
    ASSERT_EQ(seen[i].header().seq, i);  // the passthroughs forward headers untouched
  }
  for (const auto& c : r.connections) EXPECT_EQ(c.dropped, 0u) << c.from;
}

TEST_P(RuntimeBoth, EverySensorFinishedMeansSuccess) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 100 } }
  sink: { type: examples.sink }
connections: [ src.out -> sink.in ]
)"),
                 with(GetParam()));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::Success);
  EXPECT_EQ(r.reason, "every sensor finished and all data was processed");
  EXPECT_EQ(r.components[1].samples_in, 100u);
}

TEST_P(RuntimeBoth, DropOldestDropsAndCountsButKeepsOrder) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 2000 } }
  slow: { type: examples.sink, params: { delay: 0.0001 } }
  pass: { type: examples.passthrough }
connections:
  - { from: src.out, to: pass.in, buffer: drop_oldest, capacity: 4 }
  - pass.out -> slow.in
on:
  slow.gap: stop_failure
)"),
                 with(GetParam()));
  const auto& seen = task.tap("pass.out");
  const auto r = task.run();
  // A gap reaches the sink, which fails the task through the rule: data was dropped.
  EXPECT_EQ(r.outcome, Outcome::Failure) << r.reason;
  ASSERT_FALSE(seen.empty());
  for (std::size_t i = 1; i < seen.size(); ++i) EXPECT_LT(seen[i - 1].get<std::int64_t>(), seen[i].get<std::int64_t>());
  std::uint64_t dropped = 0;
  for (const auto& c : r.connections)
    if (c.from == "src.out") dropped = c.dropped;
  EXPECT_GT(dropped, 0u);
}

TEST_P(RuntimeBoth, LatestKeepsOnlyTheNewest) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 500 } }
  pass: { type: examples.passthrough }
  sink: { type: test.merge }
  end: { type: examples.sink }
connections:
  - { from: src.out, to: pass.in, buffer: latest }
  - pass.out -> sink.a
  - sink.out -> end.in
)"),
                 with(GetParam()));
  const auto& seen = task.tap("pass.out");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back().get<std::int64_t>(), 499);  // the newest always survives
  for (std::size_t i = 1; i < seen.size(); ++i) EXPECT_LT(seen[i - 1].get<std::int64_t>(), seen[i].get<std::int64_t>());
}

TEST(Runtime, DeterministicExecutorDropsExactlyTheSameEveryRun) {
  auto run = [] {
    fba::Task task(load(chain(1000, 3, "drop_oldest", 4)), with(ExecutorKind::Deterministic));
    const auto& seen = task.tap("p2.out");
    task.run();
    return ints(seen);
  };
  const auto first = run();
  EXPECT_LT(first.size(), 1000u);
  EXPECT_EQ(first, run());
}

TEST(Runtime, ExecutorsAgreeOnADeterministicGraph) {
  // Fan-out, a composite, an 'all' join matched by stamp, and a feedback loop: the results of
  // a lossless graph do not depend on how its nodes are scheduled.
  const char* yaml = R"(
components:
  src: { type: examples.counter, params: { count: 200 } }
  p: { type: examples.passthrough }
  relay: { type: examples.relay }
  pair: { type: test.pair }
  m: { type: test.merge }
  c: { type: test.countdown }
  sink: { type: examples.sink }
connections:
  - src.out -> p.in
  - src.out -> relay.in
  - p.out -> pair.a
  - relay.out -> pair.b
  - pair.sum -> m.a
  - m.out -> c.in
  - { from: c.out, to: m.b, feedback: true }
  - { from: m.out, to: sink.in, capacity: 1 }
)";
  auto run = [&](ExecutorKind e) {
    fba::Task task(load(yaml), with(e));
    const auto& sums = task.tap("pair.sum");
    const auto& merged = task.tap("m.out");
    const auto r = task.run();
    EXPECT_EQ(r.outcome, Outcome::Success) << r.reason;
    auto m = ints(merged);
    std::sort(m.begin(), m.end());  // the loop interleaves differently; the multiset is fixed
    return std::make_pair(ints(sums), m);
  };
  const auto threaded = run(ExecutorKind::Threaded);
  const auto deterministic = run(ExecutorKind::Deterministic);
  ASSERT_EQ(deterministic.first.size(), 200u);
  for (std::size_t i = 0; i < 200; ++i) EXPECT_EQ(deterministic.first[i], static_cast<std::int64_t>(2 * i));
  EXPECT_EQ(threaded.first, deterministic.first);
  EXPECT_EQ(threaded.second, deterministic.second);
  EXPECT_EQ(deterministic.second.size(), 200u * 200u);  // sum over v of (2v + 1)
}

TEST(Runtime, AllTriggerPairsSamplesWithEqualStamps) {
  // At 100 Hz and 50 Hz on the virtual clock, only every second sample of a has a partner.
  fba::Task task(load(R"(
components:
  a: { type: examples.counter, params: { count: 20, rate: 100 } }
  b: { type: examples.counter, params: { count: 10, rate: 50, start: 1000 } }
  pair: { type: test.pair }
  sink: { type: examples.sink }
connections:
  - a.out -> pair.a
  - b.out -> pair.b
  - pair.sum -> sink.in
)"),
                 with(ExecutorKind::Deterministic));
  const auto& sums = task.tap("pair.sum");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  const auto v = ints(sums);
  ASSERT_EQ(v.size(), 10u);
  for (std::size_t i = 0; i < v.size(); ++i) EXPECT_EQ(v[i], static_cast<std::int64_t>(2 * i + 1000 + i));
}

TEST(Runtime, PeriodicTriggerStampsOnTheVirtualClock) {
  fba::Task task(load("components:\n  a: { type: examples.counter, params: { count: 5, rate: 1000 } }\n  s: { type: examples.sink }\n"
                      "connections: [ a.out -> s.in ]\n"),
                 with(ExecutorKind::Deterministic));
  const auto& out = task.tap("a.out");
  task.run();
  ASSERT_EQ(out.size(), 5u);
  for (std::size_t i = 0; i < out.size(); ++i) EXPECT_EQ(out[i].header().stamp_ns, static_cast<std::int64_t>(i) * 1'000'000);
}

TEST(Runtime, PeriodicTriggerKeepsItsRateWhenThreaded) {
  fba::Task task(load("components:\n  a: { type: examples.counter, params: { count: 20, rate: 200 } }\n  s: { type: examples.sink }\n"
                      "connections: [ a.out -> s.in ]\n"),
                 with(ExecutorKind::Threaded));
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success);
  EXPECT_GT(r.wall_s, 0.09);  // 20 samples at 200 Hz: 95 ms from the first to the last
}

// Small queues, fan-out and fan-in make producers and consumers hand over control constantly:
// a lost wake-up (a sample left in an idle node's queue) would show as a 'lost_wakeup' event.
TEST(Runtime, NoWakeUpIsLostUnderContention) {
  const char* yaml = R"(
components:
  src: { type: examples.counter, params: { count: 20000 } }
  a: { type: examples.passthrough }
  b: { type: examples.relay }
  pair: { type: test.pair }
  sink: { type: examples.sink, params: { expected: 20000 } }
connections:
  - { from: src.out, to: a.in, capacity: 1 }
  - { from: src.out, to: b.in, capacity: 2 }
  - { from: a.out, to: pair.a, capacity: 1 }
  - { from: b.out, to: pair.b, capacity: 1 }
  - { from: pair.sum, to: sink.in, capacity: 1 }
on: { sink.done: stop_success }
)";
  for (int run = 0; run < 20; ++run) {
    fba::Task task(load(yaml), with(ExecutorKind::Threaded, 60));
    const auto r = task.run();
    ASSERT_EQ(r.outcome, Outcome::Success) << "run " << run << ": " << r.reason;
    for (const auto& e : r.events) ASSERT_NE(e.name, "lost_wakeup") << "run " << run << ": " << e.source;
  }
}

// Samples that arrive one at a time (a timer) find every worker asleep, and a fan-out wakes
// several at once: the wake-up bookkeeping must never count a wake-up that no sleeper will
// consume, or the next tick waits in the queue forever (the hang CI once found at 1 kHz).
TEST(Runtime, NoWakeUpIsLostWhenWorkersSleepBetweenTicks) {
  std::string yaml = "components:\n  src: { type: examples.counter, params: { count: 300, rate: 2000 } }\n";
  for (int i = 0; i < 4; ++i) yaml += "  s" + std::to_string(i) + ": { type: examples.sink, params: { expected: 300 } }\n";
  yaml += "connections:\n";
  for (int i = 0; i < 4; ++i) yaml += "  - src.out -> s" + std::to_string(i) + ".in\n";
  for (int run = 0; run < 10; ++run) {
    auto options = with(ExecutorKind::Threaded, 60);
    options.threads = 2;
    fba::Task task(load(yaml), options);
    const auto r = task.run();
    ASSERT_EQ(r.outcome, Outcome::Success) << "run " << run << ": " << r.reason;
  }
}

// fba-run's live graph dumps read the counts from another thread while the task runs (TSan
// checks that every read is atomic or locked); the counts only grow.
TEST(Runtime, SnapshotsWhileRunningAreRaceFreeAndMonotone) {
  fba::Task task(load(chain(20000, 4, "lossless", 4)), with(ExecutorKind::Threaded));
  std::atomic<bool> done{false};
  std::uint64_t last = 0;
  bool monotone = true;
  std::thread reader([&] {
    while (!done.load()) {
      const auto s = task.snapshot();
      std::uint64_t calls = 0;
      for (const auto& c : s.components) calls += c.invocations;
      monotone = monotone && calls >= last;
      last = calls;
    }
  });
  const auto r = task.run();
  done.store(true);
  reader.join();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  EXPECT_TRUE(monotone);
  const auto after = task.snapshot();
  ASSERT_EQ(after.components.size(), r.components.size());
  for (std::size_t i = 0; i < r.components.size(); ++i) EXPECT_EQ(after.components[i].invocations, r.components[i].invocations);
}

TEST_P(RuntimeBoth, FailureEventStopsWithFailure) {
  // The sink expects nothing, so the only rule that can fire is the failure.
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 100 } }
  sink: { type: examples.sink }
connections: [ src.out -> sink.in ]
on: { src.finished: stop_failure }
)"),
                 with(GetParam()));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::Failure);
  EXPECT_EQ(r.exit_code(), 1);
  ASSERT_TRUE(r.final_event.has_value());
  EXPECT_EQ(r.final_event->source, "src");
  EXPECT_EQ(r.final_event->name, "finished");
}

TEST_P(RuntimeBoth, EventsAreDeliveredToInputs) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 3 } }
  sink: { type: examples.sink, params: { expected: 3 } }
  log: { type: test.event_log }
  end: { type: examples.sink }
connections:
  - src.out -> sink.in
  - log.names -> end.in
on:
  sink.done: { deliver: log.events }
  src.finished: { deliver: log.events }
)"),
                 with(GetParam()));
  const auto& names = task.tap("log.names");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  std::vector<std::string> got;
  for (const auto& p : names) got.push_back(p.get<std::string>());
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, (std::vector<std::string>{"sink.done", "src.finished"}));
}

TEST_P(RuntimeBoth, AFailingComponentStopsTheTaskWithItsNameAndReason) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 100 } }
  bad: { type: examples.faulty, params: { fail_after: 5, message: "sensor glitch" } }
  sink: { type: examples.sink }
connections:
  - src.out -> bad.in
  - bad.out -> sink.in
)"),
                 with(GetParam()));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::RuntimeError);
  EXPECT_EQ(r.exit_code(), 3);
  EXPECT_EQ(r.reason, "component 'bad' (examples.faulty) failed: sensor glitch");
  EXPECT_TRUE(has_event(r, "bad", "error"));
  EXPECT_TRUE(has_event(r, "sink", "safe_state"));  // actuators reach a safe state on every way out
}

TEST_P(RuntimeBoth, RestartPolicyRestartsUpToItsBound) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 100 } }
  bad: { type: examples.faulty, params: { fail_after: 5 }, on_error: { policy: restart, max_restarts: 2 } }
  m: { type: test.merge }
  sink: { type: examples.sink }
connections:
  - src.out -> bad.in
  - bad.out -> m.a
  - m.out -> sink.in
)"),
                 with(GetParam()));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::RuntimeError);
  EXPECT_NE(r.reason.find("after 2 restarts"), std::string::npos) << r.reason;
  EXPECT_EQ(r.components[1].restarts, 2u);
  EXPECT_EQ(r.components[1].samples_out, 15u);  // each incarnation forwards 5, then throws
}

TEST_P(RuntimeBoth, AStallIsReportedNotHung) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 100 } }
  quiet: { type: test.silent }
  pair: { type: test.pair }
  sink: { type: examples.sink }
connections:
  - { from: src.out, to: pair.a, capacity: 4 }
  - quiet.out -> pair.b
  - pair.sum -> sink.in
)"),
                 with(GetParam(), 20));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::RuntimeError);
  EXPECT_NE(r.reason.find("stalled"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("src: held back by the full lossless queue src.out -> pair.a"), std::string::npos) << r.reason;
}

// A periodic component waiting for what never comes: nothing outside the run moves the
// deterministic executor's clock, so once ten minutes of task time have passed with only its timer
// firing the run ends as stalled, naming it, instead of spinning through ticks for ever.
TEST(Runtime, ADeterministicRunWithOnlyTimersFiringEndsAsStalled) {
  fba::Task task(load(R"(
components:
  quiet: { type: test.silent, trigger: { policy: periodic, period: 0.02 } }
  sink: { type: examples.sink }
connections: [ quiet.out -> sink.in ]
)"),
                 with(ExecutorKind::Deterministic));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::RuntimeError);
  EXPECT_NE(r.reason.find("stalled: for 600 s of task time no component produced anything, only the timers of quiet fired"),
            std::string::npos)
      << r.reason;
}

TEST_P(RuntimeBoth, TimeoutStopsALongRun) {
  fba::Task task(load(chain(100000000, 1)), with(GetParam(), 0.3));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::RuntimeError);
  EXPECT_NE(r.reason.find("timed out"), std::string::npos) << r.reason;
}

TEST(Runtime, StopIsOrderlyWithFullQueuesAndABlockedComponent) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 100000000 } }
  slow: { type: examples.sink, params: { delay: 0.01 } }
  dev: { type: test.blocker }
connections:
  - { from: src.out, to: slow.in, capacity: 2 }
  - src.out -> dev.in
)"),
                 with(ExecutorKind::Threaded));
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    task.request_stop(Outcome::Interrupted, "interrupted by the test");
  });
  const auto r = task.run();
  stopper.join();
  EXPECT_EQ(r.outcome, Outcome::Interrupted);
  EXPECT_EQ(r.exit_code(), 130);
  EXPECT_TRUE(r.stuck.empty());  // interrupt() released the blocked component
  EXPECT_TRUE(has_event(r, "slow", "safe_state"));
}

namespace {
// The counter's values `start`, `start + 1`, ... drive test.staged (1: working, 2: done, 4: a bad result).
std::string staged(int count, int start) {
  return "components:\n  src: { type: examples.counter, params: { count: " + std::to_string(count) + ", start: " +
         std::to_string(start) + R"( } }
  st: { type: test.staged }
  sink: { type: examples.sink }
connections:
  - src.out -> st.in
  - st.out -> sink.in
)";
}
}  // namespace

TEST_P(RuntimeBoth, StagesAreObservableAsEventsAndInTheSummary) {
  fba::Task task(load(staged(2, 1)),
                 with(GetParam()));
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  std::vector<std::string> stages;
  for (const auto& e : r.events)
    if (e.name == "stage") stages.push_back(e.payload);
  EXPECT_EQ(stages, (std::vector<std::string>{"working", "done"}));
  EXPECT_EQ(r.components[1].stage, "done");
}

// The time per stage and the reported results, in the summary: where a component's work went, and
// what it found, without replaying its events.
TEST_P(RuntimeBoth, TheSummaryGivesEachStagesTimeAndTheReportedResults) {
  const auto cfg = load(staged(2, 1));
  fba::Task task(cfg, with(GetParam()));
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  const auto& st = r.components[1];
  ASSERT_EQ(st.name, "st");
  ASSERT_EQ(st.stages.size(), 3u);  // every declared stage, in the spec's order
  EXPECT_EQ(st.stages[0].first, "idle");
  EXPECT_EQ(st.stages[1].first, "working");
  EXPECT_EQ(st.stages[2].first, "done");
  // Busy time is wall time inside process(): the stages' together is within the run's.
  double busy = 0;
  for (const auto& [name, t] : st.stages) {
    EXPECT_EQ(t.entered, 1u) << name;
    busy += t.busy_s;
  }
  EXPECT_LE(busy, r.run_s());
  EXPECT_EQ(st.results, (std::map<std::string, std::string>{{"last", "2"}}));  // the later report replaced the first

  const auto j = nlohmann::json::parse(fba::summary_json(r, cfg));
  EXPECT_EQ(j["components"]["st"]["results"]["last"], 2);
  EXPECT_EQ(j["components"]["st"]["stages"]["working"]["entered"], 1);
  EXPECT_TRUE(j["components"]["st"]["stages"]["idle"]["busy_s"].is_number());
  EXPECT_FALSE(j["components"]["src"].contains("stages"));  // a component without stages has none
}

TEST(Runtime, AResultThatIsNotJsonIsAPluginBugNamingTheResult) {
  fba::Task task(load(staged(1, 4)),
                 with(ExecutorKind::Deterministic));
  const auto r = task.run();
  EXPECT_EQ(r.outcome, Outcome::RuntimeError);
  EXPECT_NE(r.reason.find("plugin bug"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("reported result 'last' is not one JSON value; it begins: {four"), std::string::npos) << r.reason;
  EXPECT_TRUE(r.components[1].results.empty());
}

TEST_P(RuntimeBoth, AFeedbackLoopRunsAndEndsWhenIdle) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 4, start: 3 } }
  m: { type: test.merge }
  c: { type: test.countdown }
connections:
  - src.out -> m.a
  - m.out -> c.in
  - { from: c.out, to: m.b, feedback: true }
)"),
                 with(GetParam()));
  const auto& merged = task.tap("m.out");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  // 3,4,5,6 each count down to 0 through the loop: 4+5+6+7 samples pass the merge.
  EXPECT_EQ(merged.size(), 22u);
}

TEST(Runtime, SummaryJsonHasOutcomeEventAndCounts) {
  const auto cfg = load(chain(10, 1));
  fba::Task task(cfg, with(ExecutorKind::Deterministic));
  const auto r = task.run();
  const std::string json = fba::summary_json(r, cfg);
  for (const char* key : {"\"outcome\": \"success\"", "\"final_event\"", "\"wall_time_s\"", "\"samples_out_per_s\"", "\"p0\""})
    EXPECT_NE(json.find(key), std::string::npos) << key << "\n" << json;
}
