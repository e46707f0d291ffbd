// A classic CAN frame (CAN 2.0A/B): an 11-bit (or 29-bit extended) identifier, 0-8 data bytes or a
// remote request. What every backend carries and every protocol layer above it reads.
#pragma once

#include <array>
#include <cstdint>
#include <initializer_list>
#include <string>

namespace fba::can {

struct Frame {
  static constexpr std::uint32_t kMaxStandardId = 0x7FF;
  static constexpr std::uint32_t kMaxExtendedId = 0x1FFFFFFF;

  std::uint32_t id = 0;
  bool extended = false;  // 29-bit identifier
  bool rtr = false;       // remote transmission request: a DLC, no data
  std::uint8_t dlc = 0;   // 0..8
  std::array<std::uint8_t, 8> data{};

  // Throws std::invalid_argument naming the field when the identifier or the DLC is out of range.
  void validate() const;
  // "0x601 [8] 40 41 60 00 00 00 00 00", "0x701 RTR [1]": for logs and error messages.
  std::string describe() const;

  friend bool operator==(const Frame& a, const Frame& b);
};

// A data frame with the given bytes (at most 8).
Frame make_frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes);

}  // namespace fba::can
