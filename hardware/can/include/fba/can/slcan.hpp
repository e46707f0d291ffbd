// SLCAN: the Lawicel ASCII protocol of many USB-CAN adapters (CANable, CANtact, USBtin, Lawicel
// CANUSB), over a serial line. Every command and every received frame is one line ending in CR:
//   S0..S8   bitrate 10k, 20k, 50k, 100k, 125k, 250k, 500k, 800k, 1M     O open   C close
//   tIIILDD..  standard frame: 3 hex digits of id, 1 of length, 2 per byte; rIIIL a remote request
//   TIIIIIIIILDD.., RIIIIIIIIL  the same with a 29-bit id
// The adapter answers CR for OK and BEL (0x07) for an error; z / Z acknowledge a sent frame on
// some adapters; with time stamps on (Z1), a received frame ends in 4 more hex digits.
// This file has the codec and line splitter (shared with the adapter side the emulator plays, in
// slcan_adapter.hpp) and the host side: SlcanBus.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <stop_token>
#include <string>
#include <string_view>

#include "fba/can/bus.hpp"
#include "fba/can/fd.hpp"

namespace fba::can::slcan {

constexpr char kBell = '\a';
// The longest valid line (T, 8 id digits, length, 16 data digits, 4 time-stamp digits) is 30
// characters; anything much longer is noise, dropped without growing the buffer.
constexpr std::size_t kMaxLine = 64;
// How long a write to the serial line may block (a full kernel buffer: the other side stopped
// reading) before it fails: the adapter and its emulator alike.
constexpr std::chrono::milliseconds kWriteTimeout{500};

// The line for `frame`, with its CR.
std::string encode(const Frame& frame);
// The frame a t/T/r/R line (without its CR) carries, an optional 4-digit time stamp ignored; on a
// malformed line, nothing, with the reason in `error`.
std::optional<Frame> decode(std::string_view line, std::string* error);
// S0..S8 for a bitrate in bit/s; throws std::invalid_argument listing the supported rates.
char bitrate_code(int bitrate);
int bitrate_of_code(char code);  // 0 for an unknown code
// `text` with control and non-ASCII bytes escaped, for messages about line noise.
std::string printable(std::string_view text);

// Splits the byte stream into tokens: a line (its CR removed), a BEL, or an overlong line dropped.
// LF and NUL bytes between lines are skipped, so CR LF endings work too.
class LineReader {
 public:
  struct Token {
    enum Kind { line, bell, overflow } kind;
    std::string text;
  };
  void feed(std::span<const char> bytes);
  std::optional<Token> next();

 private:
  std::deque<Token> tokens_;
  std::string partial_;
  bool overflowing_ = false;
};

struct Options {
  int bitrate = 500000;                          // the CAN bitrate (S code); 500 kbit/s is CANopen's most common
  int baud = 115200;                             // the serial line's speed; USB CDC adapters ignore it
  std::chrono::milliseconds reply_timeout{500};  // for each command while opening
  std::stop_token stop;                          // requested while opening: the opening gives up at once
};

// The host side: opens an adapter on a serial device and speaks CAN through it.
class SlcanBus final : public CanBus {
 public:
  // Opens `device` (a tty: /dev/ttyUSB0, /dev/ttyACM0, a pseudo-terminal), sets it raw at
  // options.baud, closes the channel, sets the bitrate and opens it. Throws BusError naming the
  // device and the reason: not there, not a tty, no answer, an error reply.
  SlcanBus(const std::string& device, const Options& options = {});
  ~SlcanBus() override;

  void send(const Frame& frame) override;
  std::optional<Frame> receive(std::chrono::milliseconds timeout) override;
  void close() override;

 private:
  // Reads what is there (waiting at most `timeout`) into the line reader; throws when the line is gone.
  bool read_some(std::chrono::milliseconds timeout);
  // While opening: reads until `deadline` at most, in short slices, so that a stop ends the wait.
  void read_while_opening(std::chrono::steady_clock::time_point deadline);
  // Sends a command and waits for its CR (true) or BEL (false); frames meanwhile are kept.
  bool command(const std::string& text, std::chrono::milliseconds timeout);

  std::stop_token stop_;
  Fd fd_;
  LineReader reader_;
  std::deque<Frame> pending_;  // frames that arrived while a command waited for its answer
};

}  // namespace fba::can::slcan
