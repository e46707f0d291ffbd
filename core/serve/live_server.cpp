// The live view's server (see live_server.hpp). One io_context on one thread: every session, the
// client list and each client's queue are touched on that thread only; publish() posts to it.
#include "live_server.hpp"

#include <condition_variable>
#include <iostream>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "fba/version.hpp"
#include "outgoing_queue.hpp"
#include "request_routing.hpp"

namespace fba::serve {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

namespace {

constexpr const char* kServerName = "fba-run/" FBA_VERSION;
// A request's header and body: a page asks with a line and a few headers, and sends no body.
constexpr std::uint32_t kMaxHeaderBytes = 8192;
constexpr std::uint64_t kMaxBodyBytes = 4096;
// HTTP connections at once (a page opens a few): more are closed as they come.
constexpr std::size_t kMaxHttpSessions = 64;
// A client that cannot take even the messages that are never dropped (events, end) is cut off
// past this many queued.
constexpr std::size_t kMaxQueued = 16384;

class WsSession;

}  // namespace

struct LiveServer::Impl {
  explicit Impl(const RunRecord& r) : record(r) {}
  // Declared before io: a session the io_context destroys with its handlers still counts itself out.
  const RunRecord& record;
  ServerOptions options;
  Access access;
  std::string url;
  unsigned short port = 0;
  std::size_t http_sessions = 0;  // io thread
  bool finishing = false;         // io thread
  std::mutex mutex;
  std::condition_variable drained;
  bool no_clients = false;  // under mutex: finishing, and every client closed
  asio::io_context io{1};
  tcp::acceptor acceptor{io};
  std::set<std::shared_ptr<WsSession>> clients;  // io thread; emptied before io is destroyed
  std::vector<std::weak_ptr<WsSession>> sessions;  // io thread: every WebSocket begun, for finish() to close what is left
  std::thread thread;

  void accept();
  void remove(const std::shared_ptr<WsSession>& client);
};

namespace {

class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(tcp::socket socket, LiveServer::Impl& server)
      : ws_(std::move(socket)), server_(server), queue_(server.options.queue_limit, kMaxQueued) {}

  void start(Request request) {
    std::erase_if(server_.sessions, [](const std::weak_ptr<WsSession>& s) { return s.expired(); });  // pages that came and went
    server_.sessions.push_back(weak_from_this());
    beast::get_lowest_layer(ws_).expires_never();
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& r) { r.set(http::field::server, kServerName); }));
    ws_.read_message_max(server_.options.max_incoming);
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) { self->on_accept(ec); });
  }

  // A message published after the client was given the record up to `replayed_`.
  void send(const LiveMessage& m) {
    if (m.seq <= replayed_ || closing_) return;
    if (!queue_.push(m, writing_)) return close(websocket::close_code::policy_error);
    if (!writing_) write_next();
  }

  // With the io thread stopped: the connection ends here, whatever its close handshake had reached,
  // so that no page is left waiting on an open socket.
  void drop() {
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }

  // The run is over: what is queued is sent, then the WebSocket closes in order.
  void finish() {
    finishing_ = true;
    if (!writing_) close(websocket::close_code::normal);
  }

 private:
  void on_accept(beast::error_code ec) {
    if (ec) return;
    server_.clients.insert(shared_from_this());
    RunRecord::Replay replay = server_.record.replay();
    replayed_ = replay.up_to;
    queue_.assign(replay.messages);
    read();
    if (server_.finishing) finishing_ = true;
    write_next();
  }

  void write_next() {
    if (closing_) return;
    if (queue_.empty()) {
      writing_ = false;
      if (finishing_) close(websocket::close_code::normal);
      return;
    }
    writing_ = true;
    ws_.text(true);
    ws_.async_write(asio::buffer(*queue_.front().text), [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->server_.remove(self);
      self->queue_.pop();
      self->write_next();
    });
  }

  // The page sends nothing that matters ({"type":"ping"}); reading keeps the connection's control
  // frames going and finds a message over the cap, which ends the connection. A close this side
  // began ends the read before the close's teardown is done: then the close says when the client
  // is gone, since a server stopped before the teardown leaves the page waiting on an open socket.
  void read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) {
        if (!self->closing_) self->server_.remove(self);
        return;
      }
      self->in_.consume(self->in_.size());
      self->read();
    });
  }

  void close(websocket::close_code code) {
    if (closing_) return;
    closing_ = true;
    ws_.async_close(code, [self = shared_from_this()](beast::error_code) { self->server_.remove(self); });
  }

  websocket::stream<beast::tcp_stream> ws_;
  LiveServer::Impl& server_;
  beast::flat_buffer in_;
  OutgoingQueue queue_;
  std::uint64_t replayed_ = 0;
  bool writing_ = false, closing_ = false, finishing_ = false;
};

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, LiveServer::Impl& server) : stream_(std::move(socket)), server_(server) { ++server_.http_sessions; }
  ~HttpSession() { --server_.http_sessions; }

  void read() {
    parser_.emplace();
    parser_->header_limit(kMaxHeaderBytes);
    parser_->body_limit(kMaxBodyBytes);
    stream_.expires_after(std::chrono::seconds(30));  // a connection that says nothing does not hold its place
    http::async_read(stream_, buffer_, *parser_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

 private:
  void on_read(beast::error_code ec) {
    if (ec == http::error::body_limit || ec == http::error::header_limit)
      return answer(http::status::payload_too_large, "the request is too large", false, false);
    if (ec) return shutdown();
    Request request = parser_->release();
    const Route route = route_request(request, server_.access, server_.options.page);
    head_ = request.method() == http::verb::head;
    version_ = request.version();
    switch (route.kind) {
      case Route::Upgrade:
        if (server_.finishing) return answer(http::status::service_unavailable, "the run is over", false, false);
        if (server_.clients.size() >= server_.options.max_clients)
          return answer(http::status::service_unavailable, "too many live views of this run are open", false, false);
        stream_.expires_never();
        return std::make_shared<WsSession>(stream_.release_socket(), server_)->start(std::move(request));
      case Route::File: return send_file(*route.file, route.set_cookie, request.keep_alive());
      case Route::Forbidden: return answer(http::status::forbidden, route.reason, false, request.keep_alive());
      case Route::NotFound: return answer(http::status::not_found, route.reason, false, request.keep_alive());
      case Route::MethodNotAllowed: return answer(http::status::method_not_allowed, route.reason, true, false);
      case Route::BadRequest: return answer(http::status::bad_request, route.reason, false, false);
    }
  }

  void send_file(const PageFile& file, bool set_cookie, bool keep_alive) {
    auto res = std::make_shared<http::response<http::string_body>>(http::status::ok, version_);
    res->set(http::field::content_type, file.content_type);
    // The page's other files come without the token in their URL: a cookie carries it to them.
    if (set_cookie) res->set(http::field::set_cookie, server_.access.cookie + "=" + server_.access.token + "; Path=/; HttpOnly; SameSite=Strict");
    res->body() = file.body;
    write(res, keep_alive);
  }

  void answer(http::status status, const std::string& reason, bool allow, bool keep_alive) {
    auto res = std::make_shared<http::response<http::string_body>>(status, version_ ? version_ : 11);
    res->set(http::field::content_type, "text/plain; charset=utf-8");
    if (allow) res->set(http::field::allow, "GET, HEAD");
    res->body() = reason + "\n";
    write(res, keep_alive);
  }

  void write(const std::shared_ptr<http::response<http::string_body>>& res, bool keep_alive) {
    res->set(http::field::server, kServerName);
    res->set(http::field::cache_control, "no-store");
    res->set("X-Content-Type-Options", "nosniff");
    res->set("Referrer-Policy", "no-referrer");  // the token is in the page's URL
    res->keep_alive(keep_alive);
    res->prepare_payload();
    if (head_) res->body().clear();  // Content-Length stays the file's
    http::async_write(stream_, *res, [self = shared_from_this(), res](beast::error_code ec, std::size_t) {
      if (ec || !res->keep_alive()) return self->shutdown();
      self->read();
    });
  }

  void shutdown() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
  }

  beast::tcp_stream stream_;
  LiveServer::Impl& server_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  bool head_ = false;
  unsigned version_ = 11;
};

}  // namespace

void LiveServer::Impl::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted) return;
    if (!ec && http_sessions < kMaxHttpSessions) std::make_shared<HttpSession>(std::move(socket), *this)->read();
    accept();
  });
}

void LiveServer::Impl::remove(const std::shared_ptr<WsSession>& client) {
  clients.erase(client);
  if (finishing && clients.empty()) {
    std::lock_guard lock(mutex);
    no_clients = true;
    drained.notify_all();
  }
}

LiveServer::LiveServer(ServerOptions options, const RunRecord& record) : impl_(std::make_unique<Impl>(record)) {
  Impl& s = *impl_;
  s.options = std::move(options);
  const ListenAddress& a = s.options.address;
  const std::string where = url_host(a.host) + ":" + std::to_string(a.port);
  beast::error_code ec;
  const tcp::endpoint endpoint(asio::ip::make_address(a.host, ec), a.port);
  if (!ec) s.acceptor.open(endpoint.protocol(), ec);
  if (!ec) s.acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) s.acceptor.bind(endpoint, ec);
  if (!ec) s.acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) throw std::runtime_error("--serve: cannot listen on " + where + ": " + ec.message());
  const unsigned short bound = s.port = s.acceptor.local_endpoint().port();
  s.access.token = s.options.token.empty() ? new_token() : s.options.token;
  s.access.cookie = "fba_token_" + std::to_string(bound);
  // Listening on every address, the page may be reached by any of the machine's names: its Origin
  // must then be the Host it asked for (the token still decides).
  if (!endpoint.address().is_unspecified()) s.access.origins = page_origins(url_host(a.host), bound, a.loopback);
  s.url = "http://" + url_host(a.host) + ":" + std::to_string(bound) + "/?token=" + s.access.token;
  s.accept();
  s.thread = std::thread([&s] {
    for (;;) {
      try {
        s.io.run();
        return;
      } catch (const std::exception& e) {  // a handler's bad_alloc: the server goes on
        std::cerr << "fba-run: live view: " << e.what() << "\n";
      }
    }
  });
}

LiveServer::~LiveServer() {
  if (impl_->thread.joinable()) {
    impl_->io.stop();
    impl_->thread.join();
  }
  impl_->clients.clear();
}

std::string LiveServer::url() const { return impl_->url; }
unsigned short LiveServer::port() const { return impl_->port; }

void LiveServer::publish(const LiveMessage& message) {
  asio::post(impl_->io, [s = impl_.get(), message] {
    // A copy: a client that fails while being sent to leaves the set.
    const auto clients = s->clients;
    for (const auto& c : clients) c->send(message);
  });
}

void LiveServer::finish(std::chrono::milliseconds grace) {
  Impl& s = *impl_;
  if (!s.thread.joinable()) return;
  asio::post(s.io, [&s] {
    s.finishing = true;
    beast::error_code ignored;
    s.acceptor.close(ignored);
    const auto clients = s.clients;
    for (const auto& c : clients) c->finish();
    if (s.clients.empty()) {
      std::lock_guard lock(s.mutex);
      s.no_clients = true;
      s.drained.notify_all();
    }
  });
  {
    std::unique_lock lock(s.mutex);
    s.drained.wait_for(lock, grace, [&s] { return s.no_clients; });
  }
  s.io.stop();
  s.thread.join();
  for (const auto& session : s.sessions)
    if (const auto c = session.lock()) c->drop();
}

}  // namespace fba::serve
