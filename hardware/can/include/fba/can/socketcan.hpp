// SocketCAN: the Linux kernel's CAN sockets (can0, vcan0). A kernel without CAN support (no
// PF_CAN, as on this project's CI machine) makes open_socketcan throw; socketcan_unavailable()
// says why beforehand, so tests can skip with that message.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "fba/can/frame_socket_bus.hpp"

namespace fba::can {

// A raw CAN socket bound to `interface`. Throws BusError naming the interface and the reason
// (no kernel support, no such interface, interface down).
std::unique_ptr<FrameSocketBus> open_socketcan(const std::string& interface);
// Why this kernel cannot open CAN sockets at all, or nothing if it can.
std::optional<std::string> socketcan_unavailable();

}  // namespace fba::can
