// One string names a CAN bus, so a task file, a profile or a command line picks the backend:
//   can0, socketcan:can0        a SocketCAN interface
//   slcan:/dev/ttyUSB0          an SLCAN adapter on a serial line (or a pseudo-terminal)
#pragma once

#include <memory>
#include <stop_token>
#include <string>

#include "fba/can/bus.hpp"

namespace fba::can {

// Opens the bus `spec` names; an SLCAN adapter is set to `bitrate` (bit/s). Throws BusError naming
// the bus and the reason, or std::invalid_argument for a spec of no known form. A stop requested
// while an SLCAN adapter is awaited ends the opening at once (BusError).
std::unique_ptr<CanBus> open_bus(const std::string& spec, int bitrate = 500000, std::stop_token stop = {});

}  // namespace fba::can
