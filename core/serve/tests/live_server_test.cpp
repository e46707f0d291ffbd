// The live view's server in this process, against a real client on a real socket: who may read the
// page and the stream (token, Origin), what it serves (only the page's files), what it refuses
// (oversized messages, too many clients), and the stream's order.
#include "live_server.hpp"

#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/live_client.hpp"
#include "request_routing.hpp"
#include "support/temp_dir.hpp"

namespace {

using fba::serve::LiveMessage;
using fba::serve::LiveServer;
using fba::serve::RunRecord;
using namespace fba::test;

// A built page of two files, and a server for it on a free loopback port.
class LiveServerTest : public ::testing::Test {
 protected:
  LiveServerTest() {
    page_.write("index.html", "<!doctype html><title>page</title>");
    page_.write("assets/app.js", "console.log('app');");
    page_.write(".hidden", "secret");
    outside_.write("secret.txt", "not the page's");
  }
  void start(std::size_t max_clients = 16) {
    fba::serve::ServerOptions o;
    o.page = fba::serve::PageFiles::load(page_.path());
    o.max_clients = max_clients;
    server_ = std::make_unique<LiveServer>(std::move(o), record_);
    url_ = parse_live_url(server_->url());
  }
  void publish(LiveMessage::Kind kind, const std::string& text) { server_->publish(record_.add(kind, text)); }
  // A WebSocket accepted with the page's Origin.
  std::unique_ptr<LiveSocket> connect() {
    auto s = std::make_unique<LiveSocket>(url_);
    beast::error_code ec;
    s->handshake(url_.origin(), url_.token, ec);
    EXPECT_FALSE(ec) << ec.message();
    return s;
  }

  TempDir page_{"page"}, outside_{"outside"};
  RunRecord record_;
  std::unique_ptr<LiveServer> server_;
  LiveUrl url_;
};

std::string type_of(const std::string& message) { return nlohmann::json::parse(message).at("type"); }

TEST_F(LiveServerTest, ListensOnLoopbackWithANewTokenOfThirtyTwoHexDigits) {
  start();
  EXPECT_EQ(url_.host, "127.0.0.1");
  EXPECT_NE(url_.port, "0");
  EXPECT_EQ(url_.token.size(), 32u);
  EXPECT_EQ(url_.token.find_first_not_of("0123456789abcdef"), std::string::npos) << url_.token;
  EXPECT_NE(fba::serve::new_token(), fba::serve::new_token());
}

TEST_F(LiveServerTest, ServesThePageOnlyWithTheToken) {
  start();
  const auto ok = http_get(url_, "/?token=" + url_.token);
  EXPECT_EQ(ok.result(), http::status::ok);
  EXPECT_EQ(ok.body(), "<!doctype html><title>page</title>");
  EXPECT_EQ(http_get(url_, "/index.html?token=" + url_.token).result(), http::status::ok);
  EXPECT_EQ(http_get(url_, "/").result(), http::status::forbidden);
  EXPECT_EQ(http_get(url_, "/?token=" + std::string(32, '0')).result(), http::status::forbidden);
  EXPECT_EQ(http_get(url_, "/?token=" + url_.token.substr(1)).result(), http::status::forbidden);
  EXPECT_EQ(http_get(url_, "/assets/app.js").result(), http::status::forbidden);
}

TEST_F(LiveServerTest, ThePagesOtherFilesComeWithTheCookieTheIndexSets) {
  start();
  const auto index = http_get(url_, "/?token=" + url_.token);
  const std::string cookie(index[http::field::set_cookie]);
  ASSERT_EQ(cookie.rfind("fba_token_" + url_.port + "=" + url_.token + ";", 0), 0u) << cookie;
  EXPECT_NE(cookie.find("HttpOnly"), std::string::npos);
  const std::string pair = cookie.substr(0, cookie.find(';'));
  const auto js = http_get(url_, "/assets/app.js", pair);
  EXPECT_EQ(js.result(), http::status::ok);
  EXPECT_EQ(js.body(), "console.log('app');");
  EXPECT_EQ(std::string(js[http::field::content_type]), "text/javascript; charset=utf-8");
  EXPECT_EQ(http_get(url_, "/assets/app.js", "fba_token_" + url_.port + "=" + std::string(32, 'a')).result(), http::status::forbidden);
}

TEST_F(LiveServerTest, ServesNothingButThePagesOwnFiles) {
  start();
  const std::string t = "?token=" + url_.token;
  EXPECT_EQ(http_get(url_, "/.hidden" + t).result(), http::status::not_found);
  EXPECT_EQ(http_get(url_, "/../" + outside_.path().filename().string() + "/secret.txt" + t).result(), http::status::not_found);
  EXPECT_EQ(http_get(url_, "/assets/../index.html" + t).result(), http::status::not_found);
  EXPECT_EQ(http_get(url_, "/assets" + t).result(), http::status::not_found);
  EXPECT_EQ(http_get(url_, "/etc/passwd" + t).result(), http::status::not_found);
  EXPECT_EQ(http_get(url_, "//etc/passwd" + t).result(), http::status::not_found);
}

TEST_F(LiveServerTest, AnswersOnlyGetAndHead) {
  start();
  const auto head = http_request(url_, http::verb::head, "/?token=" + url_.token);
  EXPECT_EQ(head.result(), http::status::ok);
  EXPECT_EQ(std::string(head[http::field::content_length]), "34");
  const auto post = http_request(url_, http::verb::post, "/?token=" + url_.token);
  EXPECT_EQ(post.result(), http::status::method_not_allowed);
  EXPECT_EQ(std::string(post[http::field::allow]), "GET, HEAD");
}

TEST_F(LiveServerTest, TheBuiltInPageStandsInWhenTheFrontEndIsNotBuilt) {
  fba::serve::ServerOptions o;
  o.page = fba::serve::PageFiles::load(outside_.path());  // no index.html there
  EXPECT_FALSE(o.page.built());
  server_ = std::make_unique<LiveServer>(std::move(o), record_);
  url_ = parse_live_url(server_->url());
  const auto page = http_get(url_, "/?token=" + url_.token);
  EXPECT_EQ(page.result(), http::status::ok);
  EXPECT_NE(page.body().find("front end is not built"), std::string::npos);
  EXPECT_NE(page.body().find("npm"), std::string::npos);
  EXPECT_EQ(http_get(url_, "/secret.txt?token=" + url_.token).result(), http::status::not_found);
}

TEST_F(LiveServerTest, RefusesAWebSocketFromAnotherOriginOrWithoutTheToken) {
  start();
  EXPECT_EQ(upgrade_status(url_, "http://evil.example:" + url_.port, url_.token), http::status::forbidden);
  EXPECT_EQ(upgrade_status(url_, "http://127.0.0.1:1", url_.token), http::status::forbidden);
  EXPECT_EQ(upgrade_status(url_, "", url_.token), http::status::forbidden);
  EXPECT_EQ(upgrade_status(url_, url_.origin(), std::string(32, 'f')), http::status::forbidden);
  EXPECT_EQ(upgrade_status(url_, "http://localhost:" + url_.port, url_.token), http::status::switching_protocols);
}

TEST_F(LiveServerTest, AMessageOverTheCapEndsTheConnection) {
  start();
  auto socket = connect();
  beast::error_code ec;
  socket->write(R"({"type":"ping"})", ec);
  ASSERT_FALSE(ec) << ec.message();
  socket->write(std::string(5000, 'x'), ec);
  ASSERT_FALSE(ec) << ec.message();
  // Messages may still be in flight; the connection then ends, closed by the server as too big.
  while (!ec) socket->read(ec);
  if (ec == websocket::error::closed) EXPECT_EQ(socket->close_reason().code, websocket::close_code::too_big);
  // The server goes on for the others.
  auto other = connect();
  publish(LiveMessage::Task, R"({"type":"task"})");
  EXPECT_EQ(type_of(other->read(ec)), "task");
}

TEST_F(LiveServerTest, APageIsSentTheRunSoFarThenEachMessageInOrderThenTheEnd) {
  record_.add(LiveMessage::Task, R"({"type":"task","components":[]})");
  record_.add(LiveMessage::Stats, R"({"type":"stats","t":0.1})");
  record_.add(LiveMessage::Stats, R"({"type":"stats","t":0.2})");
  record_.add(LiveMessage::Event, R"({"type":"event","index":0})");
  start();
  auto socket = connect();
  beast::error_code ec;
  EXPECT_EQ(socket->read(ec), R"({"type":"task","components":[]})");
  EXPECT_EQ(socket->read(ec), R"({"type":"stats","t":0.2})");  // the last stats only
  EXPECT_EQ(socket->read(ec), R"({"type":"event","index":0})");
  publish(LiveMessage::Event, R"({"type":"event","index":1})");
  publish(LiveMessage::End, R"({"type":"end"})");
  EXPECT_EQ(socket->read(ec), R"({"type":"event","index":1})");
  EXPECT_EQ(socket->read(ec), R"({"type":"end"})");
  // The close handshake needs this side to read: finish() waits for it on another thread.
  std::thread finishing([this] { server_->finish(kHangLimit); });
  socket->read(ec);
  finishing.join();
  EXPECT_EQ(ec, websocket::error::closed) << ec.message();
  EXPECT_EQ(socket->close_reason().code, websocket::close_code::normal);
}

TEST_F(LiveServerTest, RefusesMoreClientsThanItsLimit) {
  start(2);
  auto a = connect();
  auto b = connect();
  // Both are registered once each has been sent a message published after it connected.
  publish(LiveMessage::Task, R"({"type":"task"})");
  beast::error_code ec;
  EXPECT_EQ(type_of(a->read(ec)), "task");
  EXPECT_EQ(type_of(b->read(ec)), "task");
  EXPECT_EQ(upgrade_status(url_, url_.origin(), url_.token), http::status::service_unavailable);
}

}  // namespace
