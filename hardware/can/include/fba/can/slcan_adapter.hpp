// The adapter side of SLCAN: what a USB-CAN adapter does with the host's commands. The emulator
// plays an adapter with the CAN nodes behind it on the master end of a pseudo-terminal, so the
// driver's SlcanBus runs its real serial code against it.
//   receive(): the frames the host transmits (t/T/r/R lines), each acknowledged with z / Z; S, O,
//              C, V, N, F are answered, anything else gets BEL.
//   send():    a frame from the bus to the host, as a t/T/r/R line, while the channel is open.
#pragma once

#include <atomic>
#include <span>

#include "fba/can/slcan.hpp"

namespace fba::can::slcan {

class SlcanAdapter final : public CanBus {
 public:
  SlcanAdapter(Fd line, std::string name);

  void send(const Frame& frame) override;
  std::optional<Frame> receive(std::chrono::milliseconds timeout) override;
  void close() override { fd_.reset(); }

  bool is_open() const { return open_; }
  int bitrate() const { return bitrate_; }
  // Bytes straight onto the line: how the emulator injects noise.
  void write_raw(std::span<const std::uint8_t> bytes);

 private:
  void reply(std::string_view text);
  std::optional<Frame> handle(const std::string& line);

  Fd fd_;
  LineReader reader_;
  // Atomic: tests read them from another thread while the adapter answers.
  std::atomic<bool> open_{false};
  std::atomic<int> bitrate_{0};
};

}  // namespace fba::can::slcan
