// Two connected CanBus ends over socketpair(AF_UNIX, SOCK_SEQPACKET), each message one
// `struct can_frame`: a point-to-point bus for tests and the emulator, with real descriptors,
// poll() timeouts and a hang-up when either end closes.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include "fba/can/frame_socket_bus.hpp"

namespace fba::can {

std::pair<std::unique_ptr<FrameSocketBus>, std::unique_ptr<FrameSocketBus>> socketpair_bus(
    const std::string& name = "socketpair");

}  // namespace fba::can
