// A kernel reduced to its bus and DDS bridge, with nodes that are only a
// name and a thread, and an echo service: one side of a DDS link for
// bench_remote and remote_quick_service_test (the other side runs in a
// second process).
#pragma once

#include "bus.hpp"
#include "dds_bridge.hpp"
#include "test_endpoint.hpp"

#include <plr/message.hpp>

#include <memory>
#include <string>
#include <vector>

namespace plr::kernel::remote_test {

constexpr std::uint64_t kEchoType = plr::fnv1a("plr.test.Echo");

class BareKernel {
 public:
  // Kernel `pipeline` on DDS `domain`: a provider exports the services
  // matching `pattern`, a caller imports them.
  BareKernel(int domain, std::string pipeline, bool provider, std::string pattern)
      : config_(make_config(domain, std::move(pipeline), provider, std::move(pattern))),
        bus_([this](const std::string& t) { return config_.topic(t); }) {}
  ~BareKernel() {
    for (auto& n : nodes_) bus_.remove_endpoint(n.get());
    if (bridge_) bus_.detach(bridge_.get());
  }
  BareKernel(const BareKernel&) = delete;
  BareKernel& operator=(const BareKernel&) = delete;

  // Before open(): how `topic` goes out (e.g. reliable).
  void set_topic(TopicSettings topic) { config_.topics.push_back(std::move(topic)); }
  // Joins the DDS domain.
  Status open() {
    auto b = DdsBridge::create(
        bus_, config_, make_kernel_id(config_.pipeline), [] { return std::string("{}"); },
        [](const nlohmann::json&) -> Status { return make_error(PLR_ERR_STATE, "bare kernel"); });
    if (!b) return b.error();
    bridge_ = std::move(*b);
    bus_.attach(bridge_.get());
    return {};
  }
  Bus& bus() { return bus_; }
  nlohmann::json bridge_stats() const { return bridge_->stats(); }
  testing::TestEndpoint& add_node(std::string name) {
    nodes_.push_back(std::make_unique<testing::TestEndpoint>(std::move(name)));
    bus_.set_live(nodes_.back().get(), true);
    return *nodes_.back();
  }
  // `node` answers `service` with each request's own bytes, as ddsperf's
  // pong writes back the sample it took: no copy of its own.
  Status provide_echo(testing::TestEndpoint& node, const std::string& service,
                      std::uint32_t flags) {
    return bus_.provide(
        &node, service, kEchoType, kEchoType,
        [](void* user, const plr_msg* req, std::uint64_t token) {
          msg_retain(req);
          (void)static_cast<Bus*>(user)->respond(token, PLR_OK, const_cast<plr_msg*>(req), "");
        },
        &bus_, flags);
  }

 private:
  static PipelineConfig make_config(int domain, std::string pipeline, bool provider,
                                    std::string pattern) {
    PipelineConfig c;
    c.pipeline = std::move(pipeline);
    c.dds.enabled = true;
    c.dds.domain = domain;
    (provider ? c.dds.export_patterns : c.dds.import_patterns) = {std::move(pattern)};
    return c;
  }

  PipelineConfig config_;
  Bus bus_;
  std::unique_ptr<DdsBridge> bridge_;
  std::vector<std::unique_ptr<testing::TestEndpoint>> nodes_;
};

}  // namespace plr::kernel::remote_test
