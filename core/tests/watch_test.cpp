// Task::watch: the newest sample of an output, taken by a reader on another thread while the task
// runs (the live view). Run under ThreadSanitizer by tools/dev.sh test.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include <fba/task.hpp>
#include <fba/view.hpp>

#include "fixture_components.hpp"

using fba::ExecutorKind;
using fba::Outcome;
using fba::test::load;
using fba::test::with;

namespace {

std::string chain(int count) {
  return R"(
components:
  src: { type: examples.counter, params: { count: )" +
         std::to_string(count) + R"( } }
  pass: { type: examples.passthrough }
  sink: { type: examples.sink, params: { expected: )" +
         std::to_string(count) + R"( } }
connections:
  - src.out -> pass.in
  - pass.out -> sink.in
on:
  sink.done: stop_success
  sink.gap: stop_failure
)";
}

// Takes from `w` until `done` is set, then once more: what a live view's server does.
std::vector<fba::Packet> read_until(fba::LatestSample& w, const std::atomic<bool>& done) {
  std::vector<fba::Packet> taken;
  for (;;) {
    const bool last_round = done.load(std::memory_order_acquire);
    if (auto p = w.take()) taken.push_back(std::move(*p));
    else if (last_round) return taken;
    else std::this_thread::yield();
  }
}

class WatchBoth : public ::testing::TestWithParam<ExecutorKind> {};

}  // namespace

INSTANTIATE_TEST_SUITE_P(Executors, WatchBoth, ::testing::Values(ExecutorKind::Threaded, ExecutorKind::Deterministic),
                         [](const auto& info) { return std::string(fba::to_string(info.param)); });

TEST_P(WatchBoth, AReaderTakesProducedSamplesInOrderAndSeesTheLast) {
  constexpr int kCount = 20000;
  fba::Task task(load(chain(kCount)), with(GetParam()));
  const auto& produced = task.tap("pass.out");
  const auto watched = task.watch("pass.out");
  std::atomic<bool> done{false};
  std::vector<fba::Packet> taken;
  std::thread reader([&] { taken = read_until(*watched, done); });
  const auto r = task.run();
  done.store(true, std::memory_order_release);
  reader.join();

  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  ASSERT_EQ(produced.size(), static_cast<std::size_t>(kCount));
  ASSERT_FALSE(taken.empty());
  std::uint64_t previous = 0;
  for (std::size_t i = 0; i < taken.size(); ++i) {
    const auto seq = taken[i].header().seq;
    ASSERT_LT(seq, produced.size());
    if (i > 0) ASSERT_GT(seq, previous) << "taken out of order";
    previous = seq;
    // The very object the port sent, not a copy or another port's.
    EXPECT_EQ(&taken[i].get<std::int64_t>(), &produced[seq].get<std::int64_t>());
    EXPECT_EQ(*taken[i].header().producer, "src.out");  // the passthrough forwards headers untouched
  }
  EXPECT_EQ(taken.back().header().seq, static_cast<std::uint64_t>(kCount - 1));
  EXPECT_EQ(watched->offered(), static_cast<std::uint64_t>(kCount));
  EXPECT_EQ(watched->superseded() + taken.size(), watched->offered());
}

TEST_P(WatchBoth, AReaderThatNeverTakesHoldsNoProducerBack) {
  constexpr int kCount = 5000;
  fba::Task task(load(chain(kCount)), with(GetParam()));
  const auto watched = task.watch("src.out");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, Outcome::Success) << r.reason;
  EXPECT_EQ(r.connections.size(), 2u) << "a watch is not a connection of the task";
  EXPECT_EQ(watched->superseded(), static_cast<std::uint64_t>(kCount - 1));
  const auto last = watched->take();
  ASSERT_TRUE(last);
  EXPECT_EQ(last->get<std::int64_t>(), kCount - 1);
  EXPECT_FALSE(watched->take()) << "a sample is taken once";
}

// keep > 1 (a view that shows every sample, the poses visited): each sample not taken yet waits, in
// order, up to `keep`; beyond, the oldest go, counted as superseded.
TEST(Watch, KeepingSamplesHandsEachInOrderUpToTheBound) {
  fba::Task task(load(chain(10)), with(ExecutorKind::Deterministic));
  const auto every = task.watch("pass.out", 16);
  const auto bounded = task.watch("pass.out", 4);
  ASSERT_EQ(task.run().outcome, Outcome::Success);
  for (std::uint64_t seq = 0; seq < 10; ++seq) {
    const auto p = every->take();
    ASSERT_TRUE(p) << "sample " << seq << " was not kept";
    EXPECT_EQ(p->header().seq, seq);
  }
  EXPECT_FALSE(every->take());
  EXPECT_EQ(every->superseded(), 0u);
  for (std::uint64_t seq = 6; seq < 10; ++seq) EXPECT_EQ(bounded->take()->header().seq, seq);  // the newest 4, oldest first
  EXPECT_FALSE(bounded->take());
  EXPECT_EQ(bounded->superseded(), 6u);
}

TEST(Watch, TwoReadersOfOnePortEachGetTheNewest) {
  fba::Task task(load(chain(10)), with(ExecutorKind::Deterministic));
  const auto a = task.watch("pass.out");
  const auto b = task.watch("pass.out");
  ASSERT_EQ(task.run().outcome, Outcome::Success);
  EXPECT_EQ(a->take()->header().seq, 9u);
  EXPECT_EQ(b->take()->header().seq, 9u);
}

TEST(Watch, TheNewestSampleOutlivesItsTask) {
  std::shared_ptr<fba::LatestSample> watched;
  {
    fba::Task task(load(chain(3)), with(ExecutorKind::Threaded));
    watched = task.watch("src.out");
    ASSERT_EQ(task.run().outcome, Outcome::Success);
  }
  const auto last = watched->take();
  ASSERT_TRUE(last);
  EXPECT_EQ(last->get<std::int64_t>(), 2);
  EXPECT_EQ(*last->header().producer, "src.out");
}

TEST(Watch, KnowsItsPortAndType) {
  fba::Task task(load(chain(1)), with(ExecutorKind::Deterministic));
  const auto watched = task.watch("src.out");
  EXPECT_EQ(watched->port(), "src.out");
  ASSERT_NE(watched->type(), nullptr);
  EXPECT_EQ(watched->type()->name, "fba.Int");
}

TEST(Watch, AnUnknownPortOrAWatchAfterTheRunIsRefused) {
  fba::Task task(load(chain(1)), with(ExecutorKind::Deterministic));
  EXPECT_THROW(task.watch("src"), std::invalid_argument);
  EXPECT_THROW(task.watch("src.nothing"), std::invalid_argument);
  ASSERT_EQ(task.run().outcome, Outcome::Success);
  EXPECT_THROW(task.watch("src.out"), std::logic_error);
}

namespace {
std::string int_view(const fba::Packet& p) { return std::to_string(p.get<std::int64_t>()); }
}  // namespace

TEST(Views, ARegisteredViewIsFoundByItsTypeAndCanBeRemoved) {
  const fba::TypeInfo* type = fba::type_of<std::int64_t>();
  EXPECT_EQ(fba::find_view(nullptr), nullptr);
  fba::register_view("fba.Int", &int_view);
  ASSERT_EQ(fba::find_view(type), &int_view);
  EXPECT_EQ(fba::find_view(type)(fba::Packet::make(std::make_shared<const std::int64_t>(7))), "7");
  EXPECT_EQ(fba::viewed_samples(type), fba::ViewedSamples::Newest);  // unless registered otherwise
  fba::register_view("fba.Int", &int_view, fba::ViewedSamples::Every);
  EXPECT_EQ(fba::viewed_samples(type), fba::ViewedSamples::Every);
  fba::register_view("fba.Int", nullptr);
  EXPECT_EQ(fba::find_view(type), nullptr);
  EXPECT_EQ(fba::viewed_samples(type), fba::ViewedSamples::Newest);
  EXPECT_EQ(fba::viewed_samples(nullptr), fba::ViewedSamples::Newest);
}
