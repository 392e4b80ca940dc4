// monitor_web: a live web dashboard of the pipeline and a Foxglove WebSocket
// server on one port, fed only from the kernel's bus (the world, the
// executor's state, progress and the kernels' telemetry). Read-only. Besides
// the bus topics, Foxglove clients get the world as a foxglove.SceneUpdate.
#include "dashboard_state.hpp"
#include "foxglove_channels.hpp"
#include "foxglove_scene.hpp"
#include "web_server.hpp"

#include <plr/embedded_file.hpp>
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <thread>
#include <type_traits>

extern const plr::EmbeddedFile plr_monitor_web_pages[];
extern const std::size_t plr_monitor_web_pages_count;

namespace plr::monitor_web {
namespace {

std::string content_type(std::string_view name) {
  if (name.ends_with(".html")) return "text/html; charset=utf-8";
  if (name.ends_with(".js")) return "text/javascript; charset=utf-8";
  if (name.ends_with(".css")) return "text/css; charset=utf-8";
  if (name.ends_with(".png")) return "image/png";
  return "application/octet-stream";
}

// The Foxglove channel of the scene ('/' keeps it apart from bus topics).
constexpr const char* kSceneTopic = "/scene";

class MonitorWebNode final : public Node, public WebHandler {
 public:
  using Node::Node;
  ~MonitorWebNode() override { stop(); }

 protected:
  Status on_configure() override {
    params().allow_only(
        {"bind", "port", "token", "send_limit_mb", "update_hz", "scene_hz", "draw_robot", "urdf"});
    options_.bind = params().get<std::string>("bind", "127.0.0.1");
    const auto port = params().get<std::int64_t>("port", 8765);
    if (port < 0 || port > 65535) return make_error(PLR_ERR_INVALID, "param 'port': 0..65535");
    options_.port = static_cast<std::uint16_t>(port);
    options_.token = params().get<std::string>("token", "");
    const auto limit = params().get<double>("send_limit_mb", 8.0);
    if (!(limit >= 0.001 && limit <= 1024))
      return make_error(PLR_ERR_INVALID, "param 'send_limit_mb': 0.001..1024");
    options_.send_limit = static_cast<std::size_t>(limit * (1 << 20));
    update_hz_ = params().get<double>("update_hz", 10.0);
    if (!(update_hz_ > 0 && update_hz_ <= 100))
      return make_error(PLR_ERR_INVALID, "param 'update_hz': must be in (0, 100]");
    scene_hz_ = params().get<double>("scene_hz", 10.0);
    if (!(scene_hz_ > 0 && scene_hz_ <= 30))
      return make_error(PLR_ERR_INVALID, "param 'scene_hz': must be in (0, 30]");
    if (auto s = validate(options_); !s) return s;
    std::optional<sim::RobotModel> robot;
    if (params().get<bool>("draw_robot", true)) {
      auto model = sim::load_robot(params().get<std::string>("urdf", ""));
      if (!model) return make_error(PLR_ERR_INVALID, "param 'urdf': " + model.error().message);
      robot = std::move(*model);
    }
    scene_ = std::make_unique<FoxgloveScene>(robot);
    state_ = std::make_unique<DashboardState>(std::move(robot));
    return {};
  }

  Status on_activate() override {
    stopping_ = false;
    // The dashboard's own topics; any other is read once a Foxglove client asks.
    for (const auto& [topic, type] :
         {std::pair{"world", MessageTraits<msg::WorldState>::type_id()},
          std::pair{"executor/state", MessageTraits<msg::ExecutorState>::type_id()},
          std::pair{"progress", MessageTraits<msg::Progress>::type_id()},
          std::pair{"kernel/telemetry", MessageTraits<msg::KernelTelemetry>::type_id()}}) {
      if (auto s = read_topic(topic, type); !s) return s;
      channels_.add(topic, type);
    }
    channels_.add_json(kSceneTopic, FoxgloveScene::kSchemaName, FoxgloveScene::json_schema());
    auto server = WebServer::start(options_, *this);
    if (!server) return server.error();
    server_ = std::move(*server);
    server_->serve();
    log().info("dashboard on http://{}:{}/", options_.bind, server_->port());
    pusher_ = std::thread([this] { push_loop(); });
    return {};
  }

  Status on_deactivate() override {
    stop();
    return {};
  }

  Status on_cleanup() override {
    state_.reset();
    scene_.reset();
    return {};
  }

  // ---- WebHandler (the server's I/O thread) --------------------------------

  std::optional<HttpReply> get(std::string_view path) override {
    if (path == "/state.json") return HttpReply{"application/json", state_->json()};
    if (path == "/") path = "/index.html";
    for (std::size_t i = 0; i < plr_monitor_web_pages_count; ++i)
      if (path.substr(1) == plr_monitor_web_pages[i].name)
        return HttpReply{content_type(path), std::string(plr_monitor_web_pages[i].bytes())};
    return std::nullopt;
  }

  void opened(std::uint64_t client, Protocol protocol) override {
    if (protocol == Protocol::kDashboard) {
      server_->send(client, std::make_shared<const std::string>(state_->json()), false);
      return;
    }
    for (auto& m : channels_.hello("plr " + ctx().name()))
      server_->send(client, std::make_shared<const std::string>(std::move(m)), false);
  }

  void received(std::uint64_t client, std::string_view text) override {
    auto r = channels_.handle(client, text);
    for (auto& reply : r.replies)
      server_->send(client, std::make_shared<const std::string>(std::move(reply)), false);
    for (const auto& topic : r.topics_wanted) {
      if (topic == kSceneTopic) scene_->resend();
      if (const auto* c = channels_.find(topic); c && c->type_id != 0)
        if (auto s = read_topic(topic, c->type_id); !s)
          log().warn("foxglove: {}", s.error().message);
    }
  }

  void closed(std::uint64_t client) override { channels_.forget(client); }

 private:
  struct Reader {
    MonitorWebNode* node;
    std::string topic;
    std::uint64_t type_id;
    std::uint64_t subscription = 0;
  };

  // Subscribes once to `topic` by its type id; every message goes to the
  // dashboard (if it is one of its types) and to subscribed Foxglove clients.
  Status read_topic(const std::string& topic, std::uint64_t type_id) {
    std::lock_guard lock(readers_m_);
    if (readers_.count(topic)) return {};
    auto reader = std::make_unique<Reader>(Reader{this, topic, type_id});
    const auto* api = ctx().api();
    const auto s = api->subscribe(api->ctx, topic.c_str(), type_id, &MonitorWebNode::on_message,
                                  reader.get(), &reader->subscription);
    if (s != PLR_OK) return make_error(s, "subscribe '" + topic + "' failed");
    readers_[topic] = std::move(reader);
    return {};
  }

  static void on_message(void* user, const plr_msg* msg) {
    auto& r = *static_cast<Reader*>(user);
    r.node->deliver(r, msg);
  }

  template <class T>
  bool show(const plr_msg_view& v) {
    if (v.type_id != MessageTraits<T>::type_id()) return false;
    if (!verify<T>(v.data, v.size)) return true;
    const auto& m = *flatbuffers::GetRoot<T>(v.data);
    state_->update(m);
    if constexpr (std::is_same_v<T, msg::WorldState>) scene_->update(m, v.stamp_ns);
    return true;
  }

  void deliver(const Reader& r, const plr_msg* msg) {
    const auto* api = ctx().api();
    const auto v = api->msg_view(msg);
    const bool dashboard = show<msg::WorldState>(v) || show<msg::ExecutorState>(v) ||
                           show<msg::Progress>(v) || show<msg::KernelTelemetry>(v);
    if (dashboard && v.type_id == MessageTraits<msg::KernelTelemetry>::type_id() &&
        verify<msg::KernelTelemetry>(v.data, v.size))
      advertise_new_topics(*flatbuffers::GetRoot<msg::KernelTelemetry>(v.data));
    const auto subscribers = channels_.subscribers(r.topic);
    if (subscribers.empty() || !server_) return;
    const std::string_view payload(reinterpret_cast<const char*>(v.data), v.size);
    for (const auto& [client, sub] : subscribers)
      server_->send(client,
                    std::make_shared<const std::string>(FoxgloveChannels::message_frame(
                        sub, static_cast<std::uint64_t>(v.stamp_ns), payload)),
                    true);
  }

  // Topics the kernels report that Foxglove clients were not told of yet.
  void advertise_new_topics(const msg::KernelTelemetry& t) {
    if (!t.topics() || !server_) return;
    std::vector<Channel> fresh;
    for (const auto* s : *t.topics())
      if (s->name() && s->type_id() != 0)
        if (const auto* c = channels_.add(s->name()->str(), s->type_id())) fresh.push_back(*c);
    if (!fresh.empty())
      server_->broadcast(Protocol::kFoxglove,
                         std::make_shared<const std::string>(FoxgloveChannels::advertise(fresh)),
                         false);
  }

  // Sends the dashboard's state to its pages at update_hz, when it changed,
  // and the scene to its Foxglove subscribers at scene_hz, when the world did.
  void push_loop() {
    using Clock = std::chrono::steady_clock;
    const auto page_period = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(1.0 / update_hz_));
    const auto scene_period =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / scene_hz_));
    auto next_page = Clock::now() + page_period;
    auto next_scene = Clock::now() + scene_period;
    std::unique_lock lock(stop_m_);
    while (
        !stop_cv_.wait_until(lock, std::min(next_page, next_scene), [this] { return stopping_; })) {
      const auto now = Clock::now();
      // A late tick is not made up for: the next one is a full period on.
      const auto due = [now](Clock::time_point& next, Clock::duration period) {
        if (now < next) return false;
        next += period;
        if (next <= now) next = now + period;
        return true;
      };
      if (due(next_scene, scene_period)) push_scene();
      if (due(next_page, page_period)) push_page();
    }
  }

  void push_scene() {
    const auto subscribers = channels_.subscribers(kSceneTopic);
    if (subscribers.empty()) return;
    const auto scene = scene_->take();
    if (!scene) return;
    for (const auto& [client, sub] : subscribers)
      server_->send(client,
                    std::make_shared<const std::string>(FoxgloveChannels::message_frame(
                        sub, static_cast<std::uint64_t>(scene->stamp_ns), scene->json)),
                    true);
  }

  void push_page() {
    const auto s = server_->stats();
    state_->set_server({{"clients", s.clients},
                        {"sent", s.sent_messages},
                        {"dropped", s.dropped_messages},
                        {"dropped_bytes", s.dropped_bytes},
                        {"refused", s.refused_requests}});
    const auto version = state_->version();
    if (version == sent_version_) return;
    sent_version_ = version;
    server_->broadcast(Protocol::kDashboard, std::make_shared<const std::string>(state_->json()),
                       false);
  }

  void stop() {
    {
      std::lock_guard lock(stop_m_);
      stopping_ = true;
    }
    stop_cv_.notify_all();
    if (pusher_.joinable()) pusher_.join();
    {
      std::lock_guard lock(readers_m_);
      const auto* api = ctx().api();
      for (auto& [topic, r] : readers_) (void)api->unsubscribe(api->ctx, r->subscription);
    }
    // The I/O thread calls the handlers, which use server_: it ends first.
    if (server_) server_->stop();
    server_.reset();
    std::lock_guard lock(readers_m_);
    readers_.clear();
  }

  WebServerOptions options_;
  double update_hz_ = 10.0;
  double scene_hz_ = 10.0;
  std::uint64_t sent_version_ = 0;  // of the dashboard's state
  std::unique_ptr<DashboardState> state_;
  std::unique_ptr<FoxgloveScene> scene_;
  FoxgloveChannels channels_;
  std::mutex readers_m_;
  std::map<std::string, std::unique_ptr<Reader>> readers_;
  std::unique_ptr<WebServer> server_;
  std::thread pusher_;
  std::mutex stop_m_;
  std::condition_variable stop_cv_;
  bool stopping_ = false;
};

}  // namespace
}  // namespace plr::monitor_web

PLR_PLUGIN(plr::monitor_web::MonitorWebNode, "monitor_web", "1.0.0", PLR_KIND_MONITOR,
           "Live web dashboard and Foxglove WebSocket server (read-only)")
// It only listens on the bus, and serves over its own HTTP/WebSocket port.
PLR_INTERFACE()
