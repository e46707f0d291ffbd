#include "fba/canopen/protocol.hpp"

#include <fmt/format.h>

namespace fba::canopen {

std::string to_string(NmtCommand command) {
  switch (command) {
    case NmtCommand::start:
      return "start";
    case NmtCommand::stop:
      return "stop";
    case NmtCommand::pre_operational:
      return "enter pre-operational";
    case NmtCommand::reset_node:
      return "reset node";
    case NmtCommand::reset_communication:
      return "reset communication";
  }
  return fmt::format("NMT command 0x{:02X}", static_cast<int>(command));
}

std::string to_string(NmtState state) {
  switch (state) {
    case NmtState::boot_up:
      return "boot-up";
    case NmtState::stopped:
      return "stopped";
    case NmtState::operational:
      return "operational";
    case NmtState::pre_operational:
      return "pre-operational";
    case NmtState::unknown:
      return "unknown";
  }
  return fmt::format("NMT state 0x{:02X}", static_cast<int>(state));
}

std::string sdo_abort_name(std::uint32_t code) {
  switch (code) {
    case 0x05030000:
      return "toggle bit not alternated";
    case 0x05040000:
      return "SDO protocol timed out";
    case 0x05040001:
      return "client/server command specifier not valid or unknown";
    case 0x05040002:
      return "invalid block size";
    case 0x05040003:
      return "invalid sequence number";
    case 0x05040004:
      return "CRC error";
    case 0x05040005:
      return "out of memory";
    case 0x06010000:
      return "unsupported access to an object";
    case 0x06010001:
      return "attempt to read a write-only object";
    case 0x06010002:
      return "attempt to write a read-only object";
    case 0x06020000:
      return "object does not exist in the object dictionary";
    case 0x06040041:
      return "object cannot be mapped to the PDO";
    case 0x06040042:
      return "the number and length of the objects to be mapped would exceed the PDO length";
    case 0x06040043:
      return "general parameter incompatibility";
    case 0x06040047:
      return "general internal incompatibility in the device";
    case 0x06060000:
      return "access failed due to a hardware error";
    case 0x06070010:
      return "data type does not match, length of service parameter does not match";
    case 0x06070012:
      return "data type does not match, length of service parameter too high";
    case 0x06070013:
      return "data type does not match, length of service parameter too low";
    case 0x06090011:
      return "sub-index does not exist";
    case 0x06090030:
      return "invalid value for parameter";
    case 0x06090031:
      return "value of parameter written too high";
    case 0x06090032:
      return "value of parameter written too low";
    case 0x06090036:
      return "maximum value is less than minimum value";
    case 0x060A0023:
      return "resource not available: SDO connection";
    case 0x08000000:
      return "general error";
    case 0x08000020:
      return "data cannot be transferred or stored to the application";
    case 0x08000021:
      return "data cannot be transferred or stored to the application because of local control";
    case 0x08000022:
      return "data cannot be transferred or stored to the application because of the present device state";
    case 0x08000023:
      return "object dictionary dynamic generation failed or no object dictionary is present";
    case 0x08000024:
      return "no data available";
  }
  return "unknown abort code";
}

std::string emcy_name(std::uint16_t code) {
  // Specific codes first (CiA 402 drives, CiA 301 communication), then the class of the high byte.
  switch (code) {
    case 0x0000:
      return "error reset or no error";
    case 0x2310:
      return "continuous over-current";
    case 0x2320:
      return "short circuit or earth leakage";
    case 0x3210:
      return "DC link over-voltage";
    case 0x3220:
      return "DC link under-voltage";
    case 0x4210:
      return "excess temperature, device";
    case 0x4310:
      return "excess temperature, drive";
    case 0x5530:
      return "data storage (EEPROM) error";
    case 0x7121:
      return "motor blocked";
    case 0x7305:
      return "incremental sensor 1 fault";
    case 0x8110:
      return "CAN overrun (objects lost)";
    case 0x8120:
      return "CAN in error passive mode";
    case 0x8130:
      return "life guard or heartbeat error";
    case 0x8140:
      return "recovered from bus off";
    case 0x8141:
      return "bus off occurred";
    case 0x8210:
      return "PDO not processed due to length error";
    case 0x8220:
      return "PDO length exceeded";
    case 0x8611:
      return "following error";
    case 0x8612:
      return "reference limit";
  }
  switch (code >> 12) {
    case 0x1:
      return "generic error";
    case 0x2:
      return "current";
    case 0x3:
      return "voltage";
    case 0x4:
      return "temperature";
    case 0x5:
      return "device hardware";
    case 0x6:
      return "device software";
    case 0x7:
      return "additional modules";
    case 0x8:
      return "monitoring";
    case 0x9:
      return "external error";
    case 0xF:
      return (code >> 8) == 0xFF ? "device specific" : "additional functions";
  }
  return "unknown error code";
}

std::string error_register_names(std::uint8_t reg) {
  static const char* const names[8] = {"generic",       "current",        "voltage",  "temperature",
                                       "communication", "device profile", "reserved", "manufacturer specific"};
  std::string s;
  for (int bit = 0; bit < 8; ++bit)
    if (reg & (1 << bit)) s += (s.empty() ? "" : ", ") + std::string(names[bit]);
  return s.empty() ? "none" : s;
}

}  // namespace fba::canopen
