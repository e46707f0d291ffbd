#include "fba/can/frame.hpp"

#include <stdexcept>

#include <fmt/format.h>

namespace fba::can {

void Frame::validate() const {
  const std::uint32_t max = extended ? kMaxExtendedId : kMaxStandardId;
  if (id > max)
    throw std::invalid_argument(fmt::format("CAN frame: identifier 0x{:X} is beyond the {}-bit range (at most 0x{:X})",
                                            id, extended ? 29 : 11, max));
  if (dlc > 8) throw std::invalid_argument(fmt::format("CAN frame 0x{:X}: data length {} is beyond 8", id, dlc));
}

std::string Frame::describe() const {
  std::string s = extended ? fmt::format("0x{:08X}", id) : fmt::format("0x{:03X}", id);
  if (rtr) s += " RTR";
  s += fmt::format(" [{}]", dlc);
  if (!rtr)
    for (int i = 0; i < dlc && i < 8; ++i) s += fmt::format(" {:02X}", data[static_cast<std::size_t>(i)]);
  return s;
}

bool operator==(const Frame& a, const Frame& b) {
  if (a.id != b.id || a.extended != b.extended || a.rtr != b.rtr || a.dlc != b.dlc) return false;
  if (a.rtr) return true;
  for (int i = 0; i < a.dlc && i < 8; ++i)
    if (a.data[static_cast<std::size_t>(i)] != b.data[static_cast<std::size_t>(i)]) return false;
  return true;
}

Frame make_frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  if (bytes.size() > 8)
    throw std::invalid_argument(fmt::format("CAN frame 0x{:X}: {} data bytes, at most 8", id, bytes.size()));
  Frame f;
  f.id = id;
  f.dlc = static_cast<std::uint8_t>(bytes.size());
  std::size_t i = 0;
  for (auto b : bytes) f.data[i++] = b;
  return f;
}

}  // namespace fba::can
