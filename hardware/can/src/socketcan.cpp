#include "fba/can/socketcan.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>

namespace fba::can {

std::optional<std::string> socketcan_unavailable() {
  Fd s(::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW));
  if (s) return std::nullopt;
  return std::string("this kernel has no SocketCAN support: socket(PF_CAN, SOCK_RAW, CAN_RAW) failed: ") +
         std::strerror(errno);
}

std::unique_ptr<FrameSocketBus> open_socketcan(const std::string& interface) {
  if (interface.empty() || interface.size() >= IFNAMSIZ)
    throw BusError("SocketCAN: interface name '" + interface + "' must have 1 to " + std::to_string(IFNAMSIZ - 1) +
                   " characters");
  Fd s(::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW));
  if (!s)
    throw BusError(interface + ": this kernel has no SocketCAN support: socket(PF_CAN, SOCK_RAW, CAN_RAW) failed: " +
                   std::strerror(errno));
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, interface.c_str(), IFNAMSIZ - 1);
  if (::ioctl(s.get(), SIOCGIFINDEX, &ifr) != 0)
    throw BusError(interface + ": no such CAN interface (" + std::strerror(errno) +
                   "); list them with 'ip link show type can'");
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  if (::bind(s.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
    throw BusError(interface + ": cannot bind a CAN socket: " + std::strerror(errno));
  if (::ioctl(s.get(), SIOCGIFFLAGS, &ifr) == 0 && !(ifr.ifr_flags & IFF_UP))
    throw BusError(interface + ": the interface is down; bring it up with 'ip link set " + interface +
                   " up type can bitrate 500000'");
  return std::make_unique<FrameSocketBus>(std::move(s), interface);
}

}  // namespace fba::can
