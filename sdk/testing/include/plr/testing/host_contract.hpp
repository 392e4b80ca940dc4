// What the SDK promises a plug-in about the kernel that hosts it — life cycle
// order, parameters, publish/subscribe/provide/call semantics, remaps, quick
// services and errors — as one GoogleTest suite that any implementation of
// plr_host_api runs. The fake kernel (tests/unit/sdk/testing) and PLR's
// kernel (tests/unit/kernel/core) both run it, so they cannot drift apart.
//
// The suite's nodes are plr::Node subclasses in this library; the test side
// talks to them through the host's own plr_host_api (a plr::Context), just as
// a node does.
#pragma once

#include <plr/plugin_abi.h>
#include <plr/expected.hpp>

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>

namespace plr::testing {

// A kernel as the suite drives it. Node names are unique within a host.
class ContractHost {
 public:
  virtual ~ContractHost() = default;

  // Creates a node of `plugin` (a descriptor in this process) named `name`,
  // with these parameters (a JSON object) and remaps; it starts unconfigured.
  virtual Status add(const plr_plugin_descriptor& plugin, const std::string& name,
                     const std::string& params_json,
                     const std::map<std::string, std::string>& remaps) = 0;
  // Life-cycle steps as the kernel runs them (an active node receives topic
  // messages and requests; one deactivated or cleaned up does not).
  virtual Status configure(const std::string& node) = 0;
  virtual Status activate(const std::string& node) = 0;
  virtual Status deactivate(const std::string& node) = 0;
  virtual Status cleanup(const std::string& node) = 0;
  // What shutting the node down does: deactivate, clean up, destroy.
  virtual void destroy(const std::string& node) = 0;

  // The test's own host table: an active endpoint without remaps.
  virtual const plr_host_api* test_api() = 0;
  // Lets `time` pass on the kernel's clock and runs what is due: deliveries,
  // timeouts. The fake kernel moves its manual clock; a real one waits.
  virtual void run(std::chrono::nanoseconds time) = 0;

  // Messages nodes rejected (failed verification), and message buffers alive.
  virtual std::uint64_t rejected() const = 0;
  virtual std::int64_t live_messages() const = 0;
};

using ContractHostFactory = std::function<std::unique_ptr<ContractHost>()>;

// Registers one test per promise in the suite `suite`, each on a fresh host.
// Call after ::testing::InitGoogleTest (or at static initialisation) and
// before RUN_ALL_TESTS.
void register_host_contract_tests(const std::string& suite, ContractHostFactory make);

}  // namespace plr::testing
