// libFuzzer target: arbitrary bytes as an HTTP request to the live view's server (fba-run --serve),
// parsed by Beast's parser with the server's limits and answered by route_request. A crash, a
// sanitizer report, or an answer that breaks the server's promises is a finding: a file served
// without the run's token, a file that is not one of the page's, an upgrade from an Origin that is
// not the page's.
#include <stdlib.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <boost/beast/http.hpp>

#include "page_files.hpp"
#include "request_routing.hpp"

namespace {

namespace http = boost::beast::http;

const std::string kToken = "0123456789abcdef0123456789abcdef";

// The page: two files in a folder of their own, read as the server reads its page.
const fba::serve::PageFiles& page() {
  static const fba::serve::PageFiles files = [] {
    char dir[] = "/tmp/fuzz-request-page-XXXXXX";
    if (!::mkdtemp(dir)) std::abort();
    std::filesystem::create_directories(std::string(dir) + "/assets");
    std::ofstream(std::string(dir) + "/index.html") << "<!doctype html>";
    std::ofstream(std::string(dir) + "/assets/app.js") << "1;";
    fba::serve::PageFiles f = fba::serve::PageFiles::load(dir);
    std::filesystem::remove_all(dir);
    return f;
  }();
  return files;
}

const fba::serve::Access& access() {
  static const fba::serve::Access a{kToken, fba::serve::page_origins("127.0.0.1", 8080, true), "fba_token_8080"};
  return a;
}

[[noreturn]] void finding(const char* what, const fba::serve::Request& r) {
  std::fprintf(stderr, "%s: %.*s\n", what, static_cast<int>(r.target().size()), r.target().data());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  http::request_parser<http::string_body> parser;
  parser.header_limit(8192);  // as the server reads a request
  parser.body_limit(4096);
  parser.eager(true);
  boost::beast::error_code ec;
  parser.put(boost::asio::buffer(data, size), ec);
  if (!ec && !parser.is_done()) parser.put_eof(ec);
  if (ec || !parser.is_done()) return 0;
  const fba::serve::Request request = parser.release();
  const fba::serve::Route route = fba::serve::route_request(request, access(), page());
  const std::string target(request.target());
  const bool token_in_query = fba::serve::query_value(target, "token") == kToken;
  const auto cookie = request.find(http::field::cookie);
  const bool token_in_cookie =
      cookie != request.end() && std::string(cookie->value()).find("fba_token_8080=" + kToken) != std::string::npos;
  if (route.kind == fba::serve::Route::File) {
    if (!token_in_query && !token_in_cookie) finding("a file served without the token", request);
    if (!route.file || (route.file != page().find("index.html") && route.file != page().find("assets/app.js")))
      finding("a file that is not the page's", request);
  }
  if (route.kind == fba::serve::Route::Upgrade) {
    const auto origin = request.find(http::field::origin);
    if (!token_in_query) finding("an upgrade without the token", request);
    if (origin == request.end() || !access().origins.count(std::string(origin->value())))
      finding("an upgrade from another Origin", request);
  }
  return 0;
}
