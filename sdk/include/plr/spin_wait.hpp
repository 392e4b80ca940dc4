// Watching for something another thread is about to do. Waking a blocked
// thread goes through the scheduler, and on a machine whose idle cores halt
// that alone costs 10-20 us; a reply due within a round trip is cheaper to
// watch for. Watching costs a core, so it is bounded, and it yields the core
// at every look: on a busy machine the thread that would answer may be
// waiting for it.
#pragma once

#include <atomic>
#include <chrono>
#include <thread>

namespace plr {

// How long a blocking call watches for its reply before it sleeps: a remote
// round trip of a small message over loopback or a LAN.
inline constexpr std::chrono::microseconds kCallSpin{50};

// True once `flag` is set; false when `budget` ran out first.
inline bool spin_until(const std::atomic<bool>& flag, std::chrono::nanoseconds budget) {
  if (flag.load(std::memory_order_acquire)) return true;
  const auto until = std::chrono::steady_clock::now() + budget;
  while (std::chrono::steady_clock::now() < until) {
    std::this_thread::yield();
    if (flag.load(std::memory_order_acquire)) return true;
  }
  return false;
}

}  // namespace plr
