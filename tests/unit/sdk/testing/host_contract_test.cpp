// The host contract (plr/testing/host_contract.hpp) against the fake kernel,
// which must keep the promises PLR's kernel keeps (kernel_host_contract_test).
#include <plr/testing/fake_kernel.hpp>
#include <plr/testing/host_contract.hpp>

#include <gtest/gtest.h>

#include <map>

namespace plr::testing {
namespace {

class FakeHost final : public ContractHost {
 public:
  Status add(const plr_plugin_descriptor& plugin, const std::string& name,
             const std::string& params_json,
             const std::map<std::string, std::string>& remaps) override {
    NodeOptions options;
    options.name = name;
    options.params_json = params_json;
    options.remaps = remaps;
    auto node = k_.create(PluginRef{&plugin, "(in this process)"}, options);
    if (!node) return node.error();
    nodes_.insert_or_assign(name, *node);
    return {};
  }
  Status configure(const std::string& node) override { return nodes_.at(node).configure(); }
  Status activate(const std::string& node) override { return nodes_.at(node).activate(); }
  Status deactivate(const std::string& node) override { return nodes_.at(node).deactivate(); }
  Status cleanup(const std::string& node) override { return nodes_.at(node).cleanup(); }
  void destroy(const std::string& node) override { nodes_.at(node).destroy(); }

  const plr_host_api* test_api() override { return k_.test_api(); }
  void run(std::chrono::nanoseconds time) override {
    k_.advance(time);
    k_.spin();
  }
  std::uint64_t rejected() const override { return k_.rejections().size(); }
  std::int64_t live_messages() const override { return k_.live_messages(); }

 private:
  FakeKernel k_{KernelOptions{.start_ns = 0, .echo_level = PLR_LOG_ERROR}};
  std::map<std::string, NodeHandle> nodes_;
};

const bool registered = [] {
  register_host_contract_tests("FakeKernelHostContract",
                               [] { return std::make_unique<FakeHost>(); });
  return true;
}();

}  // namespace
}  // namespace plr::testing
