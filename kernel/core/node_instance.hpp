// One plug-in instance behind a named node: the C host table the plug-in
// talks to, its node thread, and its life cycle as the kernel sees it.
#pragma once

#include "bus.hpp"
#include "node_thread.hpp"
#include "pipeline_config.hpp"
#include "plugin_loader.hpp"

#include <plr/plugin_abi.h>
#include <plr/expected.hpp>

#include <atomic>
#include <memory>
#include <string>

namespace plr::kernel {

// The pipeline's time source: wall clock, or the simulator's `clock` topic.
class PipelineClock {
 public:
  explicit PipelineClock(bool simulated = false) : simulated_(simulated) {}
  std::int64_t now_ns() const;
  void set_sim_ns(std::int64_t t) { sim_ns_.store(t, std::memory_order_relaxed); }
  bool simulated() const { return simulated_; }

 private:
  bool simulated_;
  std::atomic<std::int64_t> sim_ns_{0};
};

enum class InstanceState { Unconfigured, Configured, Active };
const char* to_string(InstanceState s);

class NodeInstance final : public Endpoint {
 public:
  NodeInstance(Bus& bus, NodeConfig config, std::shared_ptr<PluginLibrary> library,
               const PipelineClock& clock);
  ~NodeInstance() override;  // cleans up and destroys the plug-in's node

  Status create();
  Status configure();
  Status activate();
  Status deactivate();
  Status cleanup();

  NodeThread& node_thread() override { return node_thread_; }
  const std::string& endpoint_name() const override { return config_.name; }
  const NodeConfig& config() const { return config_; }
  const PluginLibrary& library() const { return *library_; }
  // The C table the plug-in's node was created with.
  const plr_host_api* host_api() const { return &api_; }
  InstanceState state() const { return state_.load(); }

 private:
  Status step(const char* what, plr_status (*hook)(void*, char*, std::size_t), InstanceState from,
              InstanceState to);
  std::string resolve(const char* name) const;
  static plr_host_api host_table(NodeInstance* self);

  // C trampolines of plr_host_api; ctx is the NodeInstance.
  static plr_status advertise(void*, const char*, std::uint64_t, std::uint32_t, std::uint64_t*);
  static plr_msg* loan(void*, std::uint64_t, std::size_t, std::uint8_t**);
  static plr_status publish(void*, std::uint64_t, plr_msg*, std::size_t, std::size_t);
  static plr_status subscribe(void*, const char*, std::uint64_t, plr_subscription_fn, void*,
                              std::uint64_t*);
  static plr_status unsubscribe(void*, std::uint64_t);
  static plr_status provide(void*, const char*, std::uint64_t, std::uint64_t, std::uint32_t,
                            plr_service_fn, void*);
  static plr_status provide_flags(void*, const char*, std::uint64_t, std::uint64_t, std::uint32_t,
                                  plr_service_fn, void*, std::uint32_t);
  static plr_status respond(void*, std::uint64_t, plr_status, plr_msg*, std::size_t, std::size_t,
                            const char*);
  static plr_status call(void*, const char*, std::uint64_t, std::uint32_t, plr_msg*, std::size_t,
                         std::size_t, std::int64_t, plr_reply_fn, void*, std::uint64_t*);
  static plr_status cancel(void*, std::uint64_t);
  static void reject(void*, const plr_msg*, const char*);
  static const char* params_json(void*);
  static const char* node_name(void*);
  static void log(void*, plr_log_level, const char*);
  static std::int64_t now_ns(void*);

  Bus& bus_;
  NodeConfig config_;
  std::shared_ptr<PluginLibrary> library_;
  const PipelineClock& clock_;
  std::string params_json_;
  plr_host_api api_;
  void* node_ = nullptr;
  std::atomic<InstanceState> state_{InstanceState::Unconfigured};
  NodeThread node_thread_;
};

}  // namespace plr::kernel
