#include "fba/can/fd.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "fba/can/bus.hpp"

namespace fba::can {

Fd& Fd::operator=(Fd&& other) noexcept {
  if (this != &other) reset(other.release());
  return *this;
}

void Fd::reset(int fd) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = fd;
}

namespace {

using Clock = std::chrono::steady_clock;

int poll_once(pollfd& p, Clock::time_point deadline) {
  for (;;) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now());
    const int n = ::poll(&p, 1, static_cast<int>(std::max<long long>(0, left.count())));
    if (n >= 0 || errno != EINTR) return n;
  }
}

}  // namespace

Ready wait_readable(int fd, std::chrono::milliseconds timeout, const std::string& what) {
  if (fd < 0) throw BusError(what + ": the line is closed");
  pollfd p{fd, POLLIN, 0};
  const int n = poll_once(p, Clock::now() + timeout);
  if (n < 0) throw BusError(what + ": poll failed: " + std::strerror(errno));
  if (n == 0) return Ready::timeout;
  if (p.revents & POLLNVAL) throw BusError(what + ": the line is closed");
  if (p.revents & POLLIN) return Ready::data;  // read what is left before reporting a hang-up
  return Ready::hangup;
}

void write_all(int fd, const void* data, std::size_t size, std::chrono::milliseconds timeout, const std::string& what) {
  if (fd < 0) throw BusError(what + ": the line is closed");
  const auto deadline = Clock::now() + timeout;
  const auto* bytes = static_cast<const unsigned char*>(data);
  while (size > 0) {
    // send() with MSG_NOSIGNAL on sockets: a closed peer is an EPIPE to report, not a SIGPIPE that
    // kills the process; a tty is not a socket and takes write().
    ssize_t n = ::send(fd, bytes, size, MSG_NOSIGNAL);
    if (n < 0 && errno == ENOTSOCK) n = ::write(fd, bytes, size);
    if (n > 0) {
      bytes += n;
      size -= static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != ENOBUFS)
      throw BusError(what + ": write failed: " + std::strerror(errno) + " (the line is gone)");
    pollfd p{fd, POLLOUT, 0};
    const int ready = poll_once(p, deadline);
    if (ready < 0) throw BusError(what + ": poll failed: " + std::strerror(errno));
    if (ready == 0)
      throw BusError(what + ": write timed out after " + std::to_string(timeout.count()) + " ms (the line stays full)");
    if (p.revents & (POLLHUP | POLLERR | POLLNVAL)) throw BusError(what + ": the line hung up while writing");
  }
}

void set_nonblocking(int fd, const std::string& what) {
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags < 0 || ::fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0)
    throw BusError(what + ": cannot make the descriptor non-blocking: " + std::strerror(errno));
}

}  // namespace fba::can
