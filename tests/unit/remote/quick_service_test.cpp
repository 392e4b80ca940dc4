// A quick service answered over DDS: its handler runs on Cyclone's receive
// thread, which must never wait for acknowledgements only it can take in.
// Bursts of large replies get ahead of the acknowledgements, past what the
// reply writer may leave unacknowledged: a reply written there naively
// stalls the thread for the writer's blocking time (1 s) and the call times
// out. And back-to-back large calls must not wait for acknowledgements.
// Two processes: Cyclone delivers between participants of one process
// without its receive threads.
#include "bare_kernel.hpp"

#include <plr/message.hpp>

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace plr::kernel::remote_test {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// The provider's process: answers from the thread that received each
// request, until the test process ends.
[[noreturn]] void provide_echo(int domain) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  BareKernel k(domain, "quick_provider", true, "echo");
  if (!k.open().empty()) ::_exit(3);
  if (!k.provide_echo(k.add_node("echo"), "echo", PLR_SERVICE_QUICK)) ::_exit(4);
  for (;;) ::pause();
}

// The provider's process, for the life of one test.
class Provider {
 public:
  Provider() : child_(::fork()) {  // before this process has threads
    if (child_ == 0) provide_echo(domain);
  }
  ~Provider() {
    if (child_ <= 0) return;
    ::kill(child_, SIGKILL);
    ::waitpid(child_, nullptr, 0);
  }
  bool started() const { return child_ > 0; }
  Provider(const Provider&) = delete;
  Provider& operator=(const Provider&) = delete;

  const int domain = 100 + (::getpid() + 20) % 100;

 private:
  pid_t child_;
};

// Calls of `size` bytes, one after the other; how many failed.
int one_by_one(BareKernel& k, testing::TestEndpoint& caller, int n, std::size_t size) {
  struct Answer {
    std::mutex m;
    std::condition_variable cv;
    bool done = false, ok = false;
    std::size_t size = 0;
  };
  const std::vector<std::uint8_t> payload(size, 0x5a);
  int failed = 0;
  for (int i = 0; i < n; ++i) {
    Answer a;
    a.size = size;
    auto s = k.bus().call(
        &caller, "echo", kEchoType, msg_copy(payload.data(), size, kEchoType, 1, 0), 3s,
        [](void* user, plr_status status, const plr_msg* reply, const char*) {
          auto* a = static_cast<Answer*>(user);
          std::lock_guard lock(a->m);
          a->ok = status == PLR_OK && msg_view(reply).size == a->size;
          a->done = true;
          a->cv.notify_all();
        },
        &a, nullptr);
    if (!s) {
      ++failed;
      continue;
    }
    std::unique_lock lock(a.m);
    a.cv.wait(lock, [&] { return a.done; });
    failed += !a.ok;
  }
  return failed;
}

TEST(RemoteQuickService, LargeRepliesFromTheReceiveThreadNeverStall) {
  Provider provider;
  ASSERT_TRUE(provider.started());
  BareKernel k(provider.domain, "quick_caller", false, "echo");
  ASSERT_EQ(k.open(), "");
  testing::TestEndpoint& caller = k.add_node("caller");

  // `n` calls of `size` bytes at once; how many failed, and how long the
  // slowest took.
  const auto burst = [&](int n, std::size_t size) {
    struct Answers {
      std::mutex m;
      std::condition_variable cv;
      int left = 0, failed = 0;
      std::size_t size = 0;
    } a;
    a.left = n;
    a.size = size;
    const std::vector<std::uint8_t> payload(size, 0x5a);
    const auto t0 = Clock::now();
    for (int i = 0; i < n; ++i) {
      auto s = k.bus().call(
          &caller, "echo", kEchoType, msg_copy(payload.data(), size, kEchoType, 1, 0), 3s,
          [](void* user, plr_status status, const plr_msg* reply, const char*) {
            auto* a = static_cast<Answers*>(user);
            std::lock_guard lock(a->m);
            a->failed += status != PLR_OK || msg_view(reply).size != a->size;
            --a->left;
            a->cv.notify_all();
          },
          &a, nullptr);
      if (!s) {
        std::lock_guard lock(a.m);
        ++a.failed;
        --a.left;
      }
    }
    std::unique_lock lock(a.m);
    a.cv.wait(lock, [&] { return a.left == 0; });
    return std::make_pair(a.failed, Clock::now() - t0);
  };
  const auto ready_by = Clock::now() + 20s;
  while (burst(1, 64).first != 0 && Clock::now() < ready_by) std::this_thread::sleep_for(50ms);

  // Bursts of 16 calls of 256 KiB: the provider's receive thread answers
  // them faster than acknowledgements come back, past the 2 MB a writer may
  // leave unacknowledged.
  int failed = 0;
  auto slowest = Clock::duration::zero();
  for (int i = 0; i < 20; ++i) {
    const auto [f, took] = burst(16, 256 * 1024);
    failed += f;
    slowest = std::max(slowest, took);
  }
  EXPECT_EQ(failed, 0);
  EXPECT_LT(slowest, 500ms)
      << "a burst took " << std::chrono::duration_cast<std::chrono::milliseconds>(slowest).count()
      << " ms";
}

// Back-to-back calls of 64 KiB: the writer must get its acknowledgements
// before its unacknowledged data reaches the limit, or every few calls it
// waits a round trip for them (with Cyclone's defaults, every 8th call).
TEST(RemoteQuickService, BackToBackLargeCallsKeepAheadOfAcknowledgements) {
  Provider provider;
  ASSERT_TRUE(provider.started());
  BareKernel k(provider.domain, "quick_caller", false, "echo");
  ASSERT_EQ(k.open(), "");
  testing::TestEndpoint& caller = k.add_node("caller");
  const auto ready_by = Clock::now() + 20s;
  while (one_by_one(k, caller, 1, 64) != 0 && Clock::now() < ready_by)
    std::this_thread::sleep_for(50ms);

  EXPECT_EQ(one_by_one(k, caller, 400, 64 * 1024), 0);
  // A few waits are allowed for a loaded machine's late ACK: 1 call in 100.
  const auto stats = k.bridge_stats();
  EXPECT_LE(stats["writer_waits"].get<int>(), 4) << stats.dump();
}

}  // namespace
}  // namespace plr::kernel::remote_test
