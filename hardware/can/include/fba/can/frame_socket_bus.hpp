// A CanBus over a socket that carries one Linux `struct can_frame` record per message: a SocketCAN
// raw socket (socketcan.hpp) or one end of a socketpair (socketpair_bus.hpp). Both paths share this
// code, so the socketpair tests exercise what runs on a real can0.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "fba/can/bus.hpp"
#include "fba/can/fd.hpp"

namespace fba::can {

class FrameSocketBus final : public CanBus {
 public:
  FrameSocketBus(Fd socket, std::string name);

  void send(const Frame& frame) override;
  std::optional<Frame> receive(std::chrono::milliseconds timeout) override;
  void close() override { socket_.reset(); }

  // Sends bytes as one record, bypassing the frame encoding: how tests and the emulator put a
  // malformed record on the line.
  void write_raw(std::span<const std::uint8_t> bytes);

 private:
  Fd socket_;
};

}  // namespace fba::can
