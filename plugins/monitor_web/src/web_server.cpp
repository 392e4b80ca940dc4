#include "web_server.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <deque>
#include <map>
#include <mutex>
#include <thread>

namespace plr::monitor_web {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

constexpr std::string_view kFoxgloveProtocol = "foxglove.websocket.v1";

namespace {

bool is_loopback(const std::string& bind) {
  boost::system::error_code ec;
  const auto a = net::ip::make_address(bind, ec);
  return !ec && a.is_loopback();
}

// Compares in time independent of where the strings differ.
bool same_secret(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::string_view view(beast::string_view s) {
  return {s.data(), s.size()};
}

// "/path?token=x&y" -> "/path" and the token's value.
std::pair<std::string_view, std::string_view> split_target(std::string_view target) {
  const auto q = target.find('?');
  if (q == std::string_view::npos) return {target, {}};
  std::string_view query = target.substr(q + 1);
  std::string_view token;
  while (!query.empty()) {
    const auto amp = query.find('&');
    const auto part = query.substr(0, amp);
    if (part.starts_with("token=")) token = part.substr(6);
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return {target.substr(0, q), token};
}

}  // namespace

Status validate(const WebServerOptions& o) {
  boost::system::error_code ec;
  net::ip::make_address(o.bind, ec);
  if (ec) return make_error(PLR_ERR_INVALID, "param 'bind': '" + o.bind + "' is not an IP address");
  if (!is_loopback(o.bind) && o.token.size() < 16)
    return make_error(PLR_ERR_INVALID,
                      "param 'token': bound to '" + o.bind +
                          "' (not loopback), the monitor needs a token of at least 16 characters");
  if (o.send_limit < 1024)
    return make_error(PLR_ERR_INVALID, "param 'send_limit': must be >= 1024");
  return {};
}

class WsSession;

class WebServer::Impl {
 public:
  Impl(const WebServerOptions& o, WebHandler& h) : options(o), handler(h) {}

  void accept() {
    acceptor.async_accept(net::make_strand(ioc), [this](beast::error_code ec, tcp::socket s) {
      if (ec == net::error::operation_aborted) return;
      if (!ec) start_http(std::move(s));
      accept();
    });
  }
  void start_http(tcp::socket socket);
  void add(std::uint64_t id, const std::shared_ptr<WsSession>& s, Protocol p);
  void remove(std::uint64_t id);

  WebServerOptions options;
  WebHandler& handler;
  net::io_context ioc{1};
  tcp::acceptor acceptor{ioc};
  std::thread thread;
  mutable std::mutex m;
  struct Client {
    std::weak_ptr<WsSession> session;
    Protocol protocol;
  };
  std::map<std::uint64_t, Client> clients;
  std::atomic<std::uint64_t> next_id{1};
  std::atomic<std::uint64_t> sent{0}, dropped{0}, dropped_bytes{0}, refused{0};
};

class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(WebServer::Impl& server, tcp::socket&& socket, Protocol protocol)
      : server_(server), ws_(std::move(socket)), protocol_(protocol) {}

  void accept(http::request<http::empty_body> request) {
    beast::get_lowest_layer(ws_).expires_never();
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(server_.options.max_ws_message);
    if (protocol_ == Protocol::kFoxglove)
      ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& r) {
        r.set(http::field::sec_websocket_protocol,
              beast::string_view(kFoxgloveProtocol.data(), kFoxgloveProtocol.size()));
      }));
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      self->server_.add(self->id_, self, self->protocol_);
      self->read();
    });
  }

  // On any thread: counted against the limit here, written on the I/O thread.
  bool enqueue(std::shared_ptr<const std::string> data, bool binary) {
    const auto size = data->size();
    auto queued = queued_bytes_.load();
    do {
      if (queued + size > server_.options.send_limit) return false;
    } while (!queued_bytes_.compare_exchange_weak(queued, queued + size));
    net::post(ws_.get_executor(),
              [self = shared_from_this(), data = std::move(data), binary]() mutable {
                self->queue_.emplace_back(std::move(data), binary);
                if (self->queue_.size() == 1) self->write();
              });
    return true;
  }

  std::uint64_t id() const { return id_; }
  void set_id(std::uint64_t id) { id_ = id; }

 private:
  void read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->close();
      if (self->protocol_ == Protocol::kFoxglove && self->ws_.got_text())
        self->server_.handler.received(self->id_, beast::buffers_to_string(self->in_.data()));
      self->in_.consume(self->in_.size());
      self->read();
    });
  }
  void write() {
    auto& [data, binary] = queue_.front();
    ws_.binary(binary);
    ws_.async_write(net::buffer(*data),
                    [self = shared_from_this()](beast::error_code ec, std::size_t) {
                      self->queued_bytes_ -= self->queue_.front().first->size();
                      self->queue_.pop_front();
                      if (ec) return self->close();
                      ++self->server_.sent;
                      if (!self->queue_.empty()) self->write();
                    });
  }
  void close() {
    if (closed_) return;
    closed_ = true;
    server_.remove(id_);
  }

  WebServer::Impl& server_;
  websocket::stream<beast::tcp_stream> ws_;
  Protocol protocol_;
  std::uint64_t id_ = 0;
  beast::flat_buffer in_;
  std::deque<std::pair<std::shared_ptr<const std::string>, bool>> queue_;
  std::atomic<std::size_t> queued_bytes_{0};
  bool closed_ = false;
};

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(WebServer::Impl& server, tcp::socket&& socket)
      : server_(server), stream_(std::move(socket)) {}

  void read() {
    parser_.emplace();
    parser_->header_limit(static_cast<std::uint32_t>(server_.options.max_header));
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) {
                       if (ec) return self->shut();
                       self->handle(self->parser_->release());
                     });
  }

 private:
  void handle(http::request<http::empty_body> req) {
    const auto [path, query_token] = split_target(view(req.target()));
    if (!server_.options.token.empty()) {
      std::string_view token = query_token;
      const auto auth = view(req[http::field::authorization]);
      if (auth.starts_with("Bearer ")) token = auth.substr(7);
      if (!same_secret(token, server_.options.token))
        return refuse(req, http::status::unauthorized, "a token is required\n");
    }
    if (websocket::is_upgrade(req)) {
      const auto offered = view(req[http::field::sec_websocket_protocol]);
      const bool foxglove = offered.find(kFoxgloveProtocol) != std::string_view::npos;
      if (!foxglove && path != "/ws")
        return refuse(req, http::status::not_found, "WebSocket: /ws or foxglove.websocket.v1\n");
      auto ws = std::make_shared<WsSession>(server_, stream_.release_socket(),
                                            foxglove ? Protocol::kFoxglove : Protocol::kDashboard);
      ws->set_id(server_.next_id++);
      ws->accept(std::move(req));
      return;
    }
    if (req.method() != http::verb::get && req.method() != http::verb::head)
      return refuse(req, http::status::method_not_allowed, "read-only: GET and HEAD only\n");
    auto page = server_.handler.get(path);
    if (!page) return refuse(req, http::status::not_found, "not found\n");
    auto res = std::make_shared<http::response<http::string_body>>(http::status::ok, req.version());
    res->set(http::field::content_type, page->content_type);
    res->set(http::field::cache_control, "no-store");
    res->keep_alive(req.keep_alive());
    if (req.method() == http::verb::get) res->body() = std::move(page->body);
    res->prepare_payload();
    reply(res);
  }

  void refuse(const http::request<http::empty_body>& req, http::status status,
              std::string_view why) {
    ++server_.refused;
    auto res = std::make_shared<http::response<http::string_body>>(status, req.version());
    res->set(http::field::content_type, "text/plain");
    res->keep_alive(false);
    res->body() = why;
    res->prepare_payload();
    reply(res);
  }

  void reply(const std::shared_ptr<http::response<http::string_body>>& res) {
    http::async_write(stream_, *res,
                      [self = shared_from_this(), res](beast::error_code ec, std::size_t) {
                        if (ec || !res->keep_alive()) return self->shut();
                        self->read();
                      });
  }

  void shut() {
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
  }

  WebServer::Impl& server_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_{8192};
  std::optional<http::request_parser<http::empty_body>> parser_;
};

void WebServer::Impl::start_http(tcp::socket socket) {
  std::make_shared<HttpSession>(*this, std::move(socket))->read();
}

void WebServer::Impl::add(std::uint64_t id, const std::shared_ptr<WsSession>& s, Protocol p) {
  {
    std::lock_guard lock(m);
    clients[id] = {s, p};
  }
  handler.opened(id, p);
}

void WebServer::Impl::remove(std::uint64_t id) {
  {
    std::lock_guard lock(m);
    if (clients.erase(id) == 0) return;
  }
  handler.closed(id);
}

Expected<std::unique_ptr<WebServer>> WebServer::start(const WebServerOptions& options,
                                                      WebHandler& handler) {
  if (auto s = validate(options); !s) return s.error();
  auto impl = std::make_unique<Impl>(options, handler);
  beast::error_code ec;
  const tcp::endpoint at(net::ip::make_address(options.bind), options.port);
  impl->acceptor.open(at.protocol(), ec);
  if (!ec) impl->acceptor.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) impl->acceptor.bind(at, ec);
  if (!ec) impl->acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec)
    return make_error(PLR_ERR_UNAVAILABLE, "monitor_web: cannot listen on " + options.bind + ":" +
                                               std::to_string(options.port) + ": " + ec.message());
  return std::unique_ptr<WebServer>(new WebServer(std::move(impl)));
}

WebServer::WebServer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

void WebServer::serve() {
  if (impl_->thread.joinable()) return;
  impl_->accept();
  impl_->thread = std::thread([i = impl_.get()] { i->ioc.run(); });
}

WebServer::~WebServer() {
  stop();
}

void WebServer::stop() {
  impl_->ioc.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

std::uint16_t WebServer::port() const {
  return impl_->acceptor.local_endpoint().port();
}

bool WebServer::send(std::uint64_t client, std::shared_ptr<const std::string> data, bool binary) {
  std::shared_ptr<WsSession> session;
  {
    std::lock_guard lock(impl_->m);
    const auto it = impl_->clients.find(client);
    if (it != impl_->clients.end()) session = it->second.session.lock();
  }
  if (session && session->enqueue(data, binary)) return true;
  ++impl_->dropped;
  impl_->dropped_bytes += data->size();
  return false;
}

void WebServer::broadcast(Protocol protocol, const std::shared_ptr<const std::string>& data,
                          bool binary) {
  std::vector<std::uint64_t> ids;
  {
    std::lock_guard lock(impl_->m);
    for (const auto& [id, c] : impl_->clients)
      if (c.protocol == protocol) ids.push_back(id);
  }
  for (auto id : ids) send(id, data, binary);
}

WebServerStats WebServer::stats() const {
  WebServerStats s;
  {
    std::lock_guard lock(impl_->m);
    s.clients = impl_->clients.size();
  }
  s.sent_messages = impl_->sent;
  s.dropped_messages = impl_->dropped;
  s.dropped_bytes = impl_->dropped_bytes;
  s.refused_requests = impl_->refused;
  return s;
}

}  // namespace plr::monitor_web
