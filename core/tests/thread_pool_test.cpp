// fba::ThreadPool: every index once, exceptions back to the caller, nested and concurrent use.
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

#include <fba/thread_pool.hpp>

TEST(ThreadPool, CallsEveryIndexExactlyOnce) {
  fba::ThreadPool pool(3);
  std::vector<std::atomic<int>> hits(1000);
  pool.parallel_for(hits.size(), [&](std::size_t i) { hits[i].fetch_add(1); });
  for (const auto& h : hits) EXPECT_EQ(h.load(), 1);
  pool.parallel_for(0, [](std::size_t) { FAIL(); });
}

TEST(ThreadPool, RethrowsTheFirstExceptionInTheCaller) {
  fba::ThreadPool pool(2);
  EXPECT_THROW(pool.parallel_for(100, [](std::size_t i) { if (i == 37) throw std::runtime_error("37"); }), std::runtime_error);
  std::atomic<int> n{0};
  pool.parallel_for(10, [&](std::size_t) { n.fetch_add(1); });  // still usable
  EXPECT_EQ(n.load(), 10);
}

TEST(ThreadPool, NestedAndConcurrentCallsComplete) {
  fba::ThreadPool pool(2);
  std::atomic<int> n{0};
  auto nested = [&] {
    pool.parallel_for(8, [&](std::size_t) { pool.parallel_for(8, [&](std::size_t) { n.fetch_add(1); }); });
  };
  std::thread other(nested);
  nested();
  other.join();
  EXPECT_EQ(n.load(), 2 * 64);
}
