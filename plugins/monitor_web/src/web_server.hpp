// The monitor's HTTP and WebSocket server (Boost.Beast, one I/O thread).
// Read-only: GET and HEAD only; WebSocket clients may only ask for data.
// Bound to loopback unless configured; bound elsewhere, every request needs
// the token (`?token=` or `Authorization: Bearer`). Every input is bounded:
// request headers, WebSocket messages, and what waits to be sent to each
// client (over the limit a message is dropped and counted, never waited for).
#pragma once

#include <plr/expected.hpp>

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace plr::monitor_web {

struct WebServerOptions {
  std::string bind = "127.0.0.1";
  std::uint16_t port = 8765;          // 0: any free port (see WebServer::port)
  std::string token;                  // required when `bind` is not a loopback address
  std::size_t send_limit = 8u << 20;  // bytes queued per client before messages drop
  std::size_t max_header = 8u << 10;
  std::size_t max_ws_message = 64u << 10;
};

// "What and where" when options are unusable (a token missing off loopback).
Status validate(const WebServerOptions& options);

enum class Protocol { kDashboard, kFoxglove };

struct HttpReply {
  std::string content_type;
  std::string body;
};

// Called on the server's I/O thread.
class WebHandler {
 public:
  virtual ~WebHandler() = default;
  virtual std::optional<HttpReply> get(std::string_view path) = 0;
  virtual void opened(std::uint64_t client, Protocol protocol) = 0;
  // A text message from a Foxglove client (dashboard clients' input is ignored).
  virtual void received(std::uint64_t client, std::string_view text) = 0;
  virtual void closed(std::uint64_t client) = 0;
};

struct WebServerStats {
  std::uint64_t clients = 0;
  std::uint64_t sent_messages = 0;
  std::uint64_t dropped_messages = 0;  // over a client's send limit
  std::uint64_t dropped_bytes = 0;
  std::uint64_t refused_requests = 0;  // bad token, method, size or path
};

class WebServer {
 public:
  // Listening when it returns, serving once serve() is called (so the
  // handler can keep the server before its first call); `handler` must
  // outlive the server.
  static Expected<std::unique_ptr<WebServer>> start(const WebServerOptions& options,
                                                    WebHandler& handler);
  void serve();
  // Stops serving: the handler is not called any more once it returns.
  void stop();
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  std::uint16_t port() const;
  // Queues `data` for one client (any thread). False when dropped: the
  // client is gone or already has send_limit bytes waiting.
  bool send(std::uint64_t client, std::shared_ptr<const std::string> data, bool binary);
  // The same message to every client of `protocol`.
  void broadcast(Protocol protocol, const std::shared_ptr<const std::string>& data, bool binary);
  WebServerStats stats() const;

  class Impl;

 private:
  explicit WebServer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace plr::monitor_web
