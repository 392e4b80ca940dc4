// The kernel drives every node through its life cycle in order, and undoes a
// half-started pipeline.
#include "node_instance.hpp"
#include "kernel.hpp"
#include "kernel_fixture.hpp"

#include <gtest/gtest.h>

namespace plr::kernel {
namespace {

using testing::config_from_yaml;
using testing::EventLog;
using testing::TestEndpoint;

constexpr auto kStats = MessageTraits<msg::Statistics>::type_id();

TEST(Lifecycle, StartsInConfigOrderAndStopsInReverse) {
  EventLog log;
  TestEndpoint watcher;
  {
    Kernel kernel(config_from_yaml(R"(
nodes:
  first: {plugin: test_probe}
  second: {plugin: test_probe}
)"));
    kernel.bus().set_live(&watcher, true);
    ASSERT_TRUE(kernel.bus().subscribe(&watcher, "lifecycle", kStats, &EventLog::on_message, &log));
    ASSERT_TRUE(kernel.start());
    for (const auto& n : kernel.nodes()) EXPECT_EQ(n.state, "active");
    kernel.stop();
    for (const auto& n : kernel.nodes()) EXPECT_EQ(n.state, "unloaded");
    const auto events = log.wait_for(8);
    EXPECT_EQ(events,
              (std::vector<std::string>{"first:configure", "first:activate", "second:configure",
                                        "second:activate", "second:deactivate", "first:deactivate",
                                        "second:cleanup", "first:cleanup"}));
    kernel.bus().remove_endpoint(&watcher);
    watcher.node_thread().drain();
  }
}

TEST(Lifecycle, AFailingNodeStopsWhatWasStartedAndSaysWhich) {
  EventLog log;
  TestEndpoint watcher;
  Kernel kernel(config_from_yaml(R"(
nodes:
  good: {plugin: test_probe}
  bad: {plugin: test_probe, params: {fail_activate: true}}
)"));
  kernel.bus().set_live(&watcher, true);
  ASSERT_TRUE(kernel.bus().subscribe(&watcher, "lifecycle", kStats, &EventLog::on_message, &log));
  auto s = kernel.start();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message,
            "node 'bad' (test_probe): activate failed: activation refused by test");
  const auto events = log.wait_for(6);
  EXPECT_EQ(events, (std::vector<std::string>{"good:configure", "good:activate", "bad:configure",
                                              "bad:cleanup", "good:deactivate", "good:cleanup"}));
  kernel.bus().remove_endpoint(&watcher);
  watcher.node_thread().drain();
}

TEST(Lifecycle, OutOfOrderStepsAreRefused) {
  const auto config = config_from_yaml("nodes:\n  n: {plugin: test_probe}\n");
  PluginLoader loader(plugin_search_paths(config));
  auto lib = loader.load("test_probe");
  ASSERT_TRUE(lib) << lib.error().message;
  Bus bus;
  PipelineClock clock;
  NodeInstance node(bus, config.nodes[0], *lib, clock);
  ASSERT_TRUE(node.create());
  auto early = node.activate();
  ASSERT_FALSE(early);
  EXPECT_EQ(early.error().code, PLR_ERR_STATE);
  EXPECT_EQ(early.error().message, "node 'n': activate needs state configured, it is unconfigured");
  ASSERT_TRUE(node.configure());
  EXPECT_FALSE(node.configure());
  ASSERT_TRUE(node.activate());
  ASSERT_TRUE(node.deactivate());
  EXPECT_TRUE(node.deactivate()) << "deactivate is idempotent";
  ASSERT_TRUE(node.cleanup());
  EXPECT_EQ(node.state(), InstanceState::Unconfigured);
  // Its registrations went with the cleanup, so it configures again.
  ASSERT_TRUE(node.configure());
  ASSERT_TRUE(node.activate());
  EXPECT_EQ(bus.services().at(0).providers, std::vector<std::string>{"n"});
  ASSERT_TRUE(node.deactivate());
  ASSERT_TRUE(node.cleanup());
}

TEST(Lifecycle, BadParametersAreRefusedWithTheKey) {
  Kernel kernel(config_from_yaml(R"(
nodes:
  counter: {plugin: demo_counter, params: {period_ms: "fast"}}
)"));
  auto s = kernel.start();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message,
            "node 'counter' (demo_counter): configure failed: param 'period_ms': expected a "
            "number, got \"fast\"");
}

}  // namespace
}  // namespace plr::kernel
