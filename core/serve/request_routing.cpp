// One request's answer (see request_routing.hpp). The token is compared in constant time, and a
// request's path only ever selects a name in PageFiles' list.
#include "request_routing.hpp"

#include <cstdio>
#include <random>

#include <boost/beast/websocket/rfc6455.hpp>

namespace fba::serve {

namespace http = boost::beast::http;

namespace {

bool same_secret(std::string_view a, std::string_view b) {
  if (a.size() != b.size() || a.empty()) return false;
  unsigned char diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

// The value of cookie `name` in a Cookie header ("a=1; fba_token_8080=ab").
std::string cookie_value(std::string_view header, std::string_view name) {
  while (!header.empty()) {
    const auto semi = header.find(';');
    std::string_view pair = header.substr(0, semi);
    header = semi == std::string_view::npos ? std::string_view() : header.substr(semi + 1);
    while (!pair.empty() && pair.front() == ' ') pair.remove_prefix(1);
    if (pair.size() > name.size() && pair.substr(0, name.size()) == name && pair[name.size()] == '=')
      return std::string(pair.substr(name.size() + 1));
  }
  return {};
}

}  // namespace

std::string new_token() {
  std::random_device random;
  std::string token;
  for (int i = 0; i < 4; ++i) {
    char part[9];
    std::snprintf(part, sizeof part, "%08x", static_cast<unsigned>(random()));
    token += part;
  }
  return token;
}

std::set<std::string> page_origins(const std::string& host, unsigned port, bool loopback) {
  const std::string p = ":" + std::to_string(port);
  std::set<std::string> origins{"http://" + host + p};
  if (loopback)
    for (const char* name : {"127.0.0.1", "localhost", "[::1]"}) origins.insert("http://" + std::string(name) + p);
  return origins;
}

std::string query_value(std::string_view target, std::string_view name) {
  const auto q = target.find('?');
  if (q == std::string_view::npos) return {};
  std::string_view query = target.substr(q + 1);
  if (const auto hash = query.find('#'); hash != std::string_view::npos) query = query.substr(0, hash);
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
    if (pair.size() > name.size() && pair.substr(0, name.size()) == name && pair[name.size()] == '=')
      return std::string(pair.substr(name.size() + 1));
  }
  return {};
}

Route route_request(const Request& request, const Access& access, const PageFiles& page) {
  Route r;
  const std::string_view target(request.target().data(), request.target().size());
  if (target.empty() || target.front() != '/') return {Route::BadRequest, nullptr, false, "the request's target must be a path"};
  const std::string_view path = target.substr(0, target.find_first_of("?#"));
  const bool upgrade = boost::beast::websocket::is_upgrade(request);
  if (request.method() != http::verb::get && request.method() != http::verb::head)
    return {Route::MethodNotAllowed, nullptr, false, "only GET and HEAD are served"};

  const bool query_token = same_secret(query_value(target, "token"), access.token);
  const auto cookie = request.find(http::field::cookie);
  const bool cookie_token =
      !access.cookie.empty() && cookie != request.end() &&
      same_secret(cookie_value(std::string_view(cookie->value().data(), cookie->value().size()), access.cookie), access.token);

  if (path == "/ws") {
    if (!upgrade) return {Route::BadRequest, nullptr, false, "/ws is the live stream: connect with a WebSocket"};
    if (!query_token) return {Route::Forbidden, nullptr, false, "the live stream needs this run's token: /ws?token=TOKEN"};
    const auto origin = request.find(http::field::origin);
    if (origin == request.end()) return {Route::Forbidden, nullptr, false, "a WebSocket without an Origin is refused"};
    const std::string o(origin->value().data(), origin->value().size());
    bool allowed = access.origins.count(o) > 0;
    if (access.origins.empty()) {  // listening on every address: the page's Origin is the Host it asked
      const auto host = request.find(http::field::host);
      allowed = host != request.end() && o == "http://" + std::string(host->value().data(), host->value().size());
    }
    if (!allowed) return {Route::Forbidden, nullptr, false, "Origin '" + o + "' is not this server's page"};
    return {Route::Upgrade, nullptr, false, {}};
  }
  if (!query_token && !cookie_token)
    return {Route::Forbidden, nullptr, false, "this page needs the run's token: the URL fba-run printed, with ?token="};
  std::string_view name = path.substr(1);
  if (name.empty()) name = "index.html";
  r.file = page.find(name);
  if (!r.file) return {Route::NotFound, nullptr, false, "no such file in the page"};
  r.kind = Route::File;
  r.set_cookie = query_token;
  return r;
}

}  // namespace fba::serve
