// fba-run's Monitor: one sampling thread, each watcher called on its own schedule with the sample it
// was given before, stopped at once, a last call with the final result. Synchronised by what the
// watchers record (a latch, a promise), never by a clock: the periods are either one tick or an hour.
#include "monitor.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <latch>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace {

using fba_run::Monitor;
using namespace std::chrono_literals;

// A task's samples as the runtime's snapshot gives them, numbered: the n-th sample's wall_s is n.
struct Samples {
  std::atomic<int> taken{0};
  fba::RunResult operator()() {
    fba::RunResult r;
    r.wall_s = ++taken;
    return r;
  }
};

// What one watcher was given, call by call: (now, previous or -1).
struct Calls {
  std::mutex mutex;
  std::vector<std::pair<double, double>> seen;
  void add(const fba::RunResult& now, const fba::RunResult* previous) {
    std::lock_guard lock(mutex);
    seen.emplace_back(now.wall_s, previous ? previous->wall_s : -1);
  }
};

TEST(Monitor, EachWatcherIsGivenTheSampleItWasGivenBefore) {
  Samples samples;
  Monitor m([&] { return samples(); });
  Calls calls;
  std::latch five(5);
  m.watch([&](const fba::RunResult& now, const fba::RunResult* previous) {
    calls.add(now, previous);
    if (calls.seen.size() <= 5) five.count_down();
  });
  m.start(1ms);
  five.wait();
  m.stop();
  ASSERT_GE(calls.seen.size(), 5u);
  EXPECT_EQ(calls.seen[0].second, -1);  // the first call has none: rates since the start
  for (std::size_t i = 1; i < calls.seen.size(); ++i) {
    EXPECT_EQ(calls.seen[i].second, calls.seen[i - 1].first) << i;
    EXPECT_GT(calls.seen[i].first, calls.seen[i - 1].first) << i;
  }
}

TEST(Monitor, OneSampleServesEveryWatcherDueAtATick) {
  Samples samples;
  Monitor m([&] { return samples(); });
  Calls a, b;
  std::latch three(3);
  m.watch([&](const fba::RunResult& now, const fba::RunResult* previous) { a.add(now, previous); });
  m.watch([&](const fba::RunResult& now, const fba::RunResult* previous) {
    b.add(now, previous);
    if (b.seen.size() <= 3) three.count_down();
  });
  m.start(1ms);
  three.wait();
  m.stop();
  EXPECT_EQ(a.seen, b.seen);  // the same samples, not one each
  EXPECT_EQ(samples.taken.load(), static_cast<int>(a.seen.size()));
}

TEST(Monitor, AWatcherWithALongerPeriodIsCalledLessOften) {
  Samples samples;
  Monitor m([&] { return samples(); });
  Calls hourly;
  std::latch ticks(10);
  std::atomic<int> tick_calls{0};
  m.watch([&](const fba::RunResult& now, const fba::RunResult* previous) { hourly.add(now, previous); }, {.every = 1h});
  m.watch([&](const fba::RunResult&, const fba::RunResult*) {
    if (++tick_calls <= 10) ticks.count_down();
  });
  m.start(1ms);
  ticks.wait();
  m.stop();
  ASSERT_EQ(hourly.seen.size(), 1u);  // at the first tick only
  EXPECT_EQ(hourly.seen[0], std::make_pair(1.0, -1.0));
}

TEST(Monitor, AWatcherWhosePeriodIsTheTickIsCalledAtEveryTick) {
  Samples samples;
  Monitor m([&] { return samples(); });
  std::atomic<int> each_tick{0}, every_period{0};
  std::latch ten(10);
  m.watch([&](const fba::RunResult&, const fba::RunResult*) { ++every_period; }, {.every = 2ms});
  m.watch([&](const fba::RunResult&, const fba::RunResult*) {
    if (++each_tick <= 10) ten.count_down();
  });
  m.start(2ms);
  ten.wait();
  m.stop();
  EXPECT_EQ(every_period.load(), each_tick.load());  // however late each wake-up was
}

TEST(Monitor, StopEndsTheThreadAtOnceWithoutWaitingOutThePeriod) {
  Samples samples;
  Monitor m([&] { return samples(); });
  m.watch([](const fba::RunResult&, const fba::RunResult*) {});
  m.start(24h);
  m.stop();  // would wait a day if the wait did not see the stop
  EXPECT_EQ(samples.taken.load(), 0);
}

TEST(Monitor, ARequestedSampleReachesEveryWatcherWhateverItsSchedule) {
  Samples samples;
  Monitor m([&] { return samples(); });
  std::promise<double> given;
  m.watch([&](const fba::RunResult& now, const fba::RunResult*) { given.set_value(now.wall_s); },
          {.every = Monitor::kOnRequest});
  m.start(24h);
  m.request_sample();
  EXPECT_EQ(given.get_future().get(), 1.0);
  m.stop();
}

TEST(Monitor, FinishGivesTheFinalResultWithNoPreviousToAtEndWatchersOnly) {
  Samples samples;
  Monitor m([&] { return samples(); });
  Calls at_end, not_at_end;
  m.watch([&](const fba::RunResult& now, const fba::RunResult* previous) { at_end.add(now, previous); }, {.every = Monitor::kOnRequest});
  m.watch([&](const fba::RunResult& now, const fba::RunResult* previous) { not_at_end.add(now, previous); },
          {.every = Monitor::kOnRequest, .at_end = false});
  m.start(24h);
  fba::RunResult final_result;
  final_result.wall_s = 42;
  m.finish(final_result);
  ASSERT_EQ(at_end.seen.size(), 1u);
  EXPECT_EQ(at_end.seen[0], std::make_pair(42.0, -1.0));  // rates over the whole run
  EXPECT_TRUE(not_at_end.seen.empty());
}

TEST(Monitor, AWatcherThatThrowsIsStoppedAndTheOthersGoOn) {
  Samples samples;
  Monitor m([&] { return samples(); });
  std::atomic<int> thrower_calls{0}, other_calls{0};
  std::latch three(3);
  m.watch([&](const fba::RunResult&, const fba::RunResult*) {
    ++thrower_calls;
    throw std::runtime_error("cannot write the view");
  });
  m.watch([&](const fba::RunResult&, const fba::RunResult*) {
    if (++other_calls <= 3) three.count_down();
  });
  m.start(1ms);
  three.wait();
  m.finish(fba::RunResult{});
  EXPECT_EQ(thrower_calls.load(), 1);
  EXPECT_GE(other_calls.load(), 4);  // three ticks and the end
}

TEST(Monitor, WatchersAreRegisteredBeforeStartOnly) {
  Samples samples;
  Monitor m([&] { return samples(); });
  m.start(24h);
  EXPECT_THROW(m.watch([](const fba::RunResult&, const fba::RunResult*) {}), std::logic_error);
  EXPECT_THROW(m.start(1s), std::logic_error);
  m.stop();
  Monitor n([&] { return samples(); });
  EXPECT_THROW(n.start(0s), std::invalid_argument);
}

}  // namespace
