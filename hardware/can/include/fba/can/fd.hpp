// A file descriptor owned once, and the poll()-bounded reads and writes every backend uses, so
// that no call waits longer than its timeout.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>

namespace fba::can {

class Fd {
 public:
  Fd() = default;
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() { reset(); }
  Fd(Fd&& other) noexcept : fd_(other.release()) {}
  Fd& operator=(Fd&& other) noexcept;
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;

  int get() const { return fd_; }
  explicit operator bool() const { return fd_ >= 0; }
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }
  void reset(int fd = -1);

 private:
  int fd_ = -1;
};

enum class Ready { data, timeout, hangup };
// Waits until `fd` has input, the timeout passes, or the other end is gone (POLLHUP/POLLERR with no
// input left). Retries on EINTR with the remaining time. Throws BusError naming `what` on a poll
// failure.
Ready wait_readable(int fd, std::chrono::milliseconds timeout, const std::string& what);
// Writes all of `data`, waiting for room at most `timeout` in total; throws BusError naming `what`
// when the line is gone or stays full.
void write_all(int fd, const void* data, std::size_t size, std::chrono::milliseconds timeout, const std::string& what);
// Sets O_NONBLOCK (every backend polls, then reads or writes what is ready).
void set_nonblocking(int fd, const std::string& what);

}  // namespace fba::can
