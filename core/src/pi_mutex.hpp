// A mutex with priority inheritance, for the locks that worker threads take on the data path.
// Not part of the public API.
#pragma once

#include <pthread.h>

#include <cerrno>
#include <system_error>

namespace fba::detail {

// A thread holding a PTHREAD_PRIO_INHERIT mutex runs at the priority of the highest waiter, so a
// low-priority holder preempted by a medium-priority thread cannot keep a real-time thread waiting
// without bound (priority inversion), which a plain std::mutex allows. Lockable: std::lock_guard
// and std::unique_lock work; wait on it with std::condition_variable_any.
class PiMutex {
 public:
  PiMutex() {
    pthread_mutexattr_init(&attr_);
    int rc = pthread_mutexattr_setprotocol(&attr_, PTHREAD_PRIO_INHERIT);
    if (rc == 0) rc = pthread_mutex_init(&m_, &attr_);
    if (rc != 0) {
      pthread_mutexattr_destroy(&attr_);
      throw std::system_error(rc, std::generic_category(), "a priority-inheriting mutex");
    }
  }
  ~PiMutex() {
    pthread_mutex_destroy(&m_);
    pthread_mutexattr_destroy(&attr_);
  }
  PiMutex(const PiMutex&) = delete;
  PiMutex& operator=(const PiMutex&) = delete;

  void lock() {
    // Fails only on misuse (a relock by the holder is EDEADLK), or EAGAIN/ENOMEM from the kernel's
    // priority-inheritance bookkeeping: report it like std::mutex would.
    if (const int rc = pthread_mutex_lock(&m_); rc != 0) throw std::system_error(rc, std::generic_category(), "PiMutex::lock");
  }
  bool try_lock() { return pthread_mutex_trylock(&m_) == 0; }
  void unlock() { pthread_mutex_unlock(&m_); }
  pthread_mutex_t* native_handle() { return &m_; }
  // The protocol the mutex was initialised with (PTHREAD_PRIO_INHERIT), kept for checks.
  int protocol() const {
    int p = -1;
    pthread_mutexattr_getprotocol(&attr_, &p);
    return p;
  }

 private:
  pthread_mutex_t m_;
  pthread_mutexattr_t attr_;
};

}  // namespace fba::detail
