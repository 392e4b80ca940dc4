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
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <thread>
#include <vector>

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
shm::TopicConfig exported(const PipelineConfig& config, const std::string& topic,
                          std::uint64_t type_id = 7) {
  const std::string run = shm::test::unique_run_id();
  Bus bus([&](const std::string& t) { return config.topic(t); });
  ShmBridge bridge(bus, config, "main", {"main", "b"}, run);
  bus.attach(&bridge);
  TestEndpoint ep("publisher");
  EXPECT_TRUE(bus.advertise(&ep, topic, type_id, 1).has_value());
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

TEST(BridgeConfig, SlotsAreSizedFromTheTopicsMessageTypeUnlessTheConfigSetsThem) {
  auto c = config_with("  fixed: {slot_size: 3000}\n");
  ASSERT_TRUE(c.has_value()) << c.error().message;
  EXPECT_EQ(exported(*c, "world", MessageTraits<msg::WorldState>::type_id()).slot_size, 512u * 1024)
      << "WorldState's max_bytes";
  EXPECT_EQ(exported(*c, "progress", MessageTraits<msg::Progress>::type_id()).slot_size, 256u);
  EXPECT_EQ(exported(*c, "fixed", MessageTraits<msg::WorldState>::type_id()).slot_size, 3000u);
}

plr_msg* blob(std::size_t bytes, std::uint8_t value) {
  flatbuffers::FlatBufferBuilder fbb;
  const std::vector<std::uint8_t> data(bytes, value);
  fbb.Finish(msg::CreateNextStrategyRequestDirect(fbb, &data));
  return msg_copy(fbb.GetBufferPointer(), fbb.GetSize(),
                  MessageTraits<msg::NextStrategyRequest>::type_id(), 1, 0);
}

// A provider on host b answers `blob` with `reply_bytes` bytes.
struct BlobServer {
  Bus* bus;
  std::size_t reply_bytes;
  static void on(void* user, const plr_msg*, std::uint64_t token) {
    auto* self = static_cast<BlobServer*>(user);
    (void)self->bus->respond(token, PLR_OK, blob(self->reply_bytes, 1), "");
  }
};

struct Answer {
  std::mutex m;
  std::condition_variable cv;
  bool done = false;
  plr_status status = PLR_OK;
  std::string error;
  static void on(void* user, plr_status status, const plr_msg*, const char* error) {
    auto* self = static_cast<Answer*>(user);
    std::lock_guard lock(self->m);
    self->done = true;
    self->status = status;
    self->error = error != nullptr ? error : "";
    self->cv.notify_all();
  }
  bool wait(std::chrono::milliseconds limit) {
    std::unique_lock lock(m);
    return cv.wait_for(lock, limit, [&] { return done; });
  }
};

// A call from host main to `blob` on host b (two bridges in this process)
// with a request of `request_bytes`; what it was answered, once b serves it.
Answer* call_blob(Bus& bus, Endpoint& caller, std::size_t request_bytes, Answer& answer,
                  const std::string& service = "blob") {
  const auto type = MessageTraits<msg::NextStrategyRequest>::type_id();
  for (int i = 0; i < 500; ++i) {
    answer.done = false;
    auto s =
        bus.call(&caller, service, type, blob(request_bytes, 2), 5s, &Answer::on, &answer, nullptr);
    if (!s && s.error().message.find("no provider") != std::string::npos) {
      std::this_thread::sleep_for(10ms);  // b's segment is not up yet
      continue;
    }
    if (!s) {
      ADD_FAILURE() << s.error().message;
      return nullptr;
    }
    return answer.wait(10s) ? &answer : nullptr;
  }
  return nullptr;
}

TEST(BridgeLimits, AMessageLargerThanItsServicesSlotsIsAClearErrorNotATimeout) {
  auto c = config_with("  blob: {slot_size: 1024}\n  tiny: {slot_size: 100}\n");
  ASSERT_TRUE(c.has_value()) << c.error().message;
  const std::string run = shm::test::unique_run_id();
  Bus bus_main([&](const std::string& t) { return c->topic(t); });
  Bus bus_b([&](const std::string& t) { return c->topic(t); });
  ShmBridge main_bridge(bus_main, *c, "main", {"main", "b"}, run);
  ShmBridge b_bridge(bus_b, *c, "b", {"main", "b"}, run);
  bus_main.attach(&main_bridge);
  bus_b.attach(&b_bridge);
  TestEndpoint provider("provider"), caller("caller");
  BlobServer server{&bus_b, 4000};
  const auto type = MessageTraits<msg::NextStrategyRequest>::type_id();
  ASSERT_TRUE(bus_b.provide(&provider, "blob", type, type, &BlobServer::on, &server));
  ASSERT_TRUE(bus_b.provide(&provider, "tiny", type, type, &BlobServer::on, &server));
  bus_b.set_live(&provider, true);

  // The call's 5 s timeout would end it with PLR_ERR_TIMEOUT: its status
  // says it was answered.
  Answer reply_too_large;
  ASSERT_NE(call_blob(bus_main, caller, 16, reply_too_large), nullptr);
  EXPECT_EQ(reply_too_large.status, PLR_ERR_INVALID) << "answered, not timed out";
  EXPECT_NE(reply_too_large.error.find("service 'blob': a message of "), std::string::npos)
      << reply_too_large.error;
  EXPECT_NE(reply_too_large.error.find("exceeds its 1024-byte slots"), std::string::npos)
      << reply_too_large.error;

  Answer request_too_large;
  ASSERT_NE(call_blob(bus_main, caller, 4000, request_too_large), nullptr);
  EXPECT_EQ(request_too_large.status, PLR_ERR_INVALID);
  EXPECT_NE(request_too_large.error.find("exceeds its 1024-byte slots"), std::string::npos)
      << request_too_large.error;

  // Slots smaller than the reason itself: the caller gets as much of it as fits.
  Answer tiny;
  ASSERT_NE(call_blob(bus_main, caller, 16, tiny, "tiny"), nullptr);
  EXPECT_EQ(tiny.status, PLR_ERR_INVALID);
  EXPECT_EQ(tiny.error.rfind("shm: service 'tiny': a message of ", 0), 0u) << tiny.error;

  server.reply_bytes = 100;
  Answer fits;
  ASSERT_NE(call_blob(bus_main, caller, 16, fits), nullptr);
  EXPECT_EQ(fits.status, PLR_OK) << fits.error;

  bus_b.remove_endpoint(&provider);
  bus_main.detach(&main_bridge);
  bus_b.detach(&b_bridge);
}

// A provider that keeps the requests it gets unanswered until told.
struct HoldingServer {
  Bus* bus;
  std::mutex m;
  std::vector<std::uint64_t> tokens;
  static void on(void* user, const plr_msg*, std::uint64_t token) {
    auto* self = static_cast<HoldingServer*>(user);
    std::lock_guard lock(self->m);
    self->tokens.push_back(token);
  }
  std::size_t held() {
    std::lock_guard lock(m);
    return tokens.size();
  }
  void answer_all() {
    std::lock_guard lock(m);
    for (const auto t : tokens) (void)bus->respond(t, PLR_OK, blob(8, 3), "");
    tokens.clear();
  }
};

TEST(BridgeServices, CallsGoToTheHostWithTheFewestWaitingOfSeveralServingIt) {
  auto c = parse_pipeline_config(
      "hosts:\n  b: {restart: never}\n  c: {restart: never}\n"
      "nodes:\n  a: {plugin: x}\n  b: {plugin: x, host: b}\n  c: {plugin: x, host: c}\n",
      "several_providers.yaml");
  ASSERT_TRUE(c.has_value()) << c.error().message;
  const std::string run = shm::test::unique_run_id();
  const std::vector<std::string> hosts = {"main", "b", "c"};
  Bus bus_main([&](const std::string& t) { return c->topic(t); });
  Bus bus_b([&](const std::string& t) { return c->topic(t); });
  Bus bus_c([&](const std::string& t) { return c->topic(t); });
  ShmBridge main_bridge(bus_main, *c, "main", hosts, run);
  ShmBridge b_bridge(bus_b, *c, "b", hosts, run);
  ShmBridge c_bridge(bus_c, *c, "c", hosts, run);
  bus_main.attach(&main_bridge);
  bus_b.attach(&b_bridge);
  bus_c.attach(&c_bridge);
  TestEndpoint on_b("provider_b"), on_c("provider_c"), caller("caller");
  HoldingServer server_b{&bus_b, {}, {}}, server_c{&bus_c, {}, {}};
  const auto type = MessageTraits<msg::NextStrategyRequest>::type_id();
  ASSERT_TRUE(bus_b.provide(&on_b, "work", type, type, &HoldingServer::on, &server_b));
  ASSERT_TRUE(bus_c.provide(&on_c, "work", type, type, &HoldingServer::on, &server_c));
  bus_b.set_live(&on_b, true);
  bus_c.set_live(&on_c, true);
  const auto eventually = [](auto done) {
    for (int i = 0; i < 500 && !done(); ++i) std::this_thread::sleep_for(10ms);
    return done();
  };
  // Both services' segments up before the calls (a bridge looks at a
  // missing one again 100 ms later).
  ASSERT_TRUE(eventually([&] { return shm::test::run_segments(run).size() >= 2; }));
  std::this_thread::sleep_for(150ms);

  std::vector<std::unique_ptr<Answer>> answers;
  for (int i = 0; i < 4; ++i) {
    answers.push_back(std::make_unique<Answer>());
    ASSERT_TRUE(bus_main.call(&caller, "work", type, blob(16, 2), 10s, &Answer::on,
                              answers.back().get(), nullptr));
    // Each call is with its host before the next one is counted.
    const std::size_t sent = answers.size();
    ASSERT_TRUE(eventually([&] { return server_b.held() + server_c.held() == sent; }));
  }
  EXPECT_EQ(server_b.held(), 2u);
  EXPECT_EQ(server_c.held(), 2u);
  server_b.answer_all();
  server_c.answer_all();
  for (auto& a : answers) {
    ASSERT_TRUE(a->wait(5s));
    EXPECT_EQ(a->status, PLR_OK) << a->error;
  }
  bus_b.remove_endpoint(&on_b);
  bus_c.remove_endpoint(&on_c);
  bus_main.detach(&main_bridge);
  bus_b.detach(&b_bridge);
  bus_c.detach(&c_bridge);
}

// Mappings of this process of a run's segments that are gone from /dev/shm:
// their pages stay taken there until unmapped.
int deleted_segments_mapped(const std::string& run) {
  std::ifstream maps("/proc/self/maps");
  int n = 0;
  for (std::string line; std::getline(maps, line);)
    n += line.find(run) != std::string::npos && line.find("(deleted)") != std::string::npos;
  return n;
}

// A host that restarts serves from new segments; the caller's clients of
// the dead server's are dropped, so that their pages leave /dev/shm however
// often it restarts (issue 50: a soak's simulator restarts filled it).
TEST(BridgeServices, AServerThatRestartsLeavesNoOldSegmentMapped) {
  auto c = config_with("  blob: {slot_size: 1024}\n");
  ASSERT_TRUE(c.has_value()) << c.error().message;
  const std::string run = shm::test::unique_run_id();
  const auto type = MessageTraits<msg::NextStrategyRequest>::type_id();
  Bus bus_main([&](const std::string& t) { return c->topic(t); });
  ShmBridge main_bridge(bus_main, *c, "main", {"main", "b"}, run);
  bus_main.attach(&main_bridge);
  TestEndpoint caller("caller");
  // A reply kept past its server's death and the client's end (a world
  // the executor observed): read in place, its segment stays mapped for it.
  struct Keeper {
    const plr_msg* kept = nullptr;
    static void on(void* user, plr_status status, const plr_msg* m, const char*) {
      auto* self = static_cast<Keeper*>(user);
      if (status == PLR_OK && m != nullptr && self->kept == nullptr) {
        msg_retain(m);
        self->kept = m;
      }
    }
  } keeper;
  for (int life = 0; life < 3; ++life) {
    Bus bus_b([&](const std::string& t) { return c->topic(t); });
    auto b_bridge =
        std::make_unique<ShmBridge>(bus_b, *c, "b", std::vector<std::string>{"main", "b"}, run);
    bus_b.attach(b_bridge.get());
    TestEndpoint provider("provider");
    BlobServer server{&bus_b, 100};
    ASSERT_TRUE(bus_b.provide(&provider, "blob", type, type, &BlobServer::on, &server));
    bus_b.set_live(&provider, true);
    // The first calls may still find the server before: they fail, unavailable.
    bool answered = false;
    for (int i = 0; i < 100 && !answered; ++i) {
      Answer a;
      ASSERT_NE(call_blob(bus_main, caller, 16, a), nullptr);
      answered = a.status == PLR_OK;
      if (!answered) std::this_thread::sleep_for(10ms);
    }
    EXPECT_TRUE(answered) << "life " << life;
    if (life == 0) {
      ASSERT_TRUE(
          bus_main.call(&caller, "blob", type, blob(16, 2), 5s, &Keeper::on, &keeper, nullptr));
      for (int i = 0; i < 500 && keeper.kept == nullptr; ++i) std::this_thread::sleep_for(10ms);
      ASSERT_NE(keeper.kept, nullptr);
    }
    bus_b.remove_endpoint(&provider);
    bus_b.detach(b_bridge.get());
    b_bridge.reset();
  }
  // Calls that find no server let go of the dead ones.
  for (int i = 0; i < 200 && deleted_segments_mapped(run) > 0; ++i) {
    Answer a;
    (void)bus_main.call(&caller, "blob", type, blob(16, 2), 1s, &Answer::on, &a, nullptr);
    std::this_thread::sleep_for(10ms);
  }
  // Only the kept reply's segment is still mapped, and the reply reads as sent.
  EXPECT_EQ(deleted_segments_mapped(run), 1);
  const auto view = msg_view(keeper.kept);
  auto verifier = flatbuffers::Verifier(view.data, view.size);
  ASSERT_TRUE(verifier.VerifyBuffer<msg::NextStrategyRequest>(nullptr));
  const auto* reply = flatbuffers::GetRoot<msg::NextStrategyRequest>(view.data);
  ASSERT_NE(reply->world(), nullptr);
  EXPECT_EQ(reply->world()->size(), 100u);
  EXPECT_EQ(reply->world()->Get(99), 1);
  msg_release(keeper.kept);
  EXPECT_EQ(deleted_segments_mapped(run), 0);
  bus_main.detach(&main_bridge);
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
