#include "fba/can/open_bus.hpp"

#include <stdexcept>

#include "fba/can/slcan.hpp"
#include "fba/can/socketcan.hpp"

namespace fba::can {

std::unique_ptr<CanBus> open_bus(const std::string& spec, int bitrate, std::stop_token stop) {
  if (spec.rfind("slcan:", 0) == 0) {
    const std::string device = spec.substr(6);
    if (device.empty()) throw std::invalid_argument("CAN bus 'slcan:' names no serial device (slcan:/dev/ttyUSB0)");
    slcan::Options options;
    options.bitrate = bitrate;
    options.stop = std::move(stop);
    return std::make_unique<slcan::SlcanBus>(device, options);
  }
  const std::string interface = spec.rfind("socketcan:", 0) == 0 ? spec.substr(10) : spec;
  if (interface.empty() || interface.find_first_of("/:") != std::string::npos)
    throw std::invalid_argument(
        "CAN bus '" + spec + "' is neither an interface (can0, socketcan:can0) nor slcan:DEVICE (slcan:/dev/ttyUSB0)");
  // SocketCAN's bitrate belongs to the interface: 'ip link set can0 type can bitrate 500000'.
  return open_socketcan(interface);
}

}  // namespace fba::can
