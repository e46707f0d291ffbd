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
  const std::string& name() const override { return name_; }
  std::uint64_t discarded() const override { return discarded_; }
  std::string last_discard_reason() const override { return last_discard_; }

  // Sends bytes as one record, bypassing the frame encoding: how tests and the emulator put a
  // malformed record on the line.
  void write_raw(std::span<const std::uint8_t> bytes);

 private:
  Fd socket_;
  std::string name_;
  std::uint64_t discarded_ = 0;
  std::string last_discard_;
};

}  // namespace fba::can
