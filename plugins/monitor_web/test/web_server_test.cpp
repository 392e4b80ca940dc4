// The monitor's server on its own: loopback and a token, read-only, bounded
// input, and a client that does not read loses messages (counted) instead of
// holding up the sender.
#include "web_server.hpp"
#include "web_client.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <condition_variable>
#include <mutex>

namespace plr::monitor_web::testing {
namespace {

class Pages : public WebHandler {
 public:
  std::optional<HttpReply> get(std::string_view path) override {
    if (path == "/") return HttpReply{"text/plain", "hello"};
    return std::nullopt;
  }
  void opened(std::uint64_t client, Protocol) override {
    std::lock_guard lock(m);
    last_client = client;
    cv.notify_all();
  }
  void received(std::uint64_t, std::string_view text) override {
    std::lock_guard lock(m);
    texts.emplace_back(text);
    cv.notify_all();
  }
  void closed(std::uint64_t) override { ++closed_count; }

  std::uint64_t wait_client() {
    std::unique_lock lock(m);
    cv.wait_for(lock, std::chrono::seconds(10), [&] { return last_client != 0; });
    return last_client;
  }

  std::mutex m;
  std::condition_variable cv;
  std::uint64_t last_client = 0;
  std::vector<std::string> texts;
  std::atomic<int> closed_count{0};
};

std::unique_ptr<WebServer> serve(Pages& pages, WebServerOptions o = {}) {
  o.port = 0;
  auto s = WebServer::start(o, pages);
  EXPECT_TRUE(s) << s.error().message;
  if (!s) return nullptr;
  (*s)->serve();
  return std::move(*s);
}

TEST(WebServer, OffLoopbackItNeedsAToken) {
  WebServerOptions o;
  o.bind = "0.0.0.0";
  const auto s = validate(o);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message,
            "param 'token': bound to '0.0.0.0' (not loopback), the monitor needs a token of at "
            "least 16 characters");
  o.token = "0123456789abcdef";
  EXPECT_TRUE(validate(o));
  o.bind = "localhost";
  EXPECT_EQ(validate(o).error().message, "param 'bind': 'localhost' is not an IP address");
}

TEST(WebServer, WithATokenEveryRequestMustCarryIt) {
  Pages pages;
  WebServerOptions o;
  o.token = "0123456789abcdef";
  auto server = serve(pages, o);
  ASSERT_TRUE(server);
  EXPECT_EQ(http_get(server->port(), "/").status, 401);
  EXPECT_EQ(http_get(server->port(), "/?token=0123456789abcdeX").status, 401);
  const auto ok = http_get(server->port(), "/?token=0123456789abcdef");
  EXPECT_EQ(ok.status, 200);
  EXPECT_EQ(ok.body, "hello");
  EXPECT_THROW(WsClient("127.0.0.1", server->port(), "/ws"), boost::system::system_error);
  EXPECT_NO_THROW(WsClient("127.0.0.1", server->port(), "/ws?token=0123456789abcdef"));
}

TEST(WebServer, IsReadOnlyAndBoundsRequests) {
  Pages pages;
  auto server = serve(pages);
  ASSERT_TRUE(server);
  net::io_context ioc;
  const auto ask = [&](const std::string& raw) {
    tcp::socket s(ioc);
    s.connect({net::ip::make_address("127.0.0.1"), server->port()});
    set_timeout(s, std::chrono::seconds(10));
    net::write(s, net::buffer(raw));
    std::string reply(64, '\0');
    beast::error_code ec;
    reply.resize(s.read_some(net::buffer(reply), ec));
    return reply;
  };
  EXPECT_EQ(ask("POST / HTTP/1.1\r\nHost: x\r\n\r\n").substr(0, 12), "HTTP/1.1 405");
  EXPECT_EQ(ask("GET /nothing HTTP/1.1\r\nHost: x\r\n\r\n").substr(0, 12), "HTTP/1.1 404");
  // Headers over the limit: the connection is closed without an answer.
  EXPECT_EQ(ask("GET / HTTP/1.1\r\nHost: x\r\nX-Big: " + std::string(20000, 'a') + "\r\n\r\n"), "");
  EXPECT_EQ(server->stats().refused_requests, 2u);
}

TEST(WebServer, AWebSocketMessageOverTheLimitClosesTheConnection) {
  Pages pages;
  WebServerOptions o;
  o.max_ws_message = 1024;
  auto server = serve(pages, o);
  ASSERT_TRUE(server);
  WsClient client("127.0.0.1", server->port(), "/", "foxglove.websocket.v1");
  client.send_text("small");
  client.send_text(std::string(4096, 'x'));
  EXPECT_FALSE(client.read());
  std::lock_guard lock(pages.m);
  ASSERT_EQ(pages.texts.size(), 1u);
  EXPECT_EQ(pages.texts[0], "small");
}

TEST(WebServer, AClientThatDoesNotReadLosesMessagesAndIsCounted) {
  Pages pages;
  WebServerOptions o;
  o.send_limit = 256u << 10;
  auto server = serve(pages, o);
  ASSERT_TRUE(server);
  WsClient slow("127.0.0.1", server->port(), "/ws");
  const auto client = pages.wait_client();
  ASSERT_NE(client, 0u);
  const auto message = std::make_shared<const std::string>(64u << 10, 'm');
  int accepted = 0;
  for (int i = 0; i < 2000; ++i) accepted += server->send(client, message, true) ? 1 : 0;
  // Nothing waited for the client, which never reads (a send that waited
  // would not return): of the 128 MB offered, what its send limit and the
  // socket's buffers do not hold is dropped.
  const auto s = server->stats();
  EXPECT_GT(s.dropped_messages, 1000u);
  EXPECT_EQ(s.dropped_messages + static_cast<std::uint64_t>(accepted), 2000u);
  EXPECT_EQ(s.dropped_bytes, s.dropped_messages * message->size());
  // What was accepted still arrives, in order and whole.
  auto first = slow.read();
  ASSERT_TRUE(first);
  EXPECT_EQ(first->data.size(), message->size());
}

}  // namespace
}  // namespace plr::monitor_web::testing
