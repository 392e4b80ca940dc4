// A quick service answered over DDS: its handler runs on Cyclone's receive
// thread, which must never wait for acknowledgements only it can take in.
// Bursts of large replies get ahead of the acknowledgements, past what the
// reply writer may leave unacknowledged: a reply written there naively
// stalls the thread for the writer's blocking time (1 s), and calls given
// less than that time out. And back-to-back large calls must not wait for acknowledgements.
// Two processes: Cyclone delivers between participants of one process
// without its receive threads.
#include "bare_kernel.hpp"

#include <plr/message.hpp>

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>
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
  if (!k.open()) ::_exit(3);
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
    const Status joined = kernel_.open();
    ASSERT_TRUE(joined) << joined.error().message;
    const auto ready_by = Clock::now() + 20s;
    while (calls(1, 64) != 0 && Clock::now() < ready_by) std::this_thread::sleep_for(50ms);
  }

  // `n` calls of `size` bytes, all sent at once, each with `timeout`; waits
  // for every answer and returns how many failed.
  int calls(int n, std::size_t size, std::chrono::milliseconds timeout = 3s) {
    struct Answers {
      std::mutex m;
      std::condition_variable cv;
      int left = 0, failed = 0;
      std::size_t size = 0;
    } a;
    a.left = n;
    a.size = size;
    const std::vector<std::uint8_t> payload(size, 0x5a);
    for (int i = 0; i < n; ++i) {
      auto s = kernel_.bus().call(
          &caller_, "echo", kEchoType, msg_copy(payload.data(), size, kEchoType, 1, 0), timeout,
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
    return a.failed;
  }

  static inline int domain_ = 0;
  static inline pid_t provider_ = -1;
  BareKernel kernel_{domain_, "quick_caller", false, "echo"};
  testing::TestEndpoint& caller_ = kernel_.add_node("caller");
};

TEST_F(RemoteQuickService, LargeRepliesFromTheReceiveThreadNeverStall) {
  // Bursts of 16 calls of 256 KiB: the provider's receive thread answers
  // them faster than acknowledgements come back, past the 2 MB a writer may
  // leave unacknowledged. A stalled receive thread would hold the burst for
  // 1 s: calls given 900 ms then time out, and count as failed.
  int failed = 0;
  for (int i = 0; i < 20; ++i) failed += calls(16, 256 * 1024, 900ms);
  EXPECT_EQ(failed, 0);
}

// Back-to-back calls of 64 KiB: the writer must get its acknowledgements
// before its unacknowledged data reaches the limit, or every few calls it
// waits a round trip for them (with Cyclone's defaults, every 8th call).
TEST_F(RemoteQuickService, BackToBackLargeCallsKeepAheadOfAcknowledgements) {
  int failed = 0;
  for (int i = 0; i < 400; ++i) failed += calls(1, 64 * 1024);
  EXPECT_EQ(failed, 0);
  // A few waits are allowed for a loaded machine's late ACK: 1 call in 100.
  const auto stats = kernel_.bridge_stats();
  EXPECT_LE(stats["writer_waits"].get<int>(), 4) << stats.dump();
}

}  // namespace
}  // namespace plr::kernel::remote_test
