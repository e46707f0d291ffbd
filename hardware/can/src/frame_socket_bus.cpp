#include "fba/can/frame_socket_bus.hpp"

#include <linux/can.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <fmt/format.h>

namespace fba::can {

namespace {
constexpr std::chrono::milliseconds kSendTimeout{500};
}

FrameSocketBus::FrameSocketBus(Fd socket, std::string name) : CanBus(std::move(name)), socket_(std::move(socket)) {
  set_nonblocking(socket_.get(), this->name());  // the parameter `name` was moved into the base
}

void FrameSocketBus::send(const Frame& frame) {
  frame.validate();
  can_frame raw{};
  raw.can_id = frame.id | (frame.extended ? CAN_EFF_FLAG : 0U) | (frame.rtr ? CAN_RTR_FLAG : 0U);
  raw.can_dlc = frame.dlc;
  if (!frame.rtr) std::memcpy(raw.data, frame.data.data(), frame.dlc);
  write_all(socket_.get(), &raw, sizeof raw, kSendTimeout, name());
}

void FrameSocketBus::write_raw(std::span<const std::uint8_t> bytes) {
  write_all(socket_.get(), bytes.data(), bytes.size(), kSendTimeout, name());
}

std::optional<Frame> FrameSocketBus::receive(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (bool first = true;; first = false) {
    // At least one read, even with a zero timeout; a flood of malformed records still ends at the deadline.
    if (!first && std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    const Ready ready = wait_readable(socket_.get(), std::max(left, std::chrono::milliseconds(0)), name());
    if (ready == Ready::timeout) return std::nullopt;
    if (ready == Ready::hangup) throw BusError(name() + ": the other end closed the bus");
    // One record per read; a longer one is truncated (MSG_TRUNC reports its real length).
    unsigned char buffer[sizeof(can_frame) + 16];
    const ssize_t n = ::recv(socket_.get(), buffer, sizeof buffer, MSG_TRUNC);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) continue;
      throw BusError(name() + ": read failed: " + std::strerror(errno) + " (the line is gone)");
    }
    if (n == 0) throw BusError(name() + ": the other end closed the bus");
    if (static_cast<std::size_t>(n) != sizeof(can_frame)) {
      discard(fmt::format("a record of {} bytes, expected a can_frame of {}", n, sizeof(can_frame)));
      continue;
    }
    can_frame raw;
    std::memcpy(&raw, buffer, sizeof raw);
    if (raw.can_id & CAN_ERR_FLAG) {  // error frames are the controller's state, not traffic
      discard(fmt::format("a controller error frame (class 0x{:X})", raw.can_id & CAN_ERR_MASK));
      continue;
    }
    if (raw.can_dlc > 8) {
      discard(fmt::format("a frame with data length {}, beyond 8", raw.can_dlc));
      continue;
    }
    Frame f;
    f.extended = (raw.can_id & CAN_EFF_FLAG) != 0;
    f.rtr = (raw.can_id & CAN_RTR_FLAG) != 0;
    f.id = raw.can_id & (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
    f.dlc = raw.can_dlc;
    if (!f.rtr) std::memcpy(f.data.data(), raw.data, f.dlc);
    return f;
  }
}

}  // namespace fba::can
