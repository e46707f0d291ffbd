// The CAN transport interface: send a frame, receive one with a timeout, close. Backends: SocketCAN
// (socketcan.hpp), SLCAN over a serial line (slcan.hpp) and a socketpair for tests
// (socketpair_bus.hpp). Nothing here blocks longer than the timeout it is given.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "fba/can/frame.hpp"

namespace fba::can {

// The line is gone or unusable: a closed peer, an unplugged adapter, a write that cannot complete.
// The message names the bus (device or interface) and the reason.
class BusError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class CanBus {
 public:
  virtual ~CanBus() = default;

  // Sends one frame; throws BusError if the line is gone or does not take the frame in time, and
  // std::invalid_argument for a frame that is not valid (Frame::validate).
  virtual void send(const Frame& frame) = 0;
  // The next frame, or nothing once `timeout` has passed without one. Input that is not a frame
  // (line noise, a malformed record) is skipped and counted in discarded(). Throws BusError when
  // the line is gone.
  virtual std::optional<Frame> receive(std::chrono::milliseconds timeout) = 0;
  // Releases the line; later calls throw BusError. Safe to call twice.
  virtual void close() = 0;

  // The device or interface, as used in messages: "can0", "slcan:/dev/ttyUSB0".
  const std::string& name() const { return name_; }
  // Input skipped as not a frame, and the reason for the last one ("" if none).
  std::uint64_t discarded() const { return discarded_; }
  std::string last_discard_reason() const { return last_discard_; }

 protected:
  explicit CanBus(std::string name) : name_(std::move(name)) {}
  // Input skipped as not a frame: counted, its reason kept for last_discard_reason().
  void discard(std::string reason) {
    ++discarded_;
    last_discard_ = std::move(reason);
  }

 private:
  std::string name_;
  std::uint64_t discarded_ = 0;
  std::string last_discard_;
};

}  // namespace fba::can
