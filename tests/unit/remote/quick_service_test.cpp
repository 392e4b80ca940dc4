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

// A caller kernel in this process; one quick echo provider in a child for
// all the tests, forked before this process has threads.
class RemoteQuickService : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    domain_ = 100 + (::getpid() + 20) % 100;
    provider_ = ::fork();
    if (provider_ == 0) provide_echo(domain_);
  }
  static void TearDownTestSuite() {
    if (provider_ <= 0) return;
    ::kill(provider_, SIGKILL);
    ::waitpid(provider_, nullptr, 0);
  }

  // Until the provider answers.
  void SetUp() override {
    ASSERT_GT(provider_, 0) << "fork failed";
    ASSERT_EQ(kernel_.open(), "");
    const auto ready_by = Clock::now() + 20s;
    while (calls(1, 64).failed != 0 && Clock::now() < ready_by) std::this_thread::sleep_for(50ms);
  }

  struct Outcome {
    int failed = 0;
    Clock::duration took{};
  };
  // `n` calls of `size` bytes, all sent at once; waits for every answer.
  Outcome calls(int n, std::size_t size) {
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
      auto s = kernel_.bus().call(
          &caller_, "echo", kEchoType, msg_copy(payload.data(), size, kEchoType, 1, 0), 3s,
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
    return {a.failed, Clock::now() - t0};
  }

  static inline int domain_ = 0;
  static inline pid_t provider_ = -1;
  BareKernel kernel_{domain_, "quick_caller", false, "echo"};
  testing::TestEndpoint& caller_ = kernel_.add_node("caller");
};

TEST_F(RemoteQuickService, LargeRepliesFromTheReceiveThreadNeverStall) {
  // Bursts of 16 calls of 256 KiB: the provider's receive thread answers
  // them faster than acknowledgements come back, past the 2 MB a writer may
  // leave unacknowledged.
  int failed = 0;
  auto slowest = Clock::duration::zero();
  for (int i = 0; i < 20; ++i) {
    const auto burst = calls(16, 256 * 1024);
    failed += burst.failed;
    slowest = std::max(slowest, burst.took);
  }
  EXPECT_EQ(failed, 0);
  EXPECT_LT(slowest, 500ms)
      << "a burst took " << std::chrono::duration_cast<std::chrono::milliseconds>(slowest).count()
      << " ms";
}

// Back-to-back calls of 64 KiB: the writer must get its acknowledgements
// before its unacknowledged data reaches the limit, or every few calls it
// waits a round trip for them (with Cyclone's defaults, every 8th call).
TEST_F(RemoteQuickService, BackToBackLargeCallsKeepAheadOfAcknowledgements) {
  int failed = 0;
  for (int i = 0; i < 400; ++i) failed += calls(1, 64 * 1024).failed;
  EXPECT_EQ(failed, 0);
  // A few waits are allowed for a loaded machine's late ACK: 1 call in 100.
  const auto stats = kernel_.bridge_stats();
  EXPECT_LE(stats["writer_waits"].get<int>(), 4) << stats.dump();
}

}  // namespace
}  // namespace plr::kernel::remote_test
