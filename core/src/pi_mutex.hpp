// A mutex with priority inheritance, for the locks that worker threads take on the data path.
// Not part of the public API.
#pragma once

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <system_error>

namespace fba::detail {

// A thread holding a priority-inheriting lock runs at the priority of the highest waiter, so a
// low-priority holder preempted by a medium-priority thread cannot keep a real-time thread waiting
// without bound (priority inversion), which a plain std::mutex allows. Lockable: std::lock_guard
// and std::unique_lock work; wait on it with std::condition_variable_any.
//
// The kernel's PI-futex protocol, which glibc's PTHREAD_PRIO_INHERIT mutex also uses: the word
// holds the owner's thread id, taken and released by one compare-and-swap when nobody waits; a
// waiter asks the kernel (FUTEX_LOCK_PI), which boosts the owner and sets FUTEX_WAITERS, so the
// owner's swap fails and it releases through the kernel (FUTEX_UNLOCK_PI). glibc's general mutex
// code around the same swaps cost four times as much per lock as std::mutex; a sample crosses two
// such locks per hop.
class PiMutex {
 public:
  PiMutex() = default;
  PiMutex(const PiMutex&) = delete;
  PiMutex& operator=(const PiMutex&) = delete;

  void lock() {
    int expected = 0;
    if (word_.compare_exchange_strong(expected, self(), std::memory_order_acquire, std::memory_order_relaxed)) return;
    lock_contended();
  }
  bool try_lock() {
    int expected = 0;
    return word_.compare_exchange_strong(expected, self(), std::memory_order_acquire, std::memory_order_relaxed);
  }
  void unlock() {
    int expected = self();
    if (word_.compare_exchange_strong(expected, 0, std::memory_order_release, std::memory_order_relaxed)) return;
    unlock_contended();
  }
  // The futex word as the kernel sees it: the owner's thread id (with FUTEX_WAITERS while someone
  // waits), 0 when free. For checks.
  int owner_word() const { return word_.load(std::memory_order_relaxed); }

 private:
  // The caller's thread id, read once per thread. Initial-exec TLS: libfba is loaded with the
  // program, and the default model for a shared library called __tls_get_addr on every lock.
  static int self() {
    [[gnu::tls_model("initial-exec")]] static thread_local int tid = 0;
    if (tid == 0) tid = static_cast<int>(syscall(SYS_gettid));
    return tid;
  }
  void lock_contended() {
    // Retried on EINTR; any other error is misuse (EDEADLK: a relock by the holder) or the kernel's
    // bookkeeping running out (ENOMEM), reported like std::mutex would.
    while (syscall(SYS_futex, word_ptr(), FUTEX_LOCK_PI_PRIVATE, 0, nullptr, nullptr, 0) != 0)
      if (errno != EINTR) throw std::system_error(errno, std::generic_category(), "PiMutex::lock");
    // The kernel handed the lock over without an atomic of ours: this load takes the release of the
    // previous owner's unlock (its fetch_add below), for the memory model and ThreadSanitizer.
    (void)word_.load(std::memory_order_acquire);
  }
  void unlock_contended() {
    (void)word_.fetch_add(0, std::memory_order_release);  // publishes this holder's writes first
    syscall(SYS_futex, word_ptr(), FUTEX_UNLOCK_PI_PRIVATE, 0, nullptr, nullptr, 0);
  }
  int* word_ptr() { return reinterpret_cast<int*>(&word_); }

  static_assert(sizeof(std::atomic<int>) == sizeof(int) && std::atomic<int>::is_always_lock_free);
  std::atomic<int> word_{0};
};

}  // namespace fba::detail
