// A node's executor: callbacks one at a time, and dispatch() running a task
// on the calling thread only while nothing else of the node runs.
#include "node_thread.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <future>
#include <thread>
#include <vector>

namespace plr::kernel {
namespace {

// Counts tasks and how often two of them ran at once.
struct Probe {
  std::atomic<bool> inside{false};
  std::atomic<int> overlaps{0}, ran{0};
  std::function<void()> task() {
    return [this] {
      if (inside.exchange(true)) ++overlaps;
      std::this_thread::yield();
      inside = false;
      ++ran;
    };
  }
};

TEST(NodeExecutor, DispatchRunsInlineWhenIdleAndQueuesWhenBusy) {
  NodeThread ex("test");
  std::thread::id ran_on;
  ASSERT_TRUE(ex.dispatch([&] { ran_on = std::this_thread::get_id(); }));
  EXPECT_EQ(ran_on, std::this_thread::get_id());

  std::promise<void> release;
  auto released = release.get_future().share();
  ASSERT_TRUE(ex.post([released] { released.wait(); }));
  std::atomic<bool> ran{false};
  ASSERT_TRUE(ex.dispatch([&] {
    ran_on = std::this_thread::get_id();
    ran = true;
  }));
  EXPECT_FALSE(ran);  // queued behind the busy task, not run here
  release.set_value();
  ex.drain();
  EXPECT_TRUE(ran);
  EXPECT_NE(ran_on, std::this_thread::get_id());
}

TEST(NodeExecutor, AnInlineTaskCountsAsOnTheExecutor) {
  // What a callback may do on its executor's thread (run_sync inline, no
  // waiting for its own queue) it may do in an inline task too.
  NodeThread ex("test");
  bool on = false, nested = false;
  ASSERT_TRUE(ex.dispatch([&] {
    on = ex.on_this_thread();
    ex.run_sync([&] { nested = true; });
  }));
  EXPECT_TRUE(on);
  EXPECT_TRUE(nested);
  EXPECT_FALSE(ex.on_this_thread());
}

TEST(NodeExecutor, PostedAndDispatchedTasksNeverOverlap) {
  Probe probe;
  {
    NodeThread ex("test");
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
      threads.emplace_back([&, t] {
        for (int i = 0; i < 500; ++i)
          (void)(t % 2 ? ex.dispatch(probe.task()) : ex.post(probe.task()));
      });
    ex.run_sync(probe.task());
    for (auto& t : threads) t.join();
    ex.drain();
  }
  EXPECT_EQ(probe.ran, 2001);
  EXPECT_EQ(probe.overlaps, 0);
}

TEST(NodeExecutor, DrainWaitsForAnInlineTask) {
  NodeThread ex("test");
  std::promise<void> started, release;
  std::thread dispatcher([&] {
    (void)ex.dispatch([&] {
      started.set_value();
      release.get_future().wait();
    });
  });
  started.get_future().wait();
  auto drained = std::async(std::launch::async, [&] { ex.drain(); });
  EXPECT_EQ(drained.wait_for(std::chrono::milliseconds(50)), std::future_status::timeout);
  release.set_value();
  drained.get();
  dispatcher.join();
}

}  // namespace
}  // namespace plr::kernel
