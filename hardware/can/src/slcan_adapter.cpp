#include "fba/can/slcan_adapter.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace fba::can::slcan {

SlcanAdapter::SlcanAdapter(Fd line, std::string name) : CanBus(std::move(name)), fd_(std::move(line)) {
  set_nonblocking(fd_.get(), this->name());  // the parameter `name` was moved into the base
}

void SlcanAdapter::reply(std::string_view text) {
  write_all(fd_.get(), text.data(), text.size(), kWriteTimeout, name());
}

void SlcanAdapter::write_raw(std::span<const std::uint8_t> bytes) {
  write_all(fd_.get(), bytes.data(), bytes.size(), kWriteTimeout, name());
}

void SlcanAdapter::send(const Frame& frame) {
  if (!open_) return;  // a closed channel passes nothing from the bus to the host
  reply(encode(frame));
}

// Answers one host command; returns the frame it asks to transmit, if any.
std::optional<Frame> SlcanAdapter::handle(const std::string& line) {
  const std::string bell(1, kBell);
  if (line.empty()) {
    reply(bell);
    return std::nullopt;
  }
  switch (line[0]) {
    case 'S':
      if (line.size() == 2 && !open_ && bitrate_of_code(line[1]) > 0) {
        bitrate_ = bitrate_of_code(line[1]);
        reply("\r");
      } else {
        reply(bell);
      }
      return std::nullopt;
    case 'O':
      if (line.size() == 1 && !open_ && bitrate_ > 0) {
        open_ = true;
        reply("\r");
      } else {
        reply(bell);
      }
      return std::nullopt;
    case 'C':
      if (line.size() == 1 && open_) {
        open_ = false;
        reply("\r");
      } else {
        reply(bell);
      }
      return std::nullopt;
    case 'V':
      reply("V1013\r");
      return std::nullopt;
    case 'N':
      reply("NFBA0\r");
      return std::nullopt;
    case 'F':
      reply("F00\r");
      return std::nullopt;
    case 't':
    case 'T':
    case 'r':
    case 'R': {
      std::string error;
      auto frame = decode(line, &error);
      if (!open_ || !frame) {
        if (!frame) {
          discard("not a frame: " + error);
        }
        reply(bell);
        return std::nullopt;
      }
      reply(frame->extended ? "Z\r" : "z\r");
      return frame;
    }
    default:
      discard("an unknown command: '" + printable(line) + "'");
      reply(bell);
      return std::nullopt;
  }
}

std::optional<Frame> SlcanAdapter::receive(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  bool first_read = true;
  for (;;) {
    while (auto token = reader_.next()) {
      if (token->kind == LineReader::Token::line) {
        if (auto frame = handle(token->text)) return frame;
      } else if (token->kind == LineReader::Token::overflow) {
        discard("an overlong line of noise");
        reply(std::string(1, kBell));
      }
    }
    const auto now = std::chrono::steady_clock::now();
    if (!first_read && now >= deadline) return std::nullopt;
    first_read = false;
    const auto left =
        std::max(std::chrono::milliseconds(0), std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now));
    const Ready ready = wait_readable(fd_.get(), left, name());
    if (ready == Ready::timeout) continue;
    if (ready == Ready::hangup) throw BusError(name() + ": the host closed the serial line");
    char buffer[256];
    const ssize_t n = ::read(fd_.get(), buffer, sizeof buffer);
    if (n > 0)
      reader_.feed({buffer, static_cast<std::size_t>(n)});
    else if (n == 0 || (errno != EAGAIN && errno != EINTR))
      throw BusError(name() + ": the serial line is gone" +
                     (n < 0 ? std::string(": ") + std::strerror(errno) : std::string()));
  }
}

}  // namespace fba::can::slcan
