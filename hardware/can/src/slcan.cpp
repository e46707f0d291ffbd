#include "fba/can/slcan.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

namespace fba::can::slcan {

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kBitrates[] = {10000, 20000, 50000, 100000, 125000, 250000, 500000, 800000, 1000000};

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

// The value of `text` as hex digits, or -1 if one is not a hex digit.
long long parse_hex(std::string_view text) {
  long long v = 0;
  for (char c : text) {
    const int d = hex_digit(c);
    if (d < 0) return -1;
    v = v * 16 + d;
  }
  return v;
}

std::chrono::milliseconds left_until(Clock::time_point deadline) {
  return std::max(std::chrono::milliseconds(0),
                  std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()));
}

speed_t baud_constant(int baud, const std::string& name) {
  switch (baud) {
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 500000:
      return B500000;
    case 921600:
      return B921600;
    case 1000000:
      return B1000000;
    case 2000000:
      return B2000000;
    case 3000000:
      return B3000000;
    default:
      throw BusError(
          fmt::format("{}: baud rate {} is not supported; use 9600, 19200, 38400, 57600, 115200, 230400, 460800, "
                      "500000, 921600, 1000000, 2000000 or 3000000",
                      name, baud));
  }
}

std::string what_it_is(const struct stat& st) {
  if (S_ISDIR(st.st_mode)) return "a directory";
  if (S_ISREG(st.st_mode)) return "a regular file";
  if (S_ISFIFO(st.st_mode)) return "a FIFO";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  if (S_ISBLK(st.st_mode)) return "a block device";
  return "a character device that is not a terminal";
}

}  // namespace

std::string encode(const Frame& frame) {
  frame.validate();
  std::string s;
  s += frame.extended ? (frame.rtr ? 'R' : 'T') : (frame.rtr ? 'r' : 't');
  s += frame.extended ? fmt::format("{:08X}", frame.id) : fmt::format("{:03X}", frame.id);
  s += static_cast<char>('0' + frame.dlc);
  if (!frame.rtr)
    for (int i = 0; i < frame.dlc; ++i) s += fmt::format("{:02X}", frame.data[static_cast<std::size_t>(i)]);
  s += '\r';
  return s;
}

std::optional<Frame> decode(std::string_view line, std::string* error) {
  auto fail = [&](std::string why) -> std::optional<Frame> {
    if (error) *error = fmt::format("'{}': {}", printable(line), why);
    return std::nullopt;
  };
  if (line.empty()) return fail("an empty line is not a frame");
  Frame f;
  const char kind = line[0];
  if (kind != 't' && kind != 'T' && kind != 'r' && kind != 'R') return fail("a frame starts with t, T, r or R");
  f.extended = kind == 'T' || kind == 'R';
  f.rtr = kind == 'r' || kind == 'R';
  const std::size_t id_digits = f.extended ? 8 : 3;
  if (line.size() < 1 + id_digits + 1) return fail(fmt::format("too short for {} id digits and a length", id_digits));
  const long long id = parse_hex(line.substr(1, id_digits));
  if (id < 0) return fail("the identifier is not hexadecimal");
  f.id = static_cast<std::uint32_t>(id);
  const int dlc = hex_digit(line[1 + id_digits]);
  if (dlc < 0 || dlc > 8) return fail("the length digit must be 0 to 8");
  f.dlc = static_cast<std::uint8_t>(dlc);
  const std::size_t head = 1 + id_digits + 1;
  const std::size_t data_digits = f.rtr ? 0 : 2 * static_cast<std::size_t>(dlc);
  const std::size_t rest = line.size() - head;
  if (rest != data_digits && rest != data_digits + 4)  // + 4: a time stamp (Z1)
    return fail(fmt::format("{} characters after the length, expected {} (or {} with a time stamp)", rest, data_digits,
                            data_digits + 4));
  for (std::size_t i = 0; i < data_digits / 2; ++i) {
    const long long b = parse_hex(line.substr(head + 2 * i, 2));
    if (b < 0) return fail(fmt::format("data byte {} is not hexadecimal", i));
    f.data[i] = static_cast<std::uint8_t>(b);
  }
  if (rest == data_digits + 4 && parse_hex(line.substr(head + data_digits)) < 0)
    return fail("the time stamp is not hexadecimal");
  try {
    f.validate();
  } catch (const std::invalid_argument& e) {
    return fail(e.what());
  }
  return f;
}

char bitrate_code(int bitrate) {
  for (int i = 0; i < 9; ++i)
    if (kBitrates[i] == bitrate) return static_cast<char>('0' + i);
  throw std::invalid_argument(
      fmt::format("SLCAN: CAN bitrate {} is not one the S command sets; use 10000, 20000, 50000, 100000, 125000, "
                  "250000, 500000, 800000 or 1000000",
                  bitrate));
}

int bitrate_of_code(char code) { return code >= '0' && code <= '8' ? kBitrates[code - '0'] : 0; }

std::string printable(std::string_view text) {
  std::string s;
  for (unsigned char c : text) {
    if (c >= 0x20 && c < 0x7F && c != '\\')
      s += static_cast<char>(c);
    else
      s += fmt::format("\\x{:02X}", c);
  }
  return s;
}

void LineReader::feed(std::span<const char> bytes) {
  for (char c : bytes) {
    if (c == '\r') {
      if (overflowing_)
        tokens_.push_back({Token::overflow, std::move(partial_)});
      else
        tokens_.push_back({Token::line, std::move(partial_)});
      partial_.clear();
      overflowing_ = false;
    } else if (c == kBell) {
      tokens_.push_back({Token::bell, {}});
    } else if ((c == '\n' || c == '\0') && partial_.empty()) {
      // between lines: a CR LF ending, or padding
    } else if (partial_.size() < kMaxLine) {
      partial_ += c;
    } else {
      overflowing_ = true;  // keep the start for the message, drop the rest until the next CR
    }
  }
}

std::optional<LineReader::Token> LineReader::next() {
  if (tokens_.empty()) return std::nullopt;
  Token t = std::move(tokens_.front());
  tokens_.pop_front();
  return t;
}

SlcanBus::SlcanBus(const std::string& device, const Options& options) : CanBus("slcan:" + device), stop_(options.stop) {
  const char code = bitrate_code(options.bitrate);
  const speed_t speed = baud_constant(options.baud, name());
  fd_.reset(::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC));
  if (!fd_) throw BusError(name() + ": cannot open the serial line: " + std::strerror(errno));
  if (!::isatty(fd_.get())) {
    struct stat st {};
    ::fstat(fd_.get(), &st);
    throw BusError(name() + ": not a serial line but " + what_it_is(st));
  }
  termios tio{};
  if (::tcgetattr(fd_.get(), &tio) != 0)
    throw BusError(name() + ": cannot read the line settings: " + std::strerror(errno));
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~CRTSCTS;
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  ::cfsetispeed(&tio, speed);
  ::cfsetospeed(&tio, speed);
  if (::tcsetattr(fd_.get(), TCSANOW, &tio) != 0)
    throw BusError(name() + ": cannot set the line raw: " + std::strerror(errno));
  ::tcflush(fd_.get(), TCIOFLUSH);

  // A half-typed command from an earlier session ends with the first of these CRs. Each CR is
  // answered (CR, BEL, or the half-typed command's reply), and all three answers are awaited before
  // the real commands: a late one would otherwise be taken for the answer to 'C' and shift every
  // answer after it by one, so that 'S' got 'C''s BEL (an adapter slower than a pause in the line,
  // as on a loaded machine). Frames of a channel left open are not answers. An adapter that does
  // not answer empty commands costs reply_timeout here, no more.
  write_all(fd_.get(), "\r\r\r", 3, kWriteTimeout, name());
  const auto drain_until = Clock::now() + options.reply_timeout;
  for (int answers = 0; answers < 3 && Clock::now() < drain_until;) {
    read_while_opening(drain_until);
    while (auto token = reader_.next())
      if (token->kind == LineReader::Token::bell ||
          (token->kind == LineReader::Token::line && !decode(token->text, nullptr)))
        ++answers;
  }
  reader_ = LineReader{};
  command("C", options.reply_timeout);  // closing a closed channel is an error on some adapters: either answer will do
  if (!command(std::string("S") + code, options.reply_timeout))
    throw BusError(fmt::format("{}: the adapter refused the bitrate command 'S{}' ({} bit/s) with BEL", name(), code,
                               options.bitrate));
  if (!command("O", options.reply_timeout))
    throw BusError(name() + ": the adapter refused to open the channel ('O' answered with BEL)");
}

SlcanBus::~SlcanBus() {
  try {
    close();
  } catch (...) {  // a line already gone has nothing left to close
  }
}

void SlcanBus::close() {
  if (!fd_) return;
  try {
    write_all(fd_.get(), "C\r", 2, std::chrono::milliseconds(50), name());
  } catch (const BusError&) {  // the line is gone: nothing to close on the adapter
  }
  fd_.reset();
}

bool SlcanBus::read_some(std::chrono::milliseconds timeout) {
  const Ready ready = wait_readable(fd_.get(), timeout, name());
  if (ready == Ready::timeout) return false;
  if (ready == Ready::hangup)
    throw BusError(name() + ": the serial line hung up (the adapter was unplugged or the other end closed)");
  char buffer[256];
  const ssize_t n = ::read(fd_.get(), buffer, sizeof buffer);
  if (n > 0) {
    reader_.feed({buffer, static_cast<std::size_t>(n)});
    return true;
  }
  if (n < 0 && (errno == EAGAIN || errno == EINTR)) return false;
  if (n < 0) throw BusError(name() + ": read failed: " + std::strerror(errno) + " (the adapter is gone)");
  // poll said readable, yet nothing came: the tty's other end is gone
  throw BusError(name() + ": the serial line returned end of file (the adapter was unplugged or the other end closed)");
}

bool SlcanBus::command(const std::string& text, std::chrono::milliseconds timeout) {
  const std::string line = text + '\r';
  write_all(fd_.get(), line.data(), line.size(), kWriteTimeout, name());
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    while (auto token = reader_.next()) {
      if (token->kind == LineReader::Token::bell) return false;
      if (token->kind == LineReader::Token::overflow) {
        discard("an overlong line of noise: '" + printable(token->text) + "...'");
      } else if (token->text.empty()) {
        return true;
      } else if (auto f = decode(token->text, nullptr)) {
        pending_.push_back(*f);
      }  // z/Z acknowledgements and other replies are not this command's answer
    }
    if (Clock::now() >= deadline)
      throw BusError(
          fmt::format("{}: no answer to '{}' within {} ms: is it an SLCAN adapter, and is the baud rate right?", name(),
                      text, timeout.count()));
    read_while_opening(deadline);
  }
}

void SlcanBus::read_while_opening(Clock::time_point deadline) {
  if (stop_.stop_requested()) throw BusError(name() + ": opening the adapter stopped: the application is stopping");
  read_some(std::min(left_until(deadline), std::chrono::milliseconds(10)));
}

void SlcanBus::send(const Frame& frame) {
  const std::string line = encode(frame);
  write_all(fd_.get(), line.data(), line.size(), kWriteTimeout, name());
}

std::optional<Frame> SlcanBus::receive(std::chrono::milliseconds timeout) {
  if (!fd_) throw BusError(name() + ": the line is closed");
  const auto deadline = Clock::now() + timeout;
  bool first_read = true;
  for (;;) {
    if (!pending_.empty()) {
      Frame f = pending_.front();
      pending_.pop_front();
      return f;
    }
    while (auto token = reader_.next()) {
      switch (token->kind) {
        case LineReader::Token::bell:
          discard("the adapter answered BEL (an error: bus off, overrun or a refused frame)");
          break;
        case LineReader::Token::overflow:
          discard("an overlong line of noise: '" + printable(token->text) + "...'");
          break;
        case LineReader::Token::line: {
          const std::string& text = token->text;
          if (text.empty() || text == "z" || text == "Z") break;  // acknowledgements of what we sent
          std::string error;
          if (auto f = decode(text, &error)) return f;
          discard("not a frame: " + error);
          break;
        }
      }
    }
    // At least one read, even with a zero timeout; a flood of noise still ends at the deadline.
    if (!first_read && Clock::now() >= deadline) return std::nullopt;
    first_read = false;
    read_some(left_until(deadline));
  }
}

}  // namespace fba::can::slcan
