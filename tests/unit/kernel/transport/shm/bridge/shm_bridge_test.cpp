// The shared-memory bridge: the bus's link to the other host processes of a
// run (kernel/transport/shm/bridge).
//
// A topic's wait mode comes from the config alone: `busy_poll` and `spin_us`
// end up in the segment's geometry, which every reader follows.
//
// The loan path, end to end: a plug-in builds each FlatBuffer straight into a
// buffer it loaned through the SDK (plr/loan.hpp -> plr_host_api::loan). When
// another process reads the topic that buffer is a shared-memory slot: the
// bridge sends it without a copy and in-process subscribers read the same
// slot. When nobody elsewhere reads it, it is plain kernel memory.
#include "shm_bridge.hpp"
#include "bus.hpp"
#include "message.hpp"
#include "node_instance.hpp"
#include "pipeline_config.hpp"
#include "plugin_loader.hpp"
#include "test_endpoint.hpp"
#include "test_util.hpp"

#include <plr/message.hpp>
#include <plr/messages.hpp>
#include <plr/shm/shm.hpp>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <thread>

namespace plr::kernel {
namespace {

using namespace std::chrono_literals;

using testing::TestEndpoint;

Expected<PipelineConfig> config_with(const std::string& topics) {
  return parse_pipeline_config(
      "hosts:\n  b: {restart: never}\n"
      "nodes:\n  a: {plugin: x}\n  b: {plugin: x, host: b}\n"
      "topics:\n" +
          topics,
      "bridge_config_test.yaml");
}

// The geometry a reader of `<host main>/<topic>` sees, once the bridge made it.
shm::TopicConfig exported(const PipelineConfig& config, const std::string& topic) {
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

namespace plr::kernel {
namespace {

using namespace std::chrono_literals;
using Blob = plr::msg::NextStrategyRequest;

using testing::TestEndpoint;

// Checks every blob: verified, `bytes` long, all bytes (n & 0xff) for the n-th one.
struct Reader {
  std::size_t bytes = 0;
  const void* bridge = nullptr;  // set: each message must be a committed loaned slot
  std::atomic<int> got{0};
  std::atomic<int> bad{0};
  std::atomic<int> in_slot{0};

  static void on_message(void* user, const plr_msg* m) {
    auto* self = static_cast<Reader*>(user);
    const auto v = msg_view(m);
    const int n = self->got.load();
    const Blob* blob = verify<Blob>(v.data, v.size) ? flatbuffers::GetRoot<Blob>(v.data) : nullptr;
    bool ok = blob != nullptr && blob->world() != nullptr && blob->world()->size() == self->bytes;
    for (std::size_t i = 0; ok && i < self->bytes; i += 997)
      ok = blob->world()->Get(static_cast<flatbuffers::uoffset_t>(i)) == (n & 0xff);
    if (!ok) self->bad.fetch_add(1);
    if (m->loan != nullptr && m->origin == self->bridge && m->external != nullptr &&
        v.data >= m->external && v.data + v.size <= m->external + m->capacity)
      self->in_slot.fetch_add(1);
    self->got.fetch_add(1);
  }

  bool wait_for(int n, std::chrono::seconds limit) const {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (got.load() < n && std::chrono::steady_clock::now() < end)
      std::this_thread::sleep_for(2ms);
    return got.load() >= n;
  }
};

PipelineConfig make_config(int count, int bytes, int loan_bytes) {
  const std::string yaml = fmt::format(R"(
plugin_paths: ["{}"]
hosts:
  b: {{restart: never}}
nodes:
  publisher: {{plugin: test_loan_publisher, params: {{count: {}, bytes: {}, loan_bytes: {}}}}}
  elsewhere: {{plugin: test_loan_publisher, host: b, params: {{count: 0}}}}
topics:
  blobs: {{policy: reliable, depth: 8, slot_size: {}}}
)",
                                       PLR_TEST_PLUGIN_DIR, count, bytes, loan_bytes, bytes + 4096);
  auto c = parse_pipeline_config(yaml, "loan_test.yaml");
  EXPECT_TRUE(c.has_value()) << c.error().message;
  return *c;
}

const NodeConfig& node(const PipelineConfig& c, const std::string& name) {
  for (const auto& n : c.nodes)
    if (n.name == name) return n;
  throw std::runtime_error("no node " + name);
}

// Host "b": reads `blobs` from host "main" through its own bus and bridge.
int read_elsewhere(const PipelineConfig& config, const std::string& run, int count, int bytes) {
  Bus bus([&](const std::string& t) { return config.topic(t); });
  auto bridge =
      std::make_unique<ShmBridge>(bus, config, "b", std::vector<std::string>{"main", "b"}, run);
  bus.attach(bridge.get());
  TestEndpoint ep("reader@b");
  bus.set_live(&ep, true);
  Reader reader;
  reader.bytes = static_cast<std::size_t>(bytes);
  if (!bus.subscribe(&ep, "blobs", MessageTraits<Blob>::type_id(), &Reader::on_message, &reader))
    return 10;
  const bool all = reader.wait_for(count, 30s);
  bus.remove_endpoint(&ep);
  ep.node_thread().drain();
  bus.detach(bridge.get());
  bridge.reset();
  if (!all) return 11;
  return reader.bad.load() == 0 ? 0 : 12;
}

struct Pipeline {
  explicit Pipeline(const PipelineConfig& c)
      : config(c), bus([&](const std::string& t) { return config.topic(t); }) {}
  ~Pipeline() {
    if (inst) (void)inst->deactivate();
    inst.reset();
    bus.remove_endpoint(&local);
    bus.remove_endpoint(&probe);
    local.node_thread().drain();
    if (bridge) bus.detach(bridge.get());
  }

  // Starts the publishing node; it publishes on activation.
  void start_publisher() {
    PluginLoader loader({PLR_TEST_PLUGIN_DIR});
    auto lib = loader.load("test_loan_publisher");
    ASSERT_TRUE(lib.has_value()) << lib.error().message;
    inst = std::make_unique<NodeInstance>(bus, node(config, "publisher"), *lib, clock);
    ASSERT_TRUE(inst->create());
    ASSERT_TRUE(inst->configure());
    ASSERT_TRUE(inst->activate());
  }

  PipelineConfig config;
  Bus bus;
  PipelineClock clock;
  std::unique_ptr<ShmBridge> bridge;  // destroyed after the messages and node that use it
  TestEndpoint local{"local"}, probe{"probe"};
  Reader reader;
  std::unique_ptr<NodeInstance> inst;
};

TEST(Loan, CrossProcessPublishWritesIntoTheSlotAndNobodyCopies) {
  constexpr int kCount = 200, kBytes = 64 * 1024;
  const PipelineConfig config = make_config(kCount, kBytes, kBytes + 1024);
  const std::string run = shm::test::unique_run_id();
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(read_elsewhere(config, run, kCount, kBytes));

  Pipeline p(config);
  p.bridge = std::make_unique<ShmBridge>(p.bus, p.config, "main",
                                         std::vector<std::string>{"main", "b"}, run);
  p.bus.attach(p.bridge.get());
  p.bus.set_live(&p.local, true);
  p.reader.bytes = kBytes;
  p.reader.bridge = p.bridge.get();
  ASSERT_TRUE(p.bus.subscribe(&p.local, "blobs", MessageTraits<Blob>::type_id(),
                              &Reader::on_message, &p.reader));
  // Once host b reads the segment, a loan on the topic is a slot of it.
  auto probe = p.bus.advertise(&p.probe, "blobs", MessageTraits<Blob>::type_id(), 1);
  ASSERT_TRUE(probe.has_value());
  bool slot = false;
  for (int i = 0; i < 1000 && !slot; ++i) {
    std::uint8_t* data = nullptr;
    plr_msg* m = p.bus.loan(*probe, 64, &data);
    slot = m != nullptr && m->loan != nullptr;
    if (m) msg_release(m);
    if (!slot) std::this_thread::sleep_for(10ms);
  }
  ASSERT_TRUE(slot) << "host b never read the topic";

  p.start_publisher();
  EXPECT_TRUE(p.reader.wait_for(kCount, 30s));
  EXPECT_EQ(shm::test::wait_child(child), 0) << "host b lost or misread blobs";
  EXPECT_EQ(p.reader.bad.load(), 0);
  EXPECT_EQ(p.reader.in_slot.load(), kCount)
      << "in-process subscribers read the very slot host b read";
  const auto stats = p.bridge->stats();
  EXPECT_EQ(stats["sent_copied"], 0) << stats.dump();
  EXPECT_EQ(stats["sent_in_place"], kCount) << stats.dump();
}

TEST(Loan, WithoutReadersElsewhereALoanIsPlainMemoryAndAnOvergrownBuildStillArrives) {
  constexpr int kCount = 50, kBytes = 4096;
  // A 256-byte loan for a 4 KiB blob: the builder grows onto the heap and
  // publish() copies it once into a fresh buffer.
  Pipeline p(make_config(kCount, kBytes, 256));
  p.bridge = std::make_unique<ShmBridge>(
      p.bus, p.config, "main", std::vector<std::string>{"main", "b"}, shm::test::unique_run_id());
  p.bus.attach(p.bridge.get());
  p.bus.set_live(&p.local, true);
  p.reader.bytes = kBytes;
  ASSERT_TRUE(p.bus.subscribe(&p.local, "blobs", MessageTraits<Blob>::type_id(),
                              &Reader::on_message, &p.reader));
  p.start_publisher();
  EXPECT_TRUE(p.reader.wait_for(kCount, 30s));
  EXPECT_EQ(p.reader.bad.load(), 0);
  EXPECT_EQ(p.reader.in_slot.load(), 0) << "no other process reads it: no slot is used";
  const auto stats = p.bridge->stats();
  EXPECT_EQ(stats["sent_in_place"], 0) << stats.dump();
}

}  // namespace
}  // namespace plr::kernel
