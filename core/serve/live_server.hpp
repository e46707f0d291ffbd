// fba-run --serve: the live view's HTTP and WebSocket server (Boost.Beast) on a thread of its own.
// It serves the page's files (PageFiles) to requests with the run's token, and streams the run's
// messages (RunRecord) to each page over a WebSocket: first what was said so far, then each new
// one as it is published. docs/live-view.md is the user's reference.
#pragma once

#include <chrono>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>

#include "listen_address.hpp"
#include "page_files.hpp"
#include "run_record.hpp"

namespace fba::serve {

struct ServerOptions {
  ListenAddress address;
  PageFiles page;
  std::size_t max_clients = 16;      // WebSocket clients at once; more are answered 503
  std::size_t max_incoming = 4096;   // bytes of one message from a page (read_message_max)
  std::size_t queue_limit = 64;      // messages queued per client before old stats and views are dropped
  std::string token;                 // empty: a new one (new_token())
};

class LiveServer {
 public:
  // Listens now (so the port is known, and a port in use is an error before the run starts) and
  // starts serving on its own thread. Throws std::runtime_error naming the address and the reason.
  LiveServer(ServerOptions options, const RunRecord& record);
  ~LiveServer();  // stops at once, clients cut off
  LiveServer(const LiveServer&) = delete;
  LiveServer& operator=(const LiveServer&) = delete;

  // http://HOST:PORT/?token=TOKEN: the page's address.
  std::string url() const;
  unsigned short port() const;

  // Sends a message the record has just numbered to every client. From any thread, in the order
  // the record numbered them; never waits for a client.
  void publish(const LiveMessage& message);

  // Sends what is queued, closes each client's WebSocket in order and stops; waits at most
  // `grace` for slow clients, which are then cut off.
  void finish(std::chrono::milliseconds grace);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace fba::serve
