// What fba-run --serve answers to one HTTP request, decided apart from the sockets so that it can be
// tested and fuzzed on its own: the token, the Origin of a WebSocket upgrade, the method, and the
// file by its exact name.
#pragma once

#include <set>
#include <string>
#include <string_view>

#include <boost/beast/http/message.hpp>
#include <boost/beast/http/string_body.hpp>

#include "page_files.hpp"

namespace fba::serve {

using Request = boost::beast::http::request<boost::beast::http::string_body>;

// Who may use the server: the run's token, and the Origins a page of this server has.
struct Access {
  std::string token;                // 32 hex characters
  std::set<std::string> origins;    // "http://127.0.0.1:8080", ...; empty: Origin must match Host
  std::string cookie;               // the cookie's name that carries the token for the page's other files
};

// A new token for a run: 128 bits from the random device, as 32 hex characters.
std::string new_token();

// The Origins a browser sends from the page served at `host:port` (the host as url_host gives
// it): that one, and for a loopback address the other loopback names (127.0.0.1, localhost, [::1]).
std::set<std::string> page_origins(const std::string& host, unsigned port, bool loopback);

struct Route {
  enum Kind { File, Upgrade, Forbidden, NotFound, MethodNotAllowed, BadRequest } kind = NotFound;
  const PageFile* file = nullptr;  // File
  bool set_cookie = false;         // File: the token came in the query; the page's other files need it
  std::string reason;              // what the answer's body says
};

Route route_request(const Request& request, const Access& access, const PageFiles& page);

// The value of `name` in a target's query ("/ws?token=ab&x=1"), percent-decoding left out (a
// token is hex); empty when absent.
std::string query_value(std::string_view target, std::string_view name);

}  // namespace fba::serve
