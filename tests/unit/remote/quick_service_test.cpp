// A quick service answered over DDS: its handler runs on Cyclone's receive
// thread, which must never wait for acknowledgements only it can take in.
// Large replies fill the reply writer's unacknowledged budget within a few
// calls, so a reply written there naively stalls every call for the
// writer's blocking time (1 s). Two processes: Cyclone delivers between
// participants of one process without its receive threads.
#include "bus.hpp"
#include "dds_bridge.hpp"

#include <plr/message.hpp>

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <future>
#include <thread>

namespace plr::kernel {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr std::uint64_t kEcho = fnv1a("plr.test.Echo");

class Node final : public Endpoint {
 public:
  explicit Node(std::string name) : name_(std::move(name)), executor_(name_) {}
  Executor& executor() override { return executor_; }
  const std::string& endpoint_name() const override { return name_; }

 private:
  std::string name_;
  Executor executor_;
};

Config config_for(int domain, bool provider) {
  Config c;
  c.pipeline = provider ? "quick_provider" : "quick_caller";
  c.dds.enabled = true;
  c.dds.domain = domain;
  (provider ? c.dds.export_patterns : c.dds.import_patterns) = {"echo"};
  return c;
}

// The provider's process: answers each request with its own bytes, from the
// thread that received it, until the test process ends.
[[noreturn]] void provide_echo(int domain) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  const Config config = config_for(domain, true);
  Bus bus([&](const std::string& t) { return config.topic(t); });
  auto bridge = DdsBridge::create(
      bus, config, make_kernel_id(config.pipeline), [] { return std::string("{}"); },
      [](const nlohmann::json&) -> Status { return make_error(PLR_ERR_STATE, "test"); });
  if (!bridge) ::_exit(3);
  bus.attach(bridge->get());
  Node echo("echo");
  bus.set_live(&echo, true);
  const auto answer = [](void* user, const plr_msg* req, std::uint64_t token) {
    msg_retain(req);
    (void)static_cast<Bus*>(user)->respond(token, PLR_OK, const_cast<plr_msg*>(req), "");
  };
  if (!bus.provide(&echo, "echo", kEcho, kEcho, answer, &bus, PLR_SERVICE_QUICK)) ::_exit(4);
  for (;;) ::pause();
}

TEST(RemoteQuickService, LargeRepliesFromTheReceiveThreadNeverStall) {
  const int domain = 100 + (::getpid() + 20) % 100;
  const pid_t child = ::fork();  // before this process has threads
  ASSERT_GE(child, 0);
  if (child == 0) provide_echo(domain);

  const Config config = config_for(domain, false);
  Bus bus([&](const std::string& t) { return config.topic(t); });
  auto bridge = DdsBridge::create(
      bus, config, make_kernel_id(config.pipeline), [] { return std::string("{}"); },
      [](const nlohmann::json&) -> Status { return make_error(PLR_ERR_STATE, "test"); });
  ASSERT_TRUE(bridge) << bridge.error().message;
  bus.attach(bridge->get());
  Node caller("caller");
  bus.set_live(&caller, true);

  struct Answer {
    std::promise<std::pair<plr_status, std::size_t>> done;
  };
  const auto call = [&](std::size_t size) {
    Answer a;
    auto f = a.done.get_future();
    const std::vector<std::uint8_t> payload(size, 0x5a);
    auto s = bus.call(
        &caller, "echo", kEcho, msg_copy(payload.data(), size, kEcho, 1, 0), 3s,
        [](void* user, plr_status status, const plr_msg* reply, const char*) {
          static_cast<Answer*>(user)->done.set_value({status, reply ? msg_view(reply).size : 0});
        },
        &a, nullptr);
    return s ? f.get() : std::make_pair(PLR_ERR_UNAVAILABLE, std::size_t{0});
  };
  const auto ready_by = Clock::now() + 20s;
  while (call(64).first != PLR_OK && Clock::now() < ready_by) std::this_thread::sleep_for(50ms);

  // 64 KiB both ways: the 500 kB the reply writer may leave unacknowledged
  // run out after a handful of calls.
  int failed = 0;
  auto slowest = Clock::duration::zero();
  for (int i = 0; i < 300; ++i) {
    const auto t0 = Clock::now();
    const auto [status, size] = call(64 * 1024);
    slowest = std::max(slowest, Clock::now() - t0);
    failed += status != PLR_OK || size != 64 * 1024;
  }
  EXPECT_EQ(failed, 0);
  EXPECT_LT(slowest, 500ms)
      << "a call waited " << std::chrono::duration_cast<std::chrono::milliseconds>(slowest).count()
      << " ms";

  bus.remove_endpoint(&caller);
  bus.detach(bridge->get());
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
}

}  // namespace
}  // namespace plr::kernel
