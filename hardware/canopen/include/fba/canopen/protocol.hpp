// CANopen (CiA 301) on the wire: the predefined connection set's identifiers, NMT commands and
// states, SDO command bytes, and the names of SDO abort codes and EMCY error codes, so that every
// error a device reports is named in the message a person reads.
#pragma once

#include <cstdint>
#include <string>

namespace fba::canopen {

constexpr int kMaxNode = 127;

// Function codes of the predefined connection set; a node's COB-ID is the code + its node id.
constexpr std::uint32_t kNmtId = 0x000;
constexpr std::uint32_t kSyncId = 0x080;
constexpr std::uint32_t kEmcyBase = 0x080;
constexpr std::uint32_t kTpdoBase[4] = {0x180, 0x280, 0x380, 0x480};
constexpr std::uint32_t kRpdoBase[4] = {0x200, 0x300, 0x400, 0x500};
constexpr std::uint32_t kSdoTxBase = 0x580;  // server (node) to client (master)
constexpr std::uint32_t kSdoRxBase = 0x600;  // client to server
constexpr std::uint32_t kHeartbeatBase = 0x700;

enum class NmtCommand : std::uint8_t {
  start = 0x01,
  stop = 0x02,
  pre_operational = 0x80,
  reset_node = 0x81,
  reset_communication = 0x82,
};

// The state byte of a heartbeat (or boot-up) message.
enum class NmtState : std::uint8_t {
  boot_up = 0x00,
  stopped = 0x04,
  operational = 0x05,
  pre_operational = 0x7F,
  unknown = 0xFF,  // nothing heard yet
};

std::string to_string(NmtCommand command);
std::string to_string(NmtState state);

// SDO command bytes (the first data byte): client command specifier in bits 5-7.
namespace sdo {
constexpr std::uint8_t kDownloadRequest = 0x20;  // | expedited 0x02 | size indicated 0x01 | (4 - n) << 2
constexpr std::uint8_t kDownloadResponse = 0x60;
constexpr std::uint8_t kUploadRequest = 0x40;
constexpr std::uint8_t kUploadResponse = 0x40;  // | expedited 0x02 | size indicated 0x01 | (4 - n) << 2
constexpr std::uint8_t kAbort = 0x80;
constexpr std::uint8_t kExpedited = 0x02;
constexpr std::uint8_t kSizeIndicated = 0x01;
// The command byte of an expedited download (or upload answer) of 1-4 bytes: 0x2F, 0x2B, 0x27, 0x23.
constexpr std::uint8_t expedited(std::uint8_t specifier, int bytes) {
  return static_cast<std::uint8_t>(specifier | kExpedited | kSizeIndicated | ((4 - bytes) << 2));
}
}  // namespace sdo

// Abort codes (CiA 301, 7.2.4.3.17).
namespace abort_code {
constexpr std::uint32_t kToggleBit = 0x05030000;
constexpr std::uint32_t kTimedOut = 0x05040000;
constexpr std::uint32_t kCommandSpecifier = 0x05040001;
constexpr std::uint32_t kUnsupportedAccess = 0x06010000;
constexpr std::uint32_t kWriteOnly = 0x06010001;
constexpr std::uint32_t kReadOnly = 0x06010002;
constexpr std::uint32_t kNoObject = 0x06020000;
constexpr std::uint32_t kNotMappable = 0x06040041;
constexpr std::uint32_t kPdoTooLong = 0x06040042;
constexpr std::uint32_t kLengthMismatch = 0x06070010;
constexpr std::uint32_t kNoSubIndex = 0x06090011;
constexpr std::uint32_t kInvalidValue = 0x06090030;
constexpr std::uint32_t kValueTooHigh = 0x06090031;
constexpr std::uint32_t kValueTooLow = 0x06090032;
constexpr std::uint32_t kGeneral = 0x08000000;
constexpr std::uint32_t kDeviceState = 0x08000022;
}  // namespace abort_code

// "object does not exist in the object dictionary" for 0x06020000; "unknown abort code" otherwise.
std::string sdo_abort_name(std::uint32_t code);
// The EMCY error code's meaning (CiA 301 classes, CiA 402 drive codes): "continuous over-current".
std::string emcy_name(std::uint16_t code);
// The set bits of the error register (object 0x1001): "generic, current".
std::string error_register_names(std::uint8_t reg);

}  // namespace fba::canopen
