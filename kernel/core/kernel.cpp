#include "kernel.hpp"

#include "dds_bridge.hpp"
#include "heap_policy.hpp"
#include "shm_bridge.hpp"
#include "supervisor.hpp"
#include "telemetry_publisher.hpp"

#include <plr/message.hpp>
#include <plr/messages.hpp>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <thread>

namespace plr::kernel {

// The kernel's own endpoint on the bus, for the clock subscription.
class Kernel::Internal final : public Endpoint {
 public:
  Internal() : node_thread_("kernel") {}
  NodeThread& node_thread() override { return node_thread_; }
  const std::string& endpoint_name() const override { return name_; }

 private:
  std::string name_ = "kernel";
  NodeThread node_thread_;
};

std::vector<std::string> plugin_search_paths(const PipelineConfig& config) {
  auto paths = config.plugin_paths;
  paths.push_back(default_plugin_path());
  return paths;
}

Kernel::Kernel(PipelineConfig config, std::string host, std::string run_id)
    : config_(std::move(config)),
      host_(std::move(host)),
      run_id_(std::move(run_id)),
      loader_(plugin_search_paths(config_)),
      clock_(config_.clock == "sim"),
      bus_([this](const std::string& topic) { return config_.topic(topic); }),
      internal_(std::make_unique<Internal>()) {
  bound_heap_retention();
  for (const auto& n : config_.nodes) {
    if (n.host != host_) continue;
    auto s = std::make_unique<Slot>();
    s->config = n;
    slots_.push_back(std::move(s));
  }
  bus_.set_live(internal_.get(), true);
}

Kernel::~Kernel() {
  stop();
  // Taken out under the lock, destroyed outside it: the DDS bridge joins its
  // heartbeat thread, which may be waiting for the lock in telemetry_json().
  std::unique_ptr<DdsBridge> dds;
  std::unique_ptr<ShmBridge> bridge;
  {
    std::lock_guard lock(transports_mutex_);
    dds = std::move(dds_);
    bridge = std::move(bridge_);
  }
  if (dds) bus_.detach(dds.get());
  dds.reset();
  if (bridge) bus_.detach(bridge.get());
  bridge.reset();
  bus_.remove_endpoint(internal_.get());
  internal_->node_thread().drain();
}

Expected<std::unique_ptr<NodeInstance>> Kernel::configured(const NodeConfig& config) {
  auto lib = loader_.load(config.plugin);
  if (!lib)
    return make_error(lib.error().code, fmt::format("{}: node '{}': {}", config.where.str(),
                                                    config.name, lib.error().message));
  auto inst = std::make_unique<NodeInstance>(bus_, config, *lib, clock_);
  for (auto step : {&NodeInstance::create, &NodeInstance::configure}) {
    if (auto s = (inst.get()->*step)(); !s) return s.error();
  }
  return inst;
}

Expected<std::unique_ptr<NodeInstance>> Kernel::bring_up(const NodeConfig& config) {
  auto inst = configured(config);
  if (!inst) return inst;
  if (auto s = (*inst)->activate(); !s) return s.error();
  return inst;
}

namespace {

// Nodes of these kinds hold what the run has done so far (the world acted
// on, the search, the robot's motion); the plug-in ABI has no way to hand it
// to another plug-in, and starting afresh would lie about the run.
bool holds_run_state(plr_kind kind) {
  return kind == PLR_KIND_EXECUTOR || kind == PLR_KIND_GENERATOR || kind == PLR_KIND_SIMULATOR ||
         kind == PLR_KIND_DRIVER;
}

}  // namespace

Status Kernel::start() {
  const auto hosts = hosts_with_nodes(config_);
  if (!run_id_.empty() && hosts.size() > 1 && !bridge_) {
    auto bridge = std::make_unique<ShmBridge>(bus_, config_, host_, hosts, run_id_);
    bus_.attach(bridge.get());
    std::lock_guard lock(transports_mutex_);
    bridge_ = std::move(bridge);
  }
  // Other machines: after shared memory, so calls try this machine's hosts first.
  if (config_.dds.enabled && host_ == "main" && !dds_) {
    auto dds = DdsBridge::create(
        bus_, config_, make_kernel_id(config_.pipeline), [this] { return telemetry_json(); },
        [this](const nlohmann::json& c) -> Status {
          const auto text = [&](const char* key) {
            return c.contains(key) && c[key].is_string() ? c[key].get<std::string>() : "";
          };
          if (text("cmd") == "swap") return swap(text("node"), text("plugin"));
          if (text("cmd") == "pause") return pause(text("node"));
          if (text("cmd") == "resume") return resume(text("node"));
          return make_error(PLR_ERR_INVALID, "unknown remote command '" + text("cmd") + "'");
        });
    if (!dds) return dds.error();
    bus_.attach(dds->get());
    // Its heartbeat thread runs already, and reads dds_ in telemetry_json().
    std::lock_guard lock(transports_mutex_);
    dds_ = std::move(*dds);
  }
  if (config_.clock == "sim")
    if (auto s = follow_sim_clock(); !s) return s;
  if (!telemetry_)
    telemetry_ = std::make_unique<TelemetryPublisher>(
        bus_, internal_.get(),
        [this](flatbuffers::FlatBufferBuilder& fbb) { telemetry_message(fbb); });
  for (auto& s : slots_) {
    auto inst = bring_up(s->config);
    if (!inst) {
      stop();
      return inst.error();
    }
    // Live only once active, so nothing reaches a half-started node.
    bus_.set_live(inst->get(), true);
    spdlog::info("node '{}' active ({} {})", s->config.name, (*inst)->library().name(),
                 (*inst)->library().descriptor().version);
    // The control server is already up: a swap or status may come in now.
    std::scoped_lock lock(s->swap_mutex, s->view_mutex);
    s->instance = std::move(*inst);
  }
  started_ = true;
  return {};
}

void Kernel::stop() {
  // Its thread reads the nodes and the bus: gone before the nodes go.
  telemetry_.reset();
  for (auto it = slots_.rbegin(); it != slots_.rend(); ++it) {
    auto& s = **it;
    std::lock_guard lock(s.swap_mutex);
    if (!s.instance) continue;
    if (auto r = s.instance->deactivate(); !r) spdlog::warn("{}", r.error().message);
  }
  for (auto it = slots_.rbegin(); it != slots_.rend(); ++it) {
    auto& s = **it;
    std::lock_guard lock(s.swap_mutex);
    if (!s.instance) continue;
    if (auto r = s.instance->cleanup(); !r) spdlog::warn("{}", r.error().message);
    std::unique_ptr<NodeInstance> gone;
    {
      std::lock_guard view(s.view_mutex);
      gone = std::move(s.instance);
    }
  }
  started_ = false;
}

Status Kernel::sync_transports() {
  if (bridge_) bridge_->node_thread().drain();
  if (dds_) dds_->node_thread().drain();
  if (bridge_)
    if (auto e = bridge_->first_error(); !e.empty())
      return make_error(PLR_ERR_UNAVAILABLE, fmt::format("host '{}': {}", host_, e));
  return {};
}

Kernel::Slot* Kernel::slot(const std::string& name) {
  for (auto& s : slots_)
    if (s->config.name == name) return s.get();
  return nullptr;
}

Status Kernel::swap(const std::string& node, const std::string& plugin) {
  Slot* s = slot(node);
  if (s == nullptr)
    return make_error(PLR_ERR_INVALID, fmt::format("swap: no node '{}' in this pipeline", node));
  std::lock_guard lock(s->swap_mutex);
  if (!s->instance)
    return make_error(PLR_ERR_STATE, fmt::format("swap: node '{}' is not running", node));

  const auto refused = [&](plr_status code, const std::string& why) {
    return make_error(code, fmt::format("swap of '{}' to '{}' refused, '{}' keeps running: {}",
                                        node, plugin, s->config.plugin, why));
  };
  const auto& running = s->instance->library().descriptor();
  if (holds_run_state(running.kind))
    return refused(PLR_ERR_STATE,
                   fmt::format("a {} node holds the run's state, which plug-ins cannot hand over "
                               "(stop the run and start it with the new plug-in)",
                               plr_kind_name(running.kind)));
  const auto failed = [&](const Error& e) {
    return make_error(e.code, fmt::format("swap of '{}' to '{}' failed, '{}' keeps running: {}",
                                          node, plugin, s->config.plugin, e.message));
  };
  // The kind first, from the descriptor: nothing of a wrong plug-in runs.
  auto library = loader_.load(plugin);
  if (!library) return failed(library.error());
  const auto kind = (*library)->descriptor().kind;
  if (kind != running.kind)
    return refused(PLR_ERR_INVALID, fmt::format("'{}' is a {} plug-in, the node's is a {}", plugin,
                                                plr_kind_name(kind), plr_kind_name(running.kind)));
  NodeConfig next = s->config;
  next.plugin = plugin;
  auto fresh = configured(next);
  if (!fresh) return failed(fresh.error());
  // Callers of a service the new plug-in lacks would wait for it forever.
  const auto offered = bus_.services_of(s->instance.get());
  const auto offers = bus_.services_of(fresh->get());
  std::vector<std::string> missing;
  for (const auto& name : offered)
    if (std::find(offers.begin(), offers.end(), name) == offers.end()) missing.push_back(name);
  std::string problem;
  if (!missing.empty())
    problem = fmt::format("'{}' would not offer {} (the node's callers need {})", plugin,
                          fmt::join(missing, ", "), missing.size() == 1 ? "it" : "them");
  if (!problem.empty()) {
    if (auto r = (*fresh)->cleanup(); !r) spdlog::warn("swap: {}", r.error().message);
    return refused(PLR_ERR_INVALID, problem);
  }
  if (auto r = (*fresh)->activate(); !r) return failed(r.error());

  std::unique_ptr<NodeInstance> old;
  {
    std::lock_guard view(s->view_mutex);
    old = std::move(s->instance);
    s->instance = std::move(*fresh);
    s->config.plugin = plugin;  // only the plug-in changes; slot() reads the name unlocked
  }
  bus_.swap_live(old.get(), s->instance.get());
  // The old instance answers what it already accepted before it goes.
  old->node_thread().drain();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (bus_.pending_for(old.get()) > 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  if (auto r = old->deactivate(); !r) spdlog::warn("swap: {}", r.error().message);
  old.reset();
  // Its thread's arena may keep free pages between live blocks: back to the system.
  release_free_heap();
  spdlog::info("node '{}' swapped to {} {}", node, plugin,
               s->instance->library().descriptor().version);
  return {};
}

Status Kernel::pause(const std::string& node) {
  Slot* s = slot(node);
  if (s == nullptr)
    return make_error(PLR_ERR_INVALID, fmt::format("pause: no node '{}' in this pipeline", node));
  std::lock_guard lock(s->swap_mutex);
  if (!s->instance || s->instance->state() != InstanceState::Active)
    return make_error(PLR_ERR_STATE, fmt::format("pause: node '{}' is not running", node));
  bus_.set_live(s->instance.get(), false);
  if (auto r = s->instance->deactivate(); !r) return r;
  spdlog::info("node '{}' paused", node);
  return {};
}

Status Kernel::resume(const std::string& node) {
  Slot* s = slot(node);
  if (s == nullptr)
    return make_error(PLR_ERR_INVALID, fmt::format("resume: no node '{}' in this pipeline", node));
  std::lock_guard lock(s->swap_mutex);
  if (!s->instance || s->instance->state() != InstanceState::Configured)
    return make_error(PLR_ERR_STATE, fmt::format("resume: node '{}' is not paused", node));
  if (auto r = s->instance->activate(); !r) return r;
  bus_.set_live(s->instance.get(), true);
  spdlog::info("node '{}' resumed", node);
  return {};
}

template <class T>
Status Kernel::listen(const std::string& topic, std::function<void(const T&)> fn) {
  auto handler = std::make_unique<std::function<void(const plr_msg*)>>(
      [fn = std::move(fn), this](const plr_msg* m) {
        const auto v = msg_view(m);
        if (!verify<T>(v.data, v.size)) {
          bus_.count_invalid(m);
          return;
        }
        fn(*flatbuffers::GetRoot<T>(v.data));
      });
  auto sub = bus_.subscribe(
      internal_.get(), topic, MessageTraits<T>::type_id(),
      [](void* user, const plr_msg* m) {
        (*static_cast<std::function<void(const plr_msg*)>*>(user))(m);
      },
      handler.get());
  if (!sub) return sub.error();
  listeners_.push_back(std::move(handler));
  return {};
}

Status Kernel::follow_sim_clock() {
  return listen<msg::Clock>("clock",
                            [this](const msg::Clock& c) { clock_.set_sim_ns(c.time_ns()); });
}

Status Kernel::on_pipeline_done(std::function<void(bool, std::string)> fn) {
  return listen<msg::PipelineDone>("pipeline/done",
                                   [fn = std::move(fn)](const msg::PipelineDone& d) {
                                     fn(d.ok(), d.reason() ? d.reason()->str() : "");
                                   });
}

Status Kernel::on_node_report(std::function<void(std::string, std::string)> fn) {
  return listen<msg::NodeReport>("pipeline/report", [fn = std::move(fn)](const msg::NodeReport& r) {
    fn(r.node() ? r.node()->str() : "", r.figures() ? r.figures()->str() : "");
  });
}

void Kernel::drain_listeners() {
  internal_->node_thread().drain();
}

std::vector<NodeStatus> Kernel::nodes() const {
  std::vector<NodeStatus> out;
  for (const auto& s : slots_) {
    std::lock_guard view(s->view_mutex);
    NodeStatus n;
    n.name = s->config.name;
    n.plugin = s->config.plugin;
    n.host = s->config.host;
    n.state = "unloaded";
    if (s->instance) {
      const auto& d = s->instance->library().descriptor();
      n.version = d.version;
      n.kind = plr_kind_name(d.kind);
      n.state = to_string(s->instance->state());
    }
    out.push_back(std::move(n));
  }
  return out;
}

std::string Kernel::telemetry_json() {
  nlohmann::json j;
  j["pipeline"] = config_.pipeline;
  j["host"] = host_;
  j["nodes"] = nlohmann::json::array();
  for (const auto& n : nodes())
    j["nodes"].push_back({{"name", n.name},
                          {"plugin", n.plugin},
                          {"version", n.version},
                          {"kind", n.kind},
                          {"state", n.state},
                          {"host", n.host}});
  j["topics"] = nlohmann::json::array();
  for (const auto& t : bus_.topic_stats())
    j["topics"].push_back({{"name", t.name},
                           {"messages", t.messages},
                           {"drops", t.drops},
                           {"invalid", t.invalid},
                           {"rate_hz", t.rate_hz},
                           {"latency_mean_us", t.latency_mean_us},
                           {"latency_max_us", t.latency_max_us},
                           {"subscribers", t.subscribers}});
  j["services"] = nlohmann::json::array();
  for (const auto& s : bus_.services())
    j["services"].push_back({{"name", s.name}, {"providers", s.providers}});
  j["invalid_messages"] = bus_.invalid_total();
  std::lock_guard lock(transports_mutex_);
  if (bridge_) j["shm"] = bridge_->stats();
  if (dds_) j["dds"] = dds_->stats();
  return j.dump();
}

void Kernel::telemetry_message(flatbuffers::FlatBufferBuilder& fbb) {
  std::vector<flatbuffers::Offset<msg::NodeStatus>> nodes;
  for (const auto& n : this->nodes())
    nodes.push_back(msg::CreateNodeStatusDirect(fbb, n.name.c_str(), n.plugin.c_str(),
                                                n.version.c_str(), n.kind.c_str(), n.state.c_str(),
                                                n.host.c_str()));
  std::vector<flatbuffers::Offset<msg::TopicStats>> topics;
  for (const auto& t : bus_.topic_stats())
    topics.push_back(msg::CreateTopicStatsDirect(fbb, t.name.c_str(), nullptr, t.messages, t.drops,
                                                 t.invalid, t.rate_hz, t.latency_mean_us,
                                                 t.latency_max_us, t.type_id));
  const auto id = config_.pipeline + "@" + host_;
  fbb.Finish(msg::CreateKernelTelemetryDirect(fbb, id.c_str(), clock_.now_ns(), &nodes, &topics));
}

}  // namespace plr::kernel
