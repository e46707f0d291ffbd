// --serve's address (see listen_address.hpp): parsed with Asio's own address parser, so that what
// is accepted here is exactly what the server can bind.
#include "listen_address.hpp"

#include <charconv>
#include <stdexcept>

#include <boost/asio/ip/address.hpp>

namespace fba::serve {

namespace {

std::uint16_t parse_port(const std::string& text, const std::string& whole) {
  unsigned value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size() || value > 65535)
    throw std::invalid_argument("--serve expects [ADDR:]PORT with PORT a number from 0 (a free port) to 65535; found '" +
                                whole + "'");
  return static_cast<std::uint16_t>(value);
}

}  // namespace

ListenAddress parse_listen_address(const std::string& text) {
  ListenAddress a;
  std::string host, port = text;
  if (!text.empty() && text.front() == '[') {  // [IPv6]:PORT
    const auto close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':')
      throw std::invalid_argument("--serve expects [IPV6]:PORT for an IPv6 address; found '" + text + "'");
    host = text.substr(1, close - 1);
    port = text.substr(close + 2);
  } else if (const auto colon = text.rfind(':'); colon != std::string::npos) {
    host = text.substr(0, colon);
    port = text.substr(colon + 1);
    if (host.find(':') != std::string::npos)
      throw std::invalid_argument("--serve: write an IPv6 address in brackets, [ADDR]:PORT; found '" + text + "'");
  }
  a.port = parse_port(port, text);
  if (host.empty()) return a;
  if (host == "localhost") host = "127.0.0.1";
  boost::system::error_code ec;
  const auto address = boost::asio::ip::make_address(host, ec);
  if (ec)
    throw std::invalid_argument("--serve expects an IP address before the port (127.0.0.1, 0.0.0.0, [::1]); found '" + host +
                                "' in '" + text + "'");
  a.host = address.to_string();
  a.loopback = address.is_loopback();
  return a;
}

std::string url_host(const std::string& host) { return host.find(':') != std::string::npos ? "[" + host + "]" : host; }

}  // namespace fba::serve
