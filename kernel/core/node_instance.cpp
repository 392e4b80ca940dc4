#include "node_instance.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>

namespace plr::kernel {

namespace {

NodeInstance* self_of(void* ctx) {
  return static_cast<NodeInstance*>(ctx);
}

plr_status code_of(const Status& s) {
  return s ? PLR_OK : s.error().code;
}

// Plug-in supplied ranges are checked before the kernel trusts them.
bool range_ok(const plr_msg* msg, std::size_t offset, std::size_t size) {
  return msg != nullptr && offset <= msg->capacity && size <= msg->capacity - offset;
}

}  // namespace

std::int64_t PipelineClock::now_ns() const {
  return simulated_ ? sim_ns_.load(std::memory_order_relaxed) : wall_now_ns();
}

const char* to_string(InstanceState s) {
  switch (s) {
    case InstanceState::Unconfigured:
      return "unconfigured";
    case InstanceState::Configured:
      return "configured";
    case InstanceState::Active:
      return "active";
  }
  return "unknown";
}

NodeInstance::NodeInstance(Bus& bus, NodeConfig config, std::shared_ptr<PluginLibrary> library,
                           const PipelineClock& clock)
    : bus_(bus),
      config_(std::move(config)),
      library_(std::move(library)),
      clock_(clock),
      params_json_(config_.params.dump()),
      api_(host_table(this)),
      node_thread_(config_.name) {}

NodeInstance::~NodeInstance() {
  if (node_ == nullptr) return;
  (void)deactivate();
  (void)cleanup();
  bus_.remove_endpoint(this);
  node_thread_.drain();
  node_thread_.run_sync([&] { library_->descriptor().node.destroy(node_); });
  node_ = nullptr;
}

Status NodeInstance::create() {
  node_thread_.run_sync([&] { node_ = library_->descriptor().node.create(&api_); });
  if (node_ == nullptr)
    return make_error(PLR_ERR_INTERNAL, fmt::format("node '{}': plug-in '{}' failed to create it",
                                                    config_.name, library_->name()));
  return {};
}

Status NodeInstance::step(const char* what, plr_status (*hook)(void*, char*, std::size_t),
                          InstanceState from, InstanceState to) {
  if (state_ != from)
    return make_error(PLR_ERR_STATE,
                      fmt::format("node '{}': {} needs state {}, it is {}", config_.name, what,
                                  to_string(from), to_string(state_.load())));
  char err[512] = {0};
  plr_status status = PLR_OK;
  node_thread_.run_sync([&] { status = hook(node_, err, sizeof err); });
  if (status != PLR_OK)
    return make_error(
        status, fmt::format("node '{}' ({}): {} failed: {}", config_.name, library_->name(), what,
                            err[0] ? err : "no reason given"));
  state_ = to;
  return {};
}

Status NodeInstance::configure() {
  auto s = step("configure", library_->descriptor().node.configure, InstanceState::Unconfigured,
                InstanceState::Configured);
  // A failed configure may have registered some things: forget them, so a retry starts clean.
  if (!s && s.error().code != PLR_ERR_STATE) bus_.remove_endpoint(this);
  return s;
}
Status NodeInstance::activate() {
  return step("activate", library_->descriptor().node.activate, InstanceState::Configured,
              InstanceState::Active);
}
Status NodeInstance::deactivate() {
  if (state_ != InstanceState::Active) return {};
  live = false;
  return step("deactivate", library_->descriptor().node.deactivate, InstanceState::Active,
              InstanceState::Configured);
}
Status NodeInstance::cleanup() {
  if (state_ == InstanceState::Unconfigured) return {};
  auto s = step("cleanup", library_->descriptor().node.cleanup, InstanceState::Configured,
                InstanceState::Unconfigured);
  // What configure registered goes with it, so the node can be configured again.
  if (s) bus_.remove_endpoint(this);
  return s;
}

std::string NodeInstance::resolve(const char* name) const {
  auto it = config_.remap.find(name);
  return it == config_.remap.end() ? std::string(name) : it->second;
}

plr_host_api NodeInstance::host_table(NodeInstance* self) {
  plr_host_api api{};
  api.abi_major = PLR_ABI_MAJOR;
  api.abi_minor = PLR_ABI_MINOR;
  api.ctx = self;
  api.msg_alloc = [](void*, std::size_t capacity, std::uint8_t** data) {
    return kernel::msg_alloc(capacity, data);
  };
  api.msg_retain = &kernel::msg_retain;
  api.msg_release = &kernel::msg_release;
  api.msg_view = &kernel::msg_view;
  api.reject = &NodeInstance::reject;
  api.advertise = &NodeInstance::advertise;
  api.loan = &NodeInstance::loan;
  api.publish = &NodeInstance::publish;
  api.subscribe = &NodeInstance::subscribe;
  api.unsubscribe = &NodeInstance::unsubscribe;
  api.provide = &NodeInstance::provide;
  api.respond = &NodeInstance::respond;
  api.call = &NodeInstance::call;
  api.cancel = &NodeInstance::cancel;
  api.params_json = &NodeInstance::params_json;
  api.node_name = &NodeInstance::node_name;
  api.log = &NodeInstance::log;
  api.now_ns = &NodeInstance::now_ns;
  api.provide_flags = &NodeInstance::provide_flags;
  return api;
}

plr_status NodeInstance::advertise(void* ctx, const char* topic, std::uint64_t type_id,
                                   std::uint32_t version, std::uint64_t* publisher) {
  auto* self = self_of(ctx);
  auto r = self->bus_.advertise(self, self->resolve(topic), type_id, version);
  if (!r) {
    spdlog::error("{}: {}", self->config_.name, r.error().message);
    return r.error().code;
  }
  *publisher = *r;
  return PLR_OK;
}

plr_msg* NodeInstance::loan(void* ctx, std::uint64_t publisher, std::size_t capacity,
                            std::uint8_t** data) {
  return self_of(ctx)->bus_.loan(publisher, capacity, data);
}

plr_status NodeInstance::publish(void* ctx, std::uint64_t publisher, plr_msg* msg,
                                 std::size_t offset, std::size_t size) {
  if (!range_ok(msg, offset, size)) {
    if (msg) msg_release(msg);
    return PLR_ERR_INVALID;
  }
  msg->offset = offset;
  msg->size = size;
  return code_of(self_of(ctx)->bus_.publish(publisher, msg));
}

plr_status NodeInstance::subscribe(void* ctx, const char* topic, std::uint64_t type_id,
                                   plr_subscription_fn fn, void* user, std::uint64_t* id) {
  auto* self = self_of(ctx);
  auto r = self->bus_.subscribe(self, self->resolve(topic), type_id, fn, user);
  if (!r) {
    spdlog::error("{}: {}", self->config_.name, r.error().message);
    return r.error().code;
  }
  *id = *r;
  return PLR_OK;
}

plr_status NodeInstance::unsubscribe(void* ctx, std::uint64_t id) {
  return code_of(self_of(ctx)->bus_.unsubscribe(id));
}

plr_status NodeInstance::provide(void* ctx, const char* service, std::uint64_t request_type,
                                 std::uint64_t reply_type, std::uint32_t version, plr_service_fn fn,
                                 void* user) {
  return provide_flags(ctx, service, request_type, reply_type, version, fn, user, 0);
}

plr_status NodeInstance::provide_flags(void* ctx, const char* service, std::uint64_t request_type,
                                       std::uint64_t reply_type, std::uint32_t, plr_service_fn fn,
                                       void* user, std::uint32_t flags) {
  auto* self = self_of(ctx);
  auto s =
      self->bus_.provide(self, self->resolve(service), request_type, reply_type, fn, user, flags);
  if (!s) spdlog::error("{}: {}", self->config_.name, s.error().message);
  return code_of(s);
}

plr_status NodeInstance::respond(void* ctx, std::uint64_t token, plr_status status, plr_msg* reply,
                                 std::size_t offset, std::size_t size, const char* error) {
  if (reply != nullptr) {
    if (!range_ok(reply, offset, size)) {
      msg_release(reply);
      reply = nullptr;
      status = PLR_ERR_INTERNAL;
      error = "provider answered with an out-of-range buffer";
    } else {
      reply->offset = offset;
      reply->size = size;
    }
  }
  auto s = self_of(ctx)->bus_.respond(token, status, reply, error ? error : "");
  if (!s) spdlog::warn("{}: {}", self_of(ctx)->config_.name, s.error().message);
  return code_of(s);
}

plr_status NodeInstance::call(void* ctx, const char* service, std::uint64_t request_type,
                              std::uint32_t version, plr_msg* request, std::size_t offset,
                              std::size_t size, std::int64_t timeout_ns, plr_reply_fn fn,
                              void* user, std::uint64_t* id) {
  auto* self = self_of(ctx);
  if (!range_ok(request, offset, size)) {
    if (request) msg_release(request);
    return PLR_ERR_INVALID;
  }
  request->offset = offset;
  request->size = size;
  request->schema_version = version;
  auto s = self->bus_.call(self, self->resolve(service), request_type, request,
                           std::chrono::nanoseconds(timeout_ns), fn, user, id);
  if (!s) spdlog::debug("{}: {}", self->config_.name, s.error().message);
  return code_of(s);
}

plr_status NodeInstance::cancel(void* ctx, std::uint64_t id) {
  return code_of(self_of(ctx)->bus_.cancel(id));
}

void NodeInstance::reject(void* ctx, const plr_msg* msg, const char* reason) {
  auto* self = self_of(ctx);
  self->bus_.count_invalid(msg);
  spdlog::warn("{}: dropped a message: {}", self->config_.name, reason ? reason : "invalid");
}

const char* NodeInstance::params_json(void* ctx) {
  return self_of(ctx)->params_json_.c_str();
}
const char* NodeInstance::node_name(void* ctx) {
  return self_of(ctx)->config_.name.c_str();
}

void NodeInstance::log(void* ctx, plr_log_level level, const char* message) {
  const auto& name = self_of(ctx)->config_.name;
  switch (level) {
    case PLR_LOG_DEBUG:
      spdlog::debug("[{}] {}", name, message);
      break;
    case PLR_LOG_INFO:
      spdlog::info("[{}] {}", name, message);
      break;
    case PLR_LOG_WARN:
      spdlog::warn("[{}] {}", name, message);
      break;
    default:
      spdlog::error("[{}] {}", name, message);
      break;
  }
}

std::int64_t NodeInstance::now_ns(void* ctx) {
  return self_of(ctx)->clock_.now_ns();
}

}  // namespace plr::kernel
