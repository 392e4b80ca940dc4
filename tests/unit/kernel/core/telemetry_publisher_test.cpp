// The kernel's telemetry on its own bus (`kernel/telemetry`): what a monitor
// plug-in reads, the nodes with their states and every topic with its counts.
#include "telemetry_publisher.hpp"
#include "kernel.hpp"
#include "kernel_fixture.hpp"

#include <gtest/gtest.h>

#include <condition_variable>
#include <map>
#include <mutex>

namespace plr::kernel::testing {
namespace {

// Keeps the telemetry messages a subscriber got.
struct Received {
  std::mutex m;
  std::condition_variable cv;
  std::vector<std::string> kernels;
  std::map<std::string, std::string> node_states;
  std::map<std::string, std::pair<std::uint64_t, std::uint64_t>> topics;  // messages, type id

  static void on(void* user, const plr_msg* msg) {
    auto& r = *static_cast<Received*>(user);
    const auto v = msg_view(msg);
    ASSERT_TRUE(verify<msg::KernelTelemetry>(v.data, v.size));
    const auto& t = *flatbuffers::GetRoot<msg::KernelTelemetry>(v.data);
    std::lock_guard lock(r.m);
    r.kernels.push_back(t.kernel()->str());
    if (t.nodes())
      for (const auto* n : *t.nodes()) r.node_states[n->name()->str()] = n->state()->str();
    if (t.topics())
      for (const auto* s : *t.topics()) r.topics[s->name()->str()] = {s->messages(), s->type_id()};
    r.cv.notify_all();
  }
  bool wait_for(std::size_t n) {
    std::unique_lock lock(m);
    return cv.wait_for(lock, std::chrono::seconds(10), [&] { return kernels.size() >= n; });
  }
};

TEST(TelemetryPublisher, PublishesWhatItBuildsOncePerPeriod) {
  Bus bus;
  TestEndpoint owner("kernel"), reader("reader");
  bus.set_live(&owner, true);
  bus.set_live(&reader, true);
  Received got;
  ASSERT_TRUE(bus.subscribe(&reader, TelemetryPublisher::kTopic,
                            MessageTraits<msg::KernelTelemetry>::type_id(), &Received::on, &got));
  int built = 0;
  {
    TelemetryPublisher publisher(
        bus, &owner,
        [&](flatbuffers::FlatBufferBuilder& fbb) {
          const auto name = "k" + std::to_string(++built);
          fbb.Finish(msg::CreateKernelTelemetryDirect(fbb, name.c_str(), 0, nullptr, nullptr));
        },
        std::chrono::milliseconds(20));
    ASSERT_TRUE(got.wait_for(3));
  }
  reader.node_thread().drain();
  std::lock_guard lock(got.m);
  EXPECT_EQ(got.kernels[0], "k1");
  EXPECT_EQ(got.kernels[2], "k3");
  bus.remove_endpoint(&reader);
  bus.remove_endpoint(&owner);
}

TEST(TelemetryPublisher, AKernelReportsItsNodesAndTopicsOnItsBus) {
  auto config = parse_pipeline_config("plugin_paths: [" PLR_DEMO_PLUGIN_DIR R"(]
pipeline: telemetry_on_bus
nodes:
  doubler: {plugin: demo_doubler}
  counter: {plugin: demo_counter, params: {period_ms: 10, limit: 1000000}}
)",
                                      "test.yaml");
  ASSERT_TRUE(config) << config.error().message;
  Kernel kernel(*config);
  TestEndpoint reader("reader");
  kernel.bus().set_live(&reader, true);
  Received got;
  ASSERT_TRUE(kernel.bus().subscribe(&reader, TelemetryPublisher::kTopic,
                                     MessageTraits<msg::KernelTelemetry>::type_id(), &Received::on,
                                     &got));
  ASSERT_TRUE(kernel.start());
  ASSERT_TRUE(got.wait_for(2));
  kernel.stop();
  reader.node_thread().drain();
  std::lock_guard lock(got.m);
  EXPECT_EQ(got.kernels.back(), "telemetry_on_bus@main");
  EXPECT_EQ(got.node_states["counter"], "active");
  EXPECT_EQ(got.node_states["doubler"], "active");
  ASSERT_TRUE(got.topics.count("count"));
  EXPECT_GT(got.topics["count"].first, 0u);
  EXPECT_EQ(got.topics["count"].second, MessageTraits<msg::Count>::type_id());
  EXPECT_EQ(got.topics["kernel/telemetry"].second, MessageTraits<msg::KernelTelemetry>::type_id());
  kernel.bus().remove_endpoint(&reader);
}

}  // namespace
}  // namespace plr::kernel::testing
