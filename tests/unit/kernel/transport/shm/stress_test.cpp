// Stress: 4 processes (1 publisher, 3 subscribers), 10^6 messages on a
// reliable topic: no loss, no reordering, no deadlock (children carry an
// alarm), memory bounded by the configured ring.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

#include "test_util.hpp"

namespace plr::shm {
namespace {

using namespace std::chrono_literals;

constexpr std::uint64_t kMessages = 1'000'000;
constexpr int kSubscribers = 3;
constexpr std::size_t kPayload = 64;
// A subscriber that is still running after this is taken for deadlocked and
// killed by an alarm. Under ThreadSanitizer the run is 5-10 times slower: on
// two loaded cores it took 24-48 s, and past 50 s it was killed while still
// making progress. Both stay below the test's ctest timeout (120 s).
#if defined(__SANITIZE_THREAD__)
constexpr unsigned kChildAlarmSeconds = 100;
#else
constexpr unsigned kChildAlarmSeconds = 50;
#endif

// Resident set of a process in KiB, from /proc/<pid>/status.
long rss_kib(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  std::string key;
  while (f >> key) {
    if (key == "VmRSS:") {
      long v = 0;
      f >> v;
      return v;
    }
    f.ignore(4096, '\n');
  }
  return -1;
}

std::size_t segment_bytes(const std::string& run) {
  std::size_t total = 0;
  for (const auto& n : test::run_segments(run)) {
    struct stat st {};
    if (::stat(("/dev/shm/" + n).c_str(), &st) == 0) total += static_cast<std::size_t>(st.st_size);
  }
  return total;
}

TEST(StressTest, FourProcessesMillionMessagesReliable) {
  const std::string run = test::unique_run_id();
  TopicConfig cfg;
  cfg.slot_count = 64;
  cfg.slot_size = 256;
  cfg.policy = Policy::kReliable;
  auto pub = PublisherBuilder().run_id(run).topic("stress").config(cfg).create();
  ASSERT_TRUE(pub.has_value());
  const std::size_t ring_bytes = segment_bytes(run);
  ASSERT_GT(ring_bytes, 0u);

  test::Pipe ready, done, exit_now;
  pid_t kids[kSubscribers];
  for (pid_t& kid : kids) {
    kid = test::fork_child(
        [&] {
          auto sub = SubscriberBuilder().run_id(run).topic("stress").create();
          if (!sub) return 10;
          ready.signal();
          for (std::uint64_t i = 0; i < kMessages; ++i) {
            auto m = sub->take(10s);
            if (!m) return 11;
            if (m->info().seq != i || m->data().size() != kPayload) return 12;
            std::uint64_t a = 0, z = 0;
            std::memcpy(&a, m->data().data(), 8);
            std::memcpy(&z, m->data().data() + kPayload - 8, 8);
            if (a != i || z != ~i) return 13;
          }
          const Counters c = sub->counters();
          if (c.received != kMessages || c.dropped_slow != 0 || c.dropped_invalid != 0) return 14;
          done.signal();
          exit_now.wait();
          return 0;
        },
        kChildAlarmSeconds);
    ASSERT_GT(kid, 0);
  }
  // Only the children write to these: a subscriber that fails or is killed
  // then ends our wait (0, end-of-file) instead of leaving us blocked.
  ready.close_write();
  done.close_write();
  for (int i = 0; i < kSubscribers; ++i)
    ASSERT_EQ(ready.wait(), 'x') << "a subscriber exited before it was ready";
  ASSERT_EQ(pub->subscriber_count(), static_cast<std::size_t>(kSubscribers));

  const auto t0 = std::chrono::steady_clock::now();
  for (std::uint64_t i = 0; i < kMessages; ++i) {
    auto l = pub->loan(kPayload, 10s);
    ASSERT_TRUE(l.has_value()) << "message " << i << ": " << to_string(l.error());
    const std::uint64_t z = ~i;
    std::memcpy(l->data(), &i, 8);
    std::memcpy(l->data() + kPayload - 8, &z, 8);
    ASSERT_TRUE(pub->publish(std::move(*l), MessageType{1, 1}, 0, kPayload).has_value());
    if (i % 250'000 == 0) {
      ASSERT_EQ(segment_bytes(run), ring_bytes) << "memory must not grow";
    }
  }
  for (int i = 0; i < kSubscribers; ++i)
    ASSERT_EQ(done.wait(), 'x') << "a subscriber exited (or was killed by its alarm, "
                                << kChildAlarmSeconds << " s) before it had all messages";
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%llu messages to %d processes in %.2f s (%.0f msg/s)\n",
              static_cast<unsigned long long>(kMessages), kSubscribers, secs, kMessages / secs);

  // Bounded: the ring plus the process image; nothing per message.
  for (pid_t kid : kids) {
    const long rss = rss_kib(kid);
    EXPECT_GT(rss, 0);
    EXPECT_LT(rss, 64 * 1024) << "subscriber RSS KiB";
  }
  EXPECT_EQ(segment_bytes(run), ring_bytes);
  EXPECT_EQ(pub->counters().published, kMessages);
  for (int i = 0; i < kSubscribers; ++i) exit_now.signal();
  for (pid_t kid : kids) EXPECT_EQ(test::wait_child(kid), 0);
}

}  // namespace
}  // namespace plr::shm
