// A small blocking HTTP and WebSocket client for the tests and benches that
// talk to the monitor (Boost.Beast; reads time out through SO_RCVTIMEO, so a
// test fails rather than hangs).
#pragma once

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <sys/socket.h>
#include <sys/time.h>

#include <chrono>
#include <optional>
#include <string>

namespace plr::monitor_web::testing {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

inline void set_timeout(tcp::socket& s, std::chrono::milliseconds t) {
  timeval tv{static_cast<time_t>(t.count() / 1000),
             static_cast<suseconds_t>(t.count() % 1000 * 1000)};
  ::setsockopt(s.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  ::setsockopt(s.native_handle(), SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
}

struct HttpResult {
  int status = 0;
  std::string body;
};

// GET http://127.0.0.1:port/target; status 0 when the connection failed.
inline HttpResult http_get(std::uint16_t port, const std::string& target,
                           const std::string& host = "127.0.0.1") {
  net::io_context ioc;
  tcp::socket socket(ioc);
  beast::error_code ec;
  socket.connect({net::ip::make_address(host), port}, ec);
  if (ec) return {};
  set_timeout(socket, std::chrono::seconds(10));
  http::request<http::empty_body> req{http::verb::get, target, 11};
  req.set(http::field::host, host);
  http::write(socket, req, ec);
  if (ec) return {};
  beast::flat_buffer buffer;
  http::response<http::string_body> res;
  http::read(socket, buffer, res, ec);
  if (ec) return {};
  return {static_cast<int>(res.result_int()), res.body()};
}

inline std::string unbase64(const std::string& in) {
  static const std::string kAlphabet =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::uint32_t bits = 0;
  int n = 0;
  for (char c : in) {
    const auto v = kAlphabet.find(c);
    if (v == std::string::npos) break;
    bits = bits << 6 | static_cast<std::uint32_t>(v);
    if ((n += 6) >= 8) {
      n -= 8;
      out.push_back(static_cast<char>((bits >> n) & 0xff));
    }
  }
  return out;
}

class WsClient {
 public:
  struct Frame {
    bool binary = false;
    std::string data;
  };

  // Throws when the handshake fails.
  WsClient(const std::string& host, std::uint16_t port, const std::string& target,
           const std::string& subprotocol = {}) {
    ws_.next_layer().connect({net::ip::make_address(host), port});
    set_timeout(ws_.next_layer(), std::chrono::seconds(10));
    if (!subprotocol.empty())
      ws_.set_option(websocket::stream_base::decorator([subprotocol](websocket::request_type& r) {
        r.set(http::field::sec_websocket_protocol, subprotocol);
      }));
    ws_.handshake(response_, host + ":" + std::to_string(port), target);
  }

  const websocket::response_type& handshake_response() const { return response_; }

  // Replaces the read timeout (10 s from the constructor).
  void set_read_timeout(std::chrono::milliseconds t) { set_timeout(ws_.next_layer(), t); }

  void send_text(const std::string& text) {
    ws_.text(true);
    ws_.write(net::buffer(text));
  }

  // The next message, or nothing after the read timeout or on close.
  std::optional<Frame> read() {
    beast::flat_buffer buffer;
    beast::error_code ec;
    ws_.read(buffer, ec);
    if (ec) return std::nullopt;
    return Frame{ws_.got_binary(), beast::buffers_to_string(buffer.data())};
  }

 private:
  net::io_context ioc_;
  websocket::stream<tcp::socket> ws_{ioc_};
  websocket::response_type response_;
};

}  // namespace plr::monitor_web::testing
