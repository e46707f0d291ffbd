#include "registers.hpp"

#include <cstdio>
#include <stdexcept>

namespace fba::robotiq {

const char* to_string(Mode m) {
  switch (m) {
    case Mode::basic: return "basic";
    case Mode::pinch: return "pinch";
    case Mode::wide: return "wide";
    case Mode::scissor: return "scissor";
  }
  return "?";
}

const char* axis_name(int axis) {
  static constexpr const char* kNames[kAxes] = {"A", "B", "C", "scissor"};
  return axis >= 0 && axis < kAxes ? kNames[axis] : "?";
}

const char* to_string(Contact c) {
  switch (c) {
    case Contact::moving: return "moving";
    case Contact::while_opening: return "stopped by contact while opening";
    case Contact::while_closing: return "stopped by contact while closing";
    case Contact::at_request: return "at the requested position";
  }
  return "?";
}

namespace {

std::uint8_t byte_of(int value, int axis, const char* field) {
  if (value < 0 || value > 255)
    throw std::out_of_range(std::string(field) + " of axis " + axis_name(axis) + " must be 0..255, not " +
                            std::to_string(value));
  return static_cast<std::uint8_t>(value);
}

}  // namespace

Registers encode(const Command& c) {
  std::array<std::uint8_t, 2 * kRegisterCount> b{};
  b[0] = static_cast<std::uint8_t>((c.activate ? 1 : 0) | (static_cast<int>(c.mode) << 1) | (c.go ? 1 << 3 : 0) |
                                   (c.auto_release ? 1 << 4 : 0));
  b[1] = static_cast<std::uint8_t>((c.individual_fingers ? 1 << 2 : 0) | (c.individual_scissor ? 1 << 3 : 0));
  for (int axis = 0; axis < kAxes; ++axis) {
    b[3 + 3 * axis] = byte_of(c.axes[axis].position, axis, "position");
    b[4 + 3 * axis] = byte_of(c.axes[axis].speed, axis, "speed");
    b[5 + 3 * axis] = byte_of(c.axes[axis].force, axis, "force");
  }
  Registers r{};
  for (int i = 0; i < kRegisterCount; ++i) r[i] = static_cast<std::uint16_t>(b[2 * i] << 8 | b[2 * i + 1]);
  return r;
}

Status decode(const Registers& r) {
  std::array<std::uint8_t, 2 * kRegisterCount> b{};
  for (int i = 0; i < kRegisterCount; ++i) {
    b[2 * i] = static_cast<std::uint8_t>(r[i] >> 8);
    b[2 * i + 1] = static_cast<std::uint8_t>(r[i] & 0xFF);
  }
  Status s;
  s.activated = b[0] & 1;
  s.mode = static_cast<Mode>((b[0] >> 1) & 3);
  s.go = (b[0] >> 3) & 1;
  s.imc = (b[0] >> 4) & 3;
  s.motion = (b[0] >> 6) & 3;
  s.fault = b[2] & 0x0F;  // the high nibble is reserved
  for (int axis = 0; axis < kAxes; ++axis) {
    s.axes[axis].contact = static_cast<Contact>((b[1] >> (2 * axis)) & 3);
    s.axes[axis].requested = b[3 + 3 * axis];
    s.axes[axis].position = b[4 + 3 * axis];
    s.axes[axis].current = b[5 + 3 * axis];
  }
  return s;
}

std::string fault_text(int code) {
  const char* what = nullptr;
  switch (code) {
    case 0x00: what = "no fault"; break;
    case 0x05: what = "action delayed, activation must be completed first (priority)"; break;
    case 0x06: what = "action delayed, the mode change must be completed first (priority)"; break;
    case 0x07: what = "the activation bit must be set before an action (priority)"; break;
    case 0x09: what = "the communication chip is not ready, it may be booting (minor)"; break;
    case 0x0A: what = "changing mode fault, interference on the scissor for less than 20 s (minor)"; break;
    case 0x0B: what = "automatic release in progress (minor)"; break;
    case 0x0D:
      what = "activation fault, verify that no interference or other error occurred (major: reset required)";
      break;
    case 0x0E:
      what = "changing mode fault, interference on the scissor for more than 20 s (major: reset required)";
      break;
    case 0x0F: what = "automatic release completed (major: reset and activation required)"; break;
    default: what = "a fault code the manual does not list"; break;
  }
  char code_text[8];
  std::snprintf(code_text, sizeof code_text, "0x%02X", code);
  return std::string(code_text) + " " + what;
}

bool fault_is_transient(int code) { return code == 0x05 || code == 0x06 || code == 0x09 || code == 0x0A; }

}  // namespace fba::robotiq
