#include "fba/canopen/protocol.hpp"

#include <fmt/format.h>

namespace fba::canopen {

namespace {

// The names of codes: a table each, a code and its name on one line.
template <class Code>
struct Named {
  Code code;
  const char* name;
};

template <class Code, std::size_t N>
const char* name_of(const Named<Code> (&table)[N], Code code) {
  for (const auto& n : table)
    if (n.code == code) return n.name;
  return nullptr;
}

constexpr Named<NmtCommand> kNmtCommands[] = {
    {NmtCommand::start, "start"},
    {NmtCommand::stop, "stop"},
    {NmtCommand::pre_operational, "enter pre-operational"},
    {NmtCommand::reset_node, "reset node"},
    {NmtCommand::reset_communication, "reset communication"},
};

constexpr Named<NmtState> kNmtStates[] = {
    {NmtState::boot_up, "boot-up"},
    {NmtState::stopped, "stopped"},
    {NmtState::operational, "operational"},
    {NmtState::pre_operational, "pre-operational"},
    {NmtState::unknown, "unknown"},
};

// CiA 301, 7.2.4.3.17.
constexpr Named<std::uint32_t> kAbortCodes[] = {
    {0x05030000, "toggle bit not alternated"},
    {0x05040000, "SDO protocol timed out"},
    {0x05040001, "client/server command specifier not valid or unknown"},
    {0x05040002, "invalid block size"},
    {0x05040003, "invalid sequence number"},
    {0x05040004, "CRC error"},
    {0x05040005, "out of memory"},
    {0x06010000, "unsupported access to an object"},
    {0x06010001, "attempt to read a write-only object"},
    {0x06010002, "attempt to write a read-only object"},
    {0x06020000, "object does not exist in the object dictionary"},
    {0x06040041, "object cannot be mapped to the PDO"},
    {0x06040042, "the number and length of the objects to be mapped would exceed the PDO length"},
    {0x06040043, "general parameter incompatibility"},
    {0x06040047, "general internal incompatibility in the device"},
    {0x06060000, "access failed due to a hardware error"},
    {0x06070010, "data type does not match, length of service parameter does not match"},
    {0x06070012, "data type does not match, length of service parameter too high"},
    {0x06070013, "data type does not match, length of service parameter too low"},
    {0x06090011, "sub-index does not exist"},
    {0x06090030, "invalid value for parameter"},
    {0x06090031, "value of parameter written too high"},
    {0x06090032, "value of parameter written too low"},
    {0x06090036, "maximum value is less than minimum value"},
    {0x060A0023, "resource not available: SDO connection"},
    {0x08000000, "general error"},
    {0x08000020, "data cannot be transferred or stored to the application"},
    {0x08000021, "data cannot be transferred or stored to the application because of local control"},
    {0x08000022, "data cannot be transferred or stored to the application because of the present device state"},
    {0x08000023, "object dictionary dynamic generation failed or no object dictionary is present"},
    {0x08000024, "no data available"},
};

// Specific codes (CiA 402 drives, CiA 301 communication).
constexpr Named<std::uint16_t> kEmcyCodes[] = {
    {0x0000, "error reset or no error"},
    {0x2310, "continuous over-current"},
    {0x2320, "short circuit or earth leakage"},
    {0x3210, "DC link over-voltage"},
    {0x3220, "DC link under-voltage"},
    {0x4210, "excess temperature, device"},
    {0x4310, "excess temperature, drive"},
    {0x5530, "data storage (EEPROM) error"},
    {0x7121, "motor blocked"},
    {0x7305, "incremental sensor 1 fault"},
    {0x8110, "CAN overrun (objects lost)"},
    {0x8120, "CAN in error passive mode"},
    {0x8130, "life guard or heartbeat error"},
    {0x8140, "recovered from bus off"},
    {0x8141, "bus off occurred"},
    {0x8210, "PDO not processed due to length error"},
    {0x8220, "PDO length exceeded"},
    {0x8611, "following error"},
    {0x8612, "reference limit"},
};

// The class of an error code's high nibble, where it has no specific name (0xF: see emcy_name).
constexpr Named<std::uint16_t> kEmcyClasses[] = {
    {0x1, "generic error"},
    {0x2, "current"},
    {0x3, "voltage"},
    {0x4, "temperature"},
    {0x5, "device hardware"},
    {0x6, "device software"},
    {0x7, "additional modules"},
    {0x8, "monitoring"},
    {0x9, "external error"},
};

}  // namespace

std::string to_string(NmtCommand command) {
  if (const char* name = name_of(kNmtCommands, command)) return name;
  return fmt::format("NMT command 0x{:02X}", static_cast<int>(command));
}

std::string to_string(NmtState state) {
  if (const char* name = name_of(kNmtStates, state)) return name;
  return fmt::format("NMT state 0x{:02X}", static_cast<int>(state));
}

std::string sdo_abort_name(std::uint32_t code) {
  if (const char* name = name_of(kAbortCodes, code)) return name;
  return "unknown abort code";
}

std::string emcy_name(std::uint16_t code) {
  // Specific codes first, then the class of the high nibble.
  if (const char* name = name_of(kEmcyCodes, code)) return name;
  if (const char* name = name_of(kEmcyClasses, static_cast<std::uint16_t>(code >> 12))) return name;
  if ((code >> 12) == 0xF) return (code >> 8) == 0xFF ? "device specific" : "additional functions";
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
