// Where fba-run --serve listens: `[ADDR:]PORT` as the user wrote it, checked.
#pragma once

#include <cstdint>
#include <string>

namespace fba::serve {

struct ListenAddress {
  std::string host = "127.0.0.1";  // an IP address (IPv6 without brackets)
  std::uint16_t port = 0;          // 0: a free port, chosen when listening
  bool loopback = true;            // only this machine can connect
};

// Parses "PORT", "ADDR:PORT" or "[IPv6]:PORT"; "localhost" is 127.0.0.1. Throws
// std::invalid_argument saying what was expected and what was found.
ListenAddress parse_listen_address(const std::string& text);

// The host as it goes into a URL or an Origin: IPv6 in brackets.
std::string url_host(const std::string& host);

}  // namespace fba::serve
