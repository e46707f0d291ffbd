#include "fba/can/socketpair_bus.hpp"

#include <sys/socket.h>

#include <cerrno>
#include <cstring>

namespace fba::can {

std::pair<std::unique_ptr<FrameSocketBus>, std::unique_ptr<FrameSocketBus>> socketpair_bus(const std::string& name) {
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds) != 0)
    throw BusError(name + ": socketpair failed: " + std::strerror(errno));
  Fd a(fds[0]), b(fds[1]);
  return {std::make_unique<FrameSocketBus>(std::move(a), name + ":a"),
          std::make_unique<FrameSocketBus>(std::move(b), name + ":b")};
}

}  // namespace fba::can
