// A client of the live view's server for tests: plain HTTP requests and a WebSocket, with
// Boost.Beast, as a browser would make them (Origin, Host). Blocking; every read is bounded by a
// hang detector, not a speed check.
#pragma once

#include <chrono>
#include <stdexcept>
#include <string>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

namespace fba::test {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = boost::asio::ip::tcp;

// A run that hangs is found by this, not by ctest's timeout minutes later.
constexpr std::chrono::seconds kHangLimit{120};

// "http://127.0.0.1:PORT/?token=TOKEN", as fba-run says it.
struct LiveUrl {
  std::string host, port, token;
  std::string origin() const { return "http://" + host + ":" + port; }
};

inline LiveUrl parse_live_url(const std::string& url) {
  const std::string scheme = "http://";
  const auto colon = url.find(':', scheme.size());
  const auto slash = url.find('/', scheme.size());
  const auto token = url.find("?token=");
  if (url.rfind(scheme, 0) != 0 || colon == std::string::npos || slash == std::string::npos || token == std::string::npos)
    throw std::invalid_argument("not a live view URL: '" + url + "'");
  return {url.substr(scheme.size(), colon - scheme.size()), url.substr(colon + 1, slash - colon - 1), url.substr(token + 7)};
}

// One request on a connection of its own.
inline http::response<http::string_body> http_request(const LiveUrl& url, http::verb method, const std::string& target,
                                                       const std::string& cookie = {}) {
  boost::asio::io_context io;
  beast::tcp_stream stream(io);
  stream.expires_after(kHangLimit);
  stream.connect(tcp::resolver(io).resolve(url.host, url.port));
  http::request<http::string_body> req(method, target, 11);
  req.set(http::field::host, url.host + ":" + url.port);
  if (!cookie.empty()) req.set(http::field::cookie, cookie);
  http::write(stream, req);
  beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  parser.body_limit(64u << 20);
  if (method == http::verb::head) parser.skip(true);
  http::read(stream, buffer, parser);
  return parser.release();
}

inline http::response<http::string_body> http_get(const LiveUrl& url, const std::string& target, const std::string& cookie = {}) {
  return http_request(url, http::verb::get, target, cookie);
}

// The server's answer to a WebSocket upgrade of /ws?token=TOKEN from `origin` (none when empty),
// asked as a browser asks it: 101 when it would be accepted.
inline http::status upgrade_status(const LiveUrl& url, const std::string& origin, const std::string& token) {
  boost::asio::io_context io;
  beast::tcp_stream stream(io);
  stream.expires_after(kHangLimit);
  stream.connect(tcp::resolver(io).resolve(url.host, url.port));
  http::request<http::empty_body> req(http::verb::get, "/ws?token=" + token, 11);
  req.set(http::field::host, url.host + ":" + url.port);
  req.set(http::field::connection, "Upgrade");
  req.set(http::field::upgrade, "websocket");
  req.set(http::field::sec_websocket_version, "13");
  req.set(http::field::sec_websocket_key, "dGhlIHNhbXBsZSBub25jZQ==");
  if (!origin.empty()) req.set(http::field::origin, origin);
  http::write(stream, req);
  beast::flat_buffer buffer;
  http::response<http::string_body> res;
  http::read(stream, buffer, res);
  return res.result();
}

// A WebSocket to /ws?token=TOKEN with an Origin.
class LiveSocket {
 public:
  explicit LiveSocket(const LiveUrl& url) : url_(url), ws_(io_) {
    beast::get_lowest_layer(ws_).expires_after(kHangLimit);
    beast::get_lowest_layer(ws_).connect(tcp::resolver(io_).resolve(url.host, url.port));
  }
  // The upgrade; `ec` set when it was refused (upgrade_status says how).
  void handshake(const std::string& origin, const std::string& token, beast::error_code& ec) {
    ws_.set_option(websocket::stream_base::decorator([origin](websocket::request_type& r) {
      if (!origin.empty()) r.set(http::field::origin, origin);
    }));
    ws_.handshake(url_.host + ":" + url_.port, "/ws?token=" + token, ec);
  }
  // The next message's text; empty with `ec` set when the connection ended, or timed out after
  // kHangLimit (the stream's expiry bounds asynchronous operations only: a blocking read, the close
  // handshake's teardown included, would wait for ever on a server that never closes).
  std::string read(beast::error_code& ec) {
    beast::get_lowest_layer(ws_).expires_after(kHangLimit);
    beast::flat_buffer buffer;
    ws_.async_read(buffer, [&ec](beast::error_code e, std::size_t) { ec = e; });
    io_.restart();
    io_.run();
    return ec ? std::string() : beast::buffers_to_string(buffer.data());
  }
  void write(const std::string& text, beast::error_code& ec) {
    ws_.text(true);
    ws_.write(boost::asio::buffer(text), ec);
  }
  websocket::close_reason close_reason() const { return ws_.reason(); }

 private:
  LiveUrl url_;
  boost::asio::io_context io_;
  websocket::stream<beast::tcp_stream> ws_;
};

}  // namespace fba::test
