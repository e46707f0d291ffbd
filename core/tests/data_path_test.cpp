// The data path's rules: every sample accounted for, payloads freed outside the buffer's lock,
// delivered events with real headers, producer names that outlive the task, bounded payloads,
// durations that saturate, thread limits, and byte budgets.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <thread>

#include <fba/task.hpp>

#include "graph.hpp"
#include "fixture_components.hpp"
#include "support/child_process.hpp"

using fba::ExecutorKind;
using fba::Outcome;
using fba::test::load;
using fba::test::with;

namespace {

const fba::ConnectionStats& connection(const fba::RunResult& r, const std::string& to) {
  for (const auto& c : r.connections)
    if (c.to == to) return c;
  throw std::logic_error("no connection to " + to);
}

const fba::ComponentStats& component(const fba::RunResult& r, const std::string& name) {
  for (const auto& c : r.components)
    if (c.name == name) return c;
  throw std::logic_error("no component " + name);
}

void expect_every_sample_accounted_for(const fba::RunResult& r) {
  for (const auto& c : r.connections)
    EXPECT_EQ(c.pushed, c.delivered + c.dropped + c.left) << c.from << " -> " << c.to << ": pushed " << c.pushed
                                                          << ", delivered " << c.delivered << ", dropped " << c.dropped
                                                          << ", left " << c.left;
}

class DataPathBoth : public ::testing::TestWithParam<ExecutorKind> {};

// A payload whose destructor checks, from another thread, whether a buffer's lock is held.
struct LockProbe {
  fba::detail::PiMutex* lock = nullptr;
  bool* freed_under_lock = nullptr;
  ~LockProbe() {
    bool free = false;
    std::thread([&] {
      free = lock->try_lock();
      if (free) lock->unlock();
    }).join();
    if (!free) *freed_under_lock = true;
  }
};

}  // namespace

FBA_DATA_TYPE(LockProbe, "test.LockProbe", "A payload that reports being destroyed under a buffer's lock.");

INSTANTIATE_TEST_SUITE_P(Executors, DataPathBoth, ::testing::Values(ExecutorKind::Threaded, ExecutorKind::Deterministic),
                         [](const auto& info) { return std::string(fba::to_string(info.param)); });

// --- accounting -------------------------------------------------------------------------------

TEST_P(DataPathBoth, SamplesLeftInQueuesAtTheStopAreCountedNotDelivered) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 100000 } }
  mid: { type: examples.passthrough }
  sink: { type: examples.sink, params: { expected: 100 } }
connections:
  - { from: src.out, to: mid.in, capacity: 16 }
  - { from: mid.out, to: sink.in, capacity: 16 }
on:
  sink.done: stop_success
)"),
                 with(GetParam()));
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  expect_every_sample_accounted_for(r);
  const auto& to_sink = connection(r, "sink.in");
  EXPECT_EQ(to_sink.delivered, component(r, "sink").samples_in);  // delivered means taken by the component
  EXPECT_EQ(connection(r, "mid.in").pushed, component(r, "src").samples_out);
  if (GetParam() == ExecutorKind::Deterministic) {
    // FIFO order: the counter fills both queues before the sink's 100th sample stops the run.
    std::uint64_t left = 0;
    for (const auto& c : r.connections) left += c.left;
    EXPECT_GT(left, 0u);
    EXPECT_EQ(to_sink.delivered, 100u);
  }
}

TEST_P(DataPathBoth, DroppedSamplesAreCountedForEveryPolicy) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 5000 } }
  a: { type: test.countdown }
  b: { type: test.countdown }
connections:
  - { from: src.out, to: a.in, buffer: latest }
  - { from: src.out, to: b.in, buffer: drop_oldest, capacity: 2 }
)"),
                 with(GetParam()));
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  expect_every_sample_accounted_for(r);
  EXPECT_EQ(connection(r, "a.in").pushed, 5000u);
  EXPECT_EQ(connection(r, "b.in").pushed, 5000u);
  if (GetParam() == ExecutorKind::Deterministic) {  // the counter runs 64 samples at a time
    EXPECT_GT(connection(r, "a.in").dropped, 0u);
    EXPECT_GT(connection(r, "b.in").dropped, 0u);
  }
}

TEST(DataPath, AnAllTriggersUnmatchedSamplesAreCountedAsDroppedNotDelivered) {
  // At 100 Hz and 50 Hz on the virtual clock, every second sample of a has no partner.
  fba::Task task(load(R"(
components:
  a: { type: examples.counter, params: { count: 20, rate: 100 } }
  b: { type: examples.counter, params: { count: 10, rate: 50 } }
  pair: { type: test.pair }
  sink: { type: examples.sink }
connections:
  - a.out -> pair.a
  - b.out -> pair.b
  - pair.sum -> sink.in
)"),
                 with(ExecutorKind::Deterministic));
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  expect_every_sample_accounted_for(r);
  EXPECT_EQ(connection(r, "pair.a").pushed, 20u);
  EXPECT_EQ(connection(r, "pair.a").delivered, 10u);
  EXPECT_EQ(connection(r, "pair.a").dropped + connection(r, "pair.a").left, 10u);
  EXPECT_EQ(connection(r, "pair.b").delivered, 10u);
}

TEST(DataPath, SummaryListsPushedDeliveredDroppedAndLeft) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 1000 } }
  sink: { type: examples.sink, params: { expected: 10 } }
connections: [ src.out -> sink.in ]
on:
  sink.done: stop_success
)"),
                 with(ExecutorKind::Deterministic));
  const auto r = task.run();
  const std::string json = fba::summary_json(r, fba::TaskConfig{});
  for (const char* key : {"\"pushed\"", "\"delivered\"", "\"dropped\"", "\"left\"", "\"peak\"", "\"peak_bytes\""})
    EXPECT_NE(json.find(key), std::string::npos) << key;
}

// --- payloads are freed outside the buffer's lock ----------------------------------------------

TEST(DataPath, DisplacedAndPreviousPayloadsAreFreedOutsideTheBufferLock) {
  for (auto policy : {fba::BufferPolicy::Latest, fba::BufferPolicy::DropOldest, fba::BufferPolicy::Lossless}) {
    bool freed_under_lock = false;
    fba::detail::Buffer b;
    b.policy = policy;
    b.capacity = 1;
    auto probe = [&] {
      return fba::Packet::make<LockProbe>(std::make_shared<const LockProbe>(LockProbe{&b.mutex, &freed_under_lock}));
    };
    b.push(probe());
    if (policy != fba::BufferPolicy::Lossless) b.push(probe());  // displaces the first
    fba::Packet current = probe();
    bool was_full = false;
    ASSERT_TRUE(b.pop(current, was_full));  // frees the input's previous sample
    b.push(probe());
    ASSERT_TRUE(b.drop_head(was_full));
    current = fba::Packet();
    EXPECT_FALSE(freed_under_lock) << "policy " << fba::to_string(policy);
  }
}

// --- order ---------------------------------------------------------------------------------------

// The queue is a ring that grows by doubling: a growth while the ring has wrapped round (its head
// past the start of its slots) must keep the samples in the order they came.
TEST(DataPath, ALosslessQueueKeepsItsOrderThroughWrapsAndGrowth) {
  fba::detail::Buffer b;
  b.capacity = 1000;
  std::int64_t next_in = 0, next_out = 0;
  auto push = [&](int n) {
    for (int i = 0; i < n; ++i) b.push(fba::Packet::make<std::int64_t>(std::make_shared<const std::int64_t>(next_in++), {}));
  };
  auto pop = [&](int n) {
    for (int i = 0; i < n; ++i) {
      fba::Packet p;
      bool was_full = false;
      ASSERT_TRUE(b.pop(p, was_full));
      EXPECT_EQ(p.get<std::int64_t>(), next_out++);
    }
  };
  // 5 in, 3 out, 6 in: the ring of 8 wraps; 4 more make it grow while wrapped; then past 16 and 32.
  push(5), pop(3), push(6), push(4), pop(7), push(30), pop(25), push(40);
  EXPECT_EQ(b.queued(), static_cast<std::size_t>(next_in - next_out));
  pop(static_cast<int>(next_in - next_out));
  fba::Packet none;
  bool was_full = false;
  EXPECT_FALSE(b.pop(none, was_full));
  EXPECT_EQ(b.pushed, b.consumed);
}

// --- delivered events --------------------------------------------------------------------------

TEST_P(DataPathBoth, DeliveredEventsCarryASequenceAndTheirProducer) {
  // The faulty component fails on every sixth sample and is restarted: three 'error' events,
  // delivered to a sink that refuses a gap or a repeat in any producer's sequence.
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 20 } }
  f: { type: examples.faulty, params: { fail_after: 5 }, on_error: { policy: restart, max_restarts: 10 } }
  cd: { type: test.countdown }
  sink: { type: examples.sink }
connections: [ src.out -> f.in, f.out -> cd.in ]
on:
  f.error: { deliver: sink.in }
  sink.gap: stop_failure
)"),
                 with(GetParam()));
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  EXPECT_EQ(component(r, "f").errors, 3u);
  EXPECT_EQ(component(r, "sink").samples_in, 3u);
  const auto& events = connection(r, "sink.in");
  EXPECT_EQ(events.from, "events");
  EXPECT_EQ(events.delivered, 3u);
}

TEST(DataPath, DeliveredEventsAreNamedComponentDotEvent) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 3 } }
  log: { type: test.event_log }
on:
  src.finished: { deliver: log.events }
)"),
                 with(ExecutorKind::Deterministic));
  const auto& names = task.tap("log.names");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  ASSERT_EQ(names.size(), 1u);
  EXPECT_EQ(names[0].get<std::string>(), "src.finished");
}

// --- producer names outlive the task -----------------------------------------------------------

TEST(DataPath, APacketKeptAfterItsTaskStillNamesItsProducer) {
  fba::Packet kept;
  {
    fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 5 } }
  sink: { type: examples.sink }
connections: [ src.out -> sink.in ]
)"),
                   with(ExecutorKind::Deterministic));
    const auto& seen = task.tap("src.out");
    ASSERT_EQ(task.run().outcome, Outcome::Success);
    ASSERT_EQ(seen.size(), 5u);
    kept = seen.back();
  }
  ASSERT_NE(kept.header().producer, nullptr);
  EXPECT_EQ(*kept.header().producer, "src.out");  // under AddressSanitizer, a dangling name is an error
  EXPECT_EQ(kept.get<std::int64_t>(), 4);
}

// --- bounded event payloads --------------------------------------------------------------------

TEST(DataPath, AnEventPayloadOverTheLimitIsTruncatedWithAMarker) {
  const std::string message(1 << 20, 'x');  // a 1 MiB exception message becomes an 'error' event
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 3 } }
  f: { type: examples.faulty, params: { fail_after: 0, message: ")" + message + R"(" } }
connections: [ src.out -> f.in ]
)"),
                 with(ExecutorKind::Deterministic));
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::RuntimeError);
  EXPECT_LE(r.reason.size(), fba::detail::kMaxEventPayload + 200);
  bool found = false;
  for (const auto& e : r.events) {
    if (e.name != "error") continue;
    found = true;
    EXPECT_LE(e.payload.size(), fba::detail::kMaxEventPayload);
    EXPECT_NE(e.payload.find("[truncated: "), std::string::npos);
  }
  EXPECT_TRUE(found);
}

TEST(DataPath, AnEventOverTheLimitIsTruncatedAndAPayloadAtTheLimitIsNot) {
  for (std::size_t bytes : {fba::detail::kMaxEventPayload, fba::detail::kMaxEventPayload + 1, std::size_t{3} << 20}) {
    fba::Task task(load("components:\n  s: { type: test.shout, params: { bytes: " + std::to_string(bytes) + " } }\n"),
                   with(ExecutorKind::Deterministic));
    const auto r = task.run();
    ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
    std::size_t said = 0;
    for (const auto& e : r.events) {
      if (e.name != "said") continue;
      ++said;
      EXPECT_LE(e.payload.size(), fba::detail::kMaxEventPayload);
      const bool truncated = e.payload.find("[truncated: " + std::to_string(bytes) + " bytes in all]") != std::string::npos;
      EXPECT_EQ(truncated, bytes > fba::detail::kMaxEventPayload) << bytes;
    }
    EXPECT_EQ(said, 1u);
  }
}

TEST(DataPath, TheFinalEventIsWrittenOnceInTheSummary) {
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 100 } }
  sink: { type: examples.sink, params: { expected: 42 } }
connections: [ src.out -> sink.in ]
on:
  sink.done: stop_success
)"),
                 with(ExecutorKind::Deterministic));
  const auto r = task.run();
  ASSERT_TRUE(r.final_event && r.final_event_index);
  EXPECT_EQ(r.events.at(*r.final_event_index).name, "done");
  const std::string json = fba::summary_json(r, fba::TaskConfig{});
  std::size_t copies = 0;
  for (auto at = json.find("\"42\""); at != std::string::npos; at = json.find("\"42\"", at + 1)) ++copies;
  EXPECT_EQ(copies, 1u) << json;
  EXPECT_NE(json.find("\"index\""), std::string::npos);
}

// --- durations saturate ------------------------------------------------------------------------

TEST(DataPath, DurationsBeyondTheClockRangeSaturate) {
  using fba::detail::duration_ns;
  using fba::detail::kNeverNs;
  EXPECT_EQ(duration_ns(1.5), 1'500'000'000);
  EXPECT_EQ(duration_ns(1e10), kNeverNs);
  EXPECT_EQ(duration_ns(1e308), kNeverNs);
  EXPECT_EQ(duration_ns(std::numeric_limits<double>::infinity()), kNeverNs);
  EXPECT_EQ(duration_ns(std::nan("")), kNeverNs);
  EXPECT_EQ(fba::detail::add_ns(kNeverNs - 5, 10), kNeverNs);
}

TEST_P(DataPathBoth, APeriodBeyondTheClockRangeNeverTicksAgain) {
  // A task file cannot ask for such a period (the loader and set_trigger refuse more than 1e9 s),
  // but a configuration built in code can: a period of 1e10 s is past int64 nanoseconds. One
  // tick at the start, then none, and the stall says why.
  auto config = load(R"(
components:
  src: { type: examples.counter, params: { count: 5 } }
  sink: { type: examples.sink }
connections: [ src.out -> sink.in ]
)");
  config.components[0].trigger = fba::Trigger{fba::TriggerPolicy::Periodic, 1e10};
  fba::Task task(config, with(GetParam()));
  const auto r = task.run();
  EXPECT_EQ(component(r, "sink").samples_in, 1u);
  EXPECT_EQ(r.outcome, Outcome::RuntimeError);
  EXPECT_NE(r.reason.find("stalled"), std::string::npos) << r.reason;
}

TEST(DataPath, ARateWhosePeriodIsBeyondTheDocumentedRangeIsRefused) {
  try {
    fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 5, rate: 1e-10 } }
  sink: { type: examples.sink }
connections: [ src.out -> sink.in ]
)"));
    FAIL() << "rate 1e-10 was accepted";
  } catch (const fba::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("(0, 1000000000] seconds"), std::string::npos) << e.what();
  }
}

TEST_P(DataPathBoth, ATimeoutBeyondTheClockRangeMeansNoLimit) {
  for (double timeout : {9.3e9, 1e308, std::numeric_limits<double>::infinity()}) {
    fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 100 } }
  sink: { type: examples.sink }
connections: [ src.out -> sink.in ]
)"),
                   with(GetParam(), timeout));
    const auto r = task.run();
    EXPECT_EQ(r.outcome, Outcome::Success) << "timeout " << timeout << ": " << r.reason;
  }
}

// --- threads ------------------------------------------------------------------------------------

TEST(DataPath, MoreWorkersThanTheLimitAreRefusedUpFront) {
  auto config = load("components:\n  src: { type: examples.counter, params: { count: 1 } }\n");
  fba::RunOptions o;
  o.threads = 100000;
  try {
    fba::Task task(config, o);
    FAIL() << "100000 workers accepted";
  } catch (const fba::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("[0, 256]"), std::string::npos) << e.what();
  }
}

TEST(DataPath, MoreDedicatedThreadsThanTheLimitAreRefusedUpFront) {
  std::string y = "components:\n";
  for (int i = 0; i < 1025; ++i) y += "  c" + std::to_string(i) + ": { type: examples.counter, thread: dedicated }\n";
  try {
    fba::Task task(load(y), with(ExecutorKind::Threaded));
    FAIL() << "1025 dedicated threads accepted";
  } catch (const fba::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("at most 1024"), std::string::npos) << e.what();
  }
}

TEST(DataPath, ManyMoreWorkersThanCoresStillDeliverEverything) {
  fba::RunOptions o = with(ExecutorKind::Threaded);
  o.threads = 256;
  fba::Task task(load(R"(
components:
  src: { type: examples.counter, params: { count: 5000 } }
  a: { type: examples.passthrough }
  b: { type: examples.passthrough }
  sink: { type: examples.sink, params: { expected: 5000 } }
connections:
  - { from: src.out, to: a.in, capacity: 1 }
  - { from: a.out, to: b.in, capacity: 1 }
  - { from: b.out, to: sink.in, capacity: 1 }
on:
  sink.done: stop_success
  sink.gap: stop_failure
)"),
                 o);
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  expect_every_sample_accounted_for(r);
}

#ifndef FBA_TEST_SANITIZED
TEST(DataPath, AThreadThatCannotStartEndsTheRunAsARuntimeErrorWithSafeStates) {
  // In a child process whose address space has room for a few thread stacks only: the workers
  // that cannot start make the run end in order (the sanitizers need their own address space).
  auto config = load(R"(
components:
  src: { type: examples.counter, params: { count: 1000000 } }
  sink: { type: examples.sink }
connections: [ src.out -> sink.in ]
)");
  fba::RunOptions o = with(ExecutorKind::Threaded);
  o.threads = 200;
  fba::Task task(config, o);
  const auto child = fba::test::in_child_process([&] {
    std::size_t vm_kib = 0;
    std::ifstream status("/proc/self/status");
    for (std::string key; status >> key;)
      if (key == "VmSize:") status >> vm_kib;
    const rlim_t limit = (vm_kib + 64 * 1024) * 1024;  // 64 MiB more: a few 8 MiB stacks
    const rlimit rl{limit, limit};
    if (setrlimit(RLIMIT_AS, &rl) != 0) return 10;
    const auto r = task.run();
    bool safe = false;
    for (const auto& e : r.events) safe |= e.source == "sink" && e.name == "safe_state";
    if (r.outcome != Outcome::RuntimeError) return 11;
    if (r.reason.find("could not start worker thread") == std::string::npos) return 12;
    return safe ? 0 : 13;
  });
  ASSERT_EQ(child.signal, 0) << "the child died of signal " << child.signal;
  EXPECT_EQ(child.status, 0) << "10: no limit set, 11: not a runtime error, 12: no message, 13: no safe state";
}
#endif

// --- byte budgets --------------------------------------------------------------------------------

TEST_P(DataPathBoth, ALosslessQueueOverItsByteBudgetHoldsItsProducerBack) {
  auto config = load(R"(
components:
  src: { type: examples.counter, params: { count: 2000 } }
  sink: { type: examples.sink, params: { expected: 2000 } }
connections:
  - { from: src.out, to: sink.in, capacity: 1000 }
on:
  sink.done: stop_success
  sink.gap: stop_failure
)");
  ASSERT_EQ(config.connections.size(), 1u);
  config.connections[0].max_bytes = 10 * sizeof(std::int64_t);
  fba::Task task(config, with(GetParam()));
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  const auto& c = connection(r, "sink.in");
  EXPECT_EQ(c.delivered, 2000u);
  EXPECT_LE(c.peak_bytes, 10 * sizeof(std::int64_t));
  EXPECT_LE(c.peak, 10u);
  EXPECT_GT(c.peak, 0u);
}

TEST(DataPath, ASampleLargerThanTheBudgetStillPasses) {
  fba::detail::Buffer b;
  b.gating = true;
  b.capacity = 16;
  b.max_bytes = 100;
  auto big = fba::Packet::make<std::string>(std::make_shared<const std::string>(1000, 'x'));
  EXPECT_GT(big.bytes(), 1000u);
  EXPECT_FALSE(b.full());
  b.push(std::move(big));
  EXPECT_TRUE(b.full());  // over budget: the producer waits until it is taken
  fba::Packet out;
  bool was_full = false;
  ASSERT_TRUE(b.pop(out, was_full));
  EXPECT_TRUE(was_full);
  EXPECT_FALSE(b.full());
  EXPECT_EQ(b.bytes.load(), 0u);
}

TEST(DataPath, DropOldestKeepsItsQueueWithinTheByteBudget) {
  fba::detail::Buffer b;
  b.policy = fba::BufferPolicy::DropOldest;
  b.capacity = 100;
  b.max_bytes = 3 * sizeof(std::int64_t);
  for (std::int64_t i = 0; i < 10; ++i) b.push(fba::Packet::make<std::int64_t>(std::make_shared<const std::int64_t>(i)));
  EXPECT_EQ(b.queued(), 3u);
  EXPECT_EQ(b.dropped, 7u);
  EXPECT_EQ(b.pushed, b.consumed + b.dropped + b.queued());
}
