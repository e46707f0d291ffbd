// The gripper emulator in a thread of its own on the master end of a pseudo-terminal; the driver
// opens device(), the slave end, as it would a USB-RS485 adapter.
#pragma once

#include <string>
#include <thread>

#include "fba/can/pty.hpp"
#include "fba/emulators/robotiq_3f.hpp"

namespace fba::test {

class EmulatedHand {
 public:
  explicit EmulatedHand(emulators::Robotiq3fOptions options = quick())
      : pty_(can::open_pty()), emulator_(std::move(pty_.master), "emulator", options), thread_([this] { emulator_.run(); }) {}
  ~EmulatedHand() {
    emulator_.stop();
    thread_.join();
  }
  EmulatedHand(const EmulatedHand&) = delete;
  EmulatedHand& operator=(const EmulatedHand&) = delete;

  const std::string& device() const { return pty_.slave_path; }
  emulators::Robotiq3fEmulator& emulator() { return emulator_; }

  // A hand that activates in 50 ms, not the real one's seconds: the tests are about the protocol.
  static emulators::Robotiq3fOptions quick() {
    emulators::Robotiq3fOptions o;
    o.activation_s = 0.05;
    return o;
  }

 private:
  can::Pty pty_;
  emulators::Robotiq3fEmulator emulator_;
  std::thread thread_;
};

}  // namespace fba::test
