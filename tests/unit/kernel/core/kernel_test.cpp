// Hot swap: the plug-in behind a node changes while requests flow; every
// request is answered exactly once.
#include "kernel.hpp"
#include "kernel_fixture.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace plr::kernel {
namespace {

using testing::config_from_yaml;
using testing::make_double_request;
using testing::TestEndpoint;

constexpr auto kDoubleReq = MessageTraits<msg::DoubleRequest>::type_id();

using testing::CallLedger;

struct Ledger : CallLedger {
  explicit Ledger(std::size_t calls) : CallLedger(calls), values(calls, -1) {}
  std::vector<std::int64_t> values;
};
using CallCtx = testing::CallCtx<Ledger>;

void on_reply(void* user, plr_status status, const plr_msg* reply, const char* error) {
  auto* c = static_cast<CallCtx*>(user);
  auto& l = *c->ledger;
  std::lock_guard lock(l.m);
  if (status == PLR_OK)
    l.values[c->index] = flatbuffers::GetRoot<msg::DoubleReply>(msg_view(reply).data)->value();
  l.count(c->index, status == PLR_OK ? nullptr : (error ? error : ""));
}

TEST(Swap, ThousandRequestsAcrossHundredSwapsAreEachAnsweredOnce) {
  const auto baseline = live_messages();
  {
    Kernel kernel(config_from_yaml(R"(
nodes:
  doubler: {plugin: test_probe, params: {factor: 2, max_delay_us: 300}}
)"));
    ASSERT_TRUE(kernel.start());
    TestEndpoint client;
    kernel.bus().set_live(&client, true);

    constexpr std::size_t kRequests = 1000;
    constexpr int kSwaps = 100;
    Ledger ledger(kRequests);
    std::vector<CallCtx> ctx(kRequests);
    std::atomic<std::size_t> refused{0};

    std::atomic<bool> calling{true};
    std::thread swapper([&] {
      // The probe's params are foreign to demo_doubler, so alternate between
      // two probes and check a refused swap separately below.
      for (int i = 0; i < kSwaps; ++i) {
        auto s = kernel.swap("doubler", "test_probe");
        EXPECT_TRUE(s) << s.error().message;
        std::this_thread::sleep_for(std::chrono::microseconds(500));
      }
      calling = false;
    });
    std::vector<std::thread> callers;
    for (int t = 0; t < 4; ++t)
      callers.emplace_back([&, t] {
        for (std::size_t i = t; i < kRequests; i += 4) {
          ctx[i] = {&ledger, i};
          auto s = kernel.bus().call(&client, "double", kDoubleReq,
                                     make_double_request(static_cast<std::int64_t>(i)),
                                     std::chrono::seconds(10), &on_reply, &ctx[i], nullptr);
          if (!s) {
            // Refused calls never complete; count them as answered with an error.
            std::lock_guard lock(ledger.m);
            ledger.count(i, s.error().message.c_str());
            ++refused;
          }
          std::this_thread::sleep_for(std::chrono::microseconds(50));
        }
      });
    for (auto& c : callers) c.join();
    swapper.join();
    {
      std::unique_lock lock(ledger.m);
      ledger.cv.wait_for(lock, std::chrono::seconds(20),
                         [&] { return ledger.completed >= kRequests; });
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // a second answer would land here
    std::lock_guard lock(ledger.m);
    std::size_t ok = 0;
    for (std::size_t i = 0; i < kRequests; ++i) {
      EXPECT_EQ(ledger.answers[i], 1) << "request " << i;
      if (ledger.values[i] >= 0) {
        EXPECT_EQ(ledger.values[i], 2 * static_cast<std::int64_t>(i));
        ++ok;
      }
    }
    for (const auto& e : ledger.errors) EXPECT_FALSE(e.empty());
    // The hand-over is atomic, so no request should even see an error.
    EXPECT_EQ(ok, kRequests) << "errors: " << ledger.errors.size() << ", refused " << refused;
    kernel.bus().remove_endpoint(&client);
    client.node_thread().drain();
  }
  EXPECT_EQ(live_messages(), baseline);
}

// `plr swap planner demo_doubler` was accepted: the `plan` service vanished
// and the executor waited for it forever.
TEST(Swap, AnotherKindOrAPluginLackingAServiceIsRefusedBeforeAnythingChanges) {
  Kernel kernel(config_from_yaml(R"(
nodes:
  planner: {plugin: test_planner}
  doubler: {plugin: test_probe}
)"));
  ASSERT_TRUE(kernel.start());
  auto kind = kernel.swap("planner", "demo_doubler");
  ASSERT_FALSE(kind);
  EXPECT_EQ(kind.error().message,
            "swap of 'planner' to 'demo_doubler' refused, 'test_planner' keeps running: "
            "'demo_doubler' is a other plug-in, the node's is a planner");
  auto missing = kernel.swap("doubler", "demo_counter");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, PLR_ERR_INVALID);
  EXPECT_EQ(missing.error().message,
            "swap of 'doubler' to 'demo_counter' refused, 'test_probe' keeps running: "
            "'demo_counter' would not offer double (the node's callers need it)");
  for (const auto& n : kernel.nodes()) EXPECT_EQ(n.state, "active") << n.name;
  // The probe still answers.
  TestEndpoint client;
  kernel.bus().set_live(&client, true);
  Ledger ledger(1);
  CallCtx c{&ledger, 0};
  ASSERT_TRUE(kernel.bus().call(&client, "double", kDoubleReq, make_double_request(21),
                                std::chrono::seconds(5), &on_reply, &c, nullptr));
  std::unique_lock lock(ledger.m);
  ledger.cv.wait_for(lock, std::chrono::seconds(5), [&] { return ledger.completed == 1; });
  EXPECT_EQ(ledger.values[0], 42);
  lock.unlock();
  kernel.bus().remove_endpoint(&client);
  client.node_thread().drain();
}

// Swapping the executor mid-run reset the world, and the report then claimed
// the whole job.
TEST(Swap, ANodeHoldingTheRunsStateIsNotSwapped) {
  Kernel kernel(config_from_yaml("nodes:\n  executor: {plugin: test_executor}\n"));
  ASSERT_TRUE(kernel.start());
  auto s = kernel.swap("executor", "test_executor");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_STATE);
  EXPECT_EQ(s.error().message,
            "swap of 'executor' to 'test_executor' refused, 'test_executor' keeps running: a "
            "executor node holds the run's state, which plug-ins cannot hand over (stop the run "
            "and start it with the new plug-in)");
}

TEST(Swap, FailedSwapKeepsTheOldPluginRunning) {
  Kernel kernel(config_from_yaml(R"(
nodes:
  doubler: {plugin: test_probe, params: {factor: 3, max_delay_us: 0}}
)"));
  ASSERT_TRUE(kernel.start());

  auto missing = kernel.swap("doubler", "no_such_plugin");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find(
                "swap of 'doubler' to 'no_such_plugin' failed, 'test_probe' keeps running"),
            std::string::npos)
      << missing.error().message;

  // demo_doubler refuses the probe's parameters in configure.
  auto refused = kernel.swap("doubler", "demo_doubler");
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("param 'max_delay_us': unknown parameter"),
            std::string::npos)
      << refused.error().message;

  auto unknown = kernel.swap("nobody", "test_probe");
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().message, "swap: no node 'nobody' in this pipeline");

  TestEndpoint client;
  kernel.bus().set_live(&client, true);
  Ledger ledger(1);
  CallCtx c{&ledger, 0};
  ASSERT_TRUE(kernel.bus().call(&client, "double", kDoubleReq, make_double_request(5),
                                std::chrono::seconds(5), &on_reply, &c, nullptr));
  std::unique_lock lock(ledger.m);
  ledger.cv.wait_for(lock, std::chrono::seconds(5), [&] { return ledger.completed == 1; });
  EXPECT_EQ(ledger.values[0], 15);
  EXPECT_EQ(kernel.nodes()[0].plugin, "test_probe");
  EXPECT_EQ(kernel.nodes()[0].state, "active");
  lock.unlock();
  kernel.bus().remove_endpoint(&client);
  client.node_thread().drain();
}

TEST(Swap, SwapToAnotherPluginMovesTheService) {
  Kernel kernel(config_from_yaml(R"(
nodes:
  doubler: {plugin: demo_doubler, params: {factor: 2}}
)"));
  ASSERT_TRUE(kernel.start());
  // test_probe also knows `factor`, so it accepts demo_doubler's params.
  ASSERT_TRUE(kernel.swap("doubler", "test_probe"));
  EXPECT_EQ(kernel.nodes()[0].plugin, "test_probe");
  ASSERT_TRUE(kernel.swap("doubler", "demo_doubler"));
  EXPECT_EQ(kernel.nodes()[0].plugin, "demo_doubler");
  const auto services = kernel.bus().services();
  ASSERT_EQ(services.size(), 1u);
  EXPECT_EQ(services[0].providers, std::vector<std::string>{"doubler"});
}

}  // namespace
}  // namespace plr::kernel
