// The host contract (plr/testing/host_contract.hpp) against PLR's kernel: its
// bus, and node instances behind the C host table, each on its own thread.
#include "bus.hpp"
#include "message.hpp"
#include "node_instance.hpp"
#include "plugin_loader.hpp"

#include <plr/testing/host_contract.hpp>

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <thread>

namespace plr::kernel {
namespace {

// The test's own endpoint: a node that does nothing, whose host table the
// suite uses as a node would.
const plr_plugin_descriptor& test_plugin() {
  static int object = 0;
  static const plr_plugin_descriptor descriptor = {
      PLR_ABI_MAJOR,
      PLR_ABI_MINOR,
      "contract_test",
      "1.0.0",
      "the test side of the host contract",
      PLR_KIND_OTHER,
      {[](const plr_host_api*) -> void* { return &object; }, [](void*) {},
       [](void*, char*, std::size_t) { return PLR_OK; },
       [](void*, char*, std::size_t) { return PLR_OK; },
       [](void*, char*, std::size_t) { return PLR_OK; },
       [](void*, char*, std::size_t) { return PLR_OK; }}};
  return descriptor;
}

class KernelHost final : public testing::ContractHost {
 public:
  KernelHost() {
    // What Kernel::start does for every node: create, configure, activate, live.
    EXPECT_TRUE(add(test_plugin(), "test", "{}", {}));
    EXPECT_TRUE(configure("test"));
    EXPECT_TRUE(activate("test"));
  }
  ~KernelHost() override {
    for (auto it = order_.rbegin(); it != order_.rend(); ++it) nodes_.erase(*it);
  }

  Status add(const plr_plugin_descriptor& plugin, const std::string& name,
             const std::string& params_json,
             const std::map<std::string, std::string>& remaps) override {
    NodeConfig config;
    config.name = name;
    config.plugin = plugin.name;
    config.params = nlohmann::json::parse(params_json);
    config.remap = remaps;
    auto library = std::make_shared<PluginLibrary>(nullptr, &plugin, "(in this process)");
    auto node = std::make_unique<NodeInstance>(bus_, config, library, clock_);
    if (auto s = node->create(); !s) return s;
    nodes_[name] = std::move(node);
    order_.push_back(name);
    return {};
  }
  Status configure(const std::string& node) override { return nodes_.at(node)->configure(); }
  Status activate(const std::string& node) override {
    auto& n = *nodes_.at(node);
    if (auto s = n.activate(); !s) return s;
    bus_.set_live(&n, true);
    return {};
  }
  Status deactivate(const std::string& node) override { return nodes_.at(node)->deactivate(); }
  Status cleanup(const std::string& node) override { return nodes_.at(node)->cleanup(); }
  void destroy(const std::string& node) override {
    nodes_.erase(node);
    std::erase(order_, node);
  }

  const plr_host_api* test_api() override { return nodes_.at("test")->host_api(); }
  void run(std::chrono::nanoseconds time) override {
    if (time.count() > 0) std::this_thread::sleep_for(time);
    // What one node's callback queues on another's thread is done by the next pass.
    for (int pass = 0; pass < 2; ++pass)
      for (auto& [name, node] : nodes_) node->node_thread().drain();
  }
  std::uint64_t rejected() const override { return bus_.invalid_total(); }
  std::int64_t live_messages() const override { return kernel::live_messages(); }

 private:
  PipelineClock clock_;
  Bus bus_;
  std::map<std::string, std::unique_ptr<NodeInstance>> nodes_;
  std::vector<std::string> order_;  // destroyed in reverse, the test's endpoint last
};

const bool registered = [] {
  testing::register_host_contract_tests("KernelHostContract",
                                        [] { return std::make_unique<KernelHost>(); });
  return true;
}();

}  // namespace
}  // namespace plr::kernel
