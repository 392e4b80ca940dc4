// A quick service answered over DDS: its handler runs on Cyclone's receive
// thread, which must never wait for acknowledgements only it can take in.
// Bursts of large replies get ahead of the acknowledgements, past what the
// reply writer may leave unacknowledged: a reply written there naively
// stalls the thread for the writer's blocking time (1 s) and the call times
// out. Two processes: Cyclone delivers between participants of one process
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

TEST(RemoteQuickService, LargeRepliesFromTheReceiveThreadNeverStall) {
  const int domain = 100 + (::getpid() + 20) % 100;
  const pid_t child = ::fork();  // before this process has threads
  ASSERT_GE(child, 0);
  if (child == 0) provide_echo(domain);

  BareKernel k(domain, "quick_caller", false, "echo");
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
  // them faster than acknowledgements come back, past the 500 kB a writer
  // may leave unacknowledged.
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

  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
}

}  // namespace
}  // namespace plr::kernel::remote_test
