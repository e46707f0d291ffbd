// The CANopen arm emulator (six CiA 402 drives) in a thread of its own, behind an SLCAN adapter on a
// new pseudo-terminal: a driver opens device() as it would slcan:/dev/ttyUSB0, in this process or
// in another (fba-run), and the test reads what the drives heard and did.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "fba/can/pty.hpp"
#include "fba/can/slcan_adapter.hpp"
#include "fba/emulators/canopen_arm.hpp"

namespace fba::test {

class EmulatedCanopenArm {
 public:
  explicit EmulatedCanopenArm(emulators::CanopenArmOptions options = {}) : pty_(can::open_pty()) {
    auto adapter = std::make_unique<can::slcan::SlcanAdapter>(std::move(pty_.master), "emulator");
    noise_ = emulators::noise_for(*adapter);
    adapter_ = std::move(adapter);
    options.nodes = {1, 2, 3, 4, 5, 6};
    emulator_ = std::make_unique<emulators::CanopenArmEmulator>(*adapter_, options, noise_);
    thread_ = std::thread([this] { emulator_->run(); });
    // The drives' power-on boot-ups go out before a driver's first request, as on a bus whose
    // drives are on when the task starts.
    while (!emulator_->started()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ~EmulatedCanopenArm() {
    emulator_->stop();
    thread_.join();
  }
  EmulatedCanopenArm(const EmulatedCanopenArm&) = delete;
  EmulatedCanopenArm& operator=(const EmulatedCanopenArm&) = delete;

  std::string device() const { return "slcan:" + pty_.slave_path; }
  emulators::CanopenArmEmulator* operator->() { return emulator_.get(); }
  emulators::CanopenArmEmulator& operator*() { return *emulator_; }
  bool quick_stopped(int node) { return (emulator_->statusword(node) & 0x6F) == 0x07; }
  bool enabled(int node) { return (emulator_->statusword(node) & 0x6F) == 0x27; }
  bool in_fault(int node) { return (emulator_->statusword(node) & 0x4F) == 0x08; }

 private:
  can::Pty pty_;
  std::unique_ptr<can::CanBus> adapter_;
  std::function<void()> noise_;
  std::unique_ptr<emulators::CanopenArmEmulator> emulator_;
  std::thread thread_;
};

}  // namespace fba::test
