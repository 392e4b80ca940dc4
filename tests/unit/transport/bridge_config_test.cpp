// A topic's wait mode comes from the config alone: `busy_poll` and `spin_us`
// end up in the segment's geometry, which every reader follows.
#include "bus.hpp"
#include "config.hpp"
#include "shm_bridge.hpp"
#include "test_endpoint.hpp"
#include "test_util.hpp"

#include <gtest/gtest.h>

#include <thread>

namespace plr::kernel {
namespace {

using namespace std::chrono_literals;

using testing::TestEndpoint;

Expected<Config> config_with(const std::string& topics) {
  return parse_config(
      "hosts:\n  b: {restart: never}\n"
      "nodes:\n  a: {plugin: x}\n  b: {plugin: x, host: b}\n"
      "topics:\n" +
          topics,
      "bridge_config_test.yaml");
}

// The geometry a reader of `<host main>/<topic>` sees, once the bridge made it.
shm::TopicConfig exported(const Config& config, const std::string& topic) {
  const std::string run = shm::test::unique_run_id();
  Bus bus([&](const std::string& t) { return config.topic(t); });
  ShmBridge bridge(bus, config, "main", {"main", "b"}, run);
  bus.attach(&bridge);
  TestEndpoint ep("publisher");
  EXPECT_TRUE(bus.advertise(&ep, topic, 7, 1).has_value());
  shm::TopicConfig seen;
  for (int i = 0; i < 500; ++i) {
    auto sub = shm::SubscriberBuilder().run_id(run).topic("main/" + topic).create();
    if (sub) {
      seen = sub->config();
      break;
    }
    std::this_thread::sleep_for(10ms);
  }
  bus.remove_endpoint(&ep);
  bus.detach(&bridge);
  return seen;
}

TEST(BridgeConfig, WaitModesComeFromTheTopicsSettings) {
  auto c = config_with(
      "  spin: {spin_us: 50, depth: 4, slot_size: 256}\n"
      "  poll: {busy_poll: true}\n"
      "  plain: {policy: reliable}\n");
  ASSERT_TRUE(c.has_value()) << c.error().message;
  const auto spin = exported(*c, "spin");
  EXPECT_EQ(spin.wait_mode, shm::WaitMode::kBlocking);
  EXPECT_EQ(spin.spin_us, 50u);
  EXPECT_EQ(spin.slot_count, 4u);
  EXPECT_EQ(spin.slot_size, 256u);
  EXPECT_EQ(exported(*c, "poll").wait_mode, shm::WaitMode::kPolling);
  const auto plain = exported(*c, "plain");
  EXPECT_EQ(plain.wait_mode, shm::WaitMode::kBlocking);
  EXPECT_EQ(plain.spin_us, 0u);
  EXPECT_EQ(plain.policy, shm::Policy::kReliable);
}

TEST(BridgeConfig, SpinBudgetOutOfRangeIsRefusedWithOneLine) {
  auto c = config_with("  spin: {spin_us: 20000}\n");
  ASSERT_FALSE(c.has_value());
  EXPECT_NE(c.error().message.find("spin_us"), std::string::npos) << c.error().message;
  EXPECT_EQ(c.error().message.find('\n'), std::string::npos) << c.error().message;
}

}  // namespace
}  // namespace plr::kernel
