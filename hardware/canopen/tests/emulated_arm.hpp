// The arm emulator running in a thread of its own on one end of a transport, and the other end for
// the master: SLCAN over a pseudo-terminal (the serial path) or a socketpair (the SocketCAN path).
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "fba/can/pty.hpp"
#include "fba/can/slcan.hpp"
#include "fba/can/slcan_adapter.hpp"
#include "fba/can/socketpair_bus.hpp"
#include "fba/emulators/canopen_arm.hpp"

namespace fba::test {

enum class Transport { slcan_pty, socketpair };

inline std::string transport_name(const ::testing::TestParamInfo<Transport>& info) {
  return info.param == Transport::slcan_pty ? "SlcanPty" : "Socketpair";
}

class EmulatedArm {
 public:
  EmulatedArm(Transport transport, const emulators::CanopenArmOptions& options) {
    if (transport == Transport::slcan_pty) {
      pty_ = can::open_pty();
      auto adapter = std::make_unique<can::slcan::SlcanAdapter>(std::move(pty_.master), "emulator");
      noise_ = emulators::noise_for(*adapter);
      device_ = std::move(adapter);
    } else {
      auto [a, b] = can::socketpair_bus("socketpair");
      noise_ = emulators::noise_for(*b);
      device_ = std::move(b);
      host_ = std::move(a);
    }
    emulator_ = std::make_unique<emulators::CanopenArmEmulator>(*device_, options, noise_);
    thread_ = std::thread([this] { emulator_->run(); });
    // The drives' power-on boot-ups go out before the master's first request (as when a master
    // opens a bus whose drives are on): one arriving after a reset the master sends would be taken
    // for its answer, and the answer for a reboot nobody asked for.
    while (!emulator_->started()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    // Generous answer times: the emulator's thread may wait for a core on a loaded machine.
    if (transport == Transport::slcan_pty) {
      try {
        host_ = std::make_unique<can::slcan::SlcanBus>(pty_.slave_path,
                                                       can::slcan::Options{.reply_timeout = std::chrono::seconds(2)});
      } catch (...) {  // the emulator's thread ends first: a failed open is a failure, not std::terminate
        emulator_->stop();
        thread_.join();
        throw;
      }
    }
  }
  ~EmulatedArm() {
    emulator_->stop();
    thread_.join();
  }
  EmulatedArm(const EmulatedArm&) = delete;
  EmulatedArm& operator=(const EmulatedArm&) = delete;

  can::CanBus& host() { return *host_; }
  emulators::CanopenArmEmulator& emulator() { return *emulator_; }

 private:
  can::Pty pty_;
  std::unique_ptr<can::CanBus> device_, host_;
  std::function<void()> noise_;
  std::unique_ptr<emulators::CanopenArmEmulator> emulator_;
  std::thread thread_;
};

}  // namespace fba::test
