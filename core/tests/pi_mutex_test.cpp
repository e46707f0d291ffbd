// The data path's lock: a mutex with priority inheritance that works with the standard lock types.
#include <gtest/gtest.h>

#include <sys/syscall.h>
#include <linux/futex.h>
#include <unistd.h>

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "pi_mutex.hpp"

using fba::detail::PiMutex;

TEST(PiMutex, HoldsItsOwnersThreadIdAsTheKernelsPriorityInheritanceProtocolRequires) {
  // What the kernel sees: a priority-inheriting lock's futex word holds its owner's thread id (so
  // that FUTEX_LOCK_PI can boost that thread), where a plain mutex holds 1 or 2.
  PiMutex m;
  EXPECT_EQ(m.owner_word(), 0);
  {
    std::lock_guard lock(m);
    EXPECT_EQ(m.owner_word(), static_cast<int>(syscall(SYS_gettid)));
  }
  EXPECT_EQ(m.owner_word(), 0);
}

// A waiter goes through the kernel (FUTEX_LOCK_PI), which marks the word; the owner's release then
// goes through the kernel too, and hands the lock to the waiter.
TEST(PiMutex, AWaiterIsMarkedInTheWordAndGetsTheLockWhenReleased) {
  PiMutex m;
  std::unique_lock lock(m);
  std::atomic<bool> got{false};
  std::thread waiter([&] {
    std::lock_guard l(m);
    got = true;
  });
  while ((m.owner_word() & FUTEX_WAITERS) == 0) std::this_thread::yield();
  EXPECT_FALSE(got.load());
  lock.unlock();
  waiter.join();
  EXPECT_TRUE(got.load());
  EXPECT_EQ(m.owner_word(), 0);
}

TEST(PiMutex, ExcludesOtherThreads) {
  PiMutex m;
  long count = 0;  // a data race here is what ThreadSanitizer would report
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&] {
      for (int i = 0; i < 10000; ++i) {
        std::lock_guard lock(m);
        ++count;
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(count, 40000);
}

TEST(PiMutex, TryLockFailsWhileAnotherThreadHoldsIt) {
  PiMutex m;
  std::unique_lock lock(m);
  bool got = true;
  std::thread([&] {
    got = m.try_lock();
    if (got) m.unlock();
  }).join();
  EXPECT_FALSE(got);
  lock.unlock();
  std::thread([&] {
    got = m.try_lock();
    if (got) m.unlock();
  }).join();
  EXPECT_TRUE(got);
}

TEST(PiMutex, WaitsWithAConditionVariable) {
  PiMutex m;
  std::condition_variable_any cv;
  int turn = 0;  // ping-pong between two threads, each waiting for its turn under the lock
  auto player = [&](int me) {
    for (int i = 0; i < 1000; ++i) {
      std::unique_lock lock(m);
      cv.wait(lock, [&] { return turn % 2 == me; });
      ++turn;
      cv.notify_all();
    }
  };
  std::thread a(player, 0), b(player, 1);
  a.join();
  b.join();
  EXPECT_EQ(turn, 2000);
}
