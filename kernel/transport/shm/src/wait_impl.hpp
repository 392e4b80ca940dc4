// Template part of ring.hpp: the futex / busy-poll wait loop.
#pragma once

#include <sched.h>

#include <algorithm>

#include "futex.hpp"

namespace plr::shm::detail {

template <class Ready, class Check>
Result<void> wait_until(Notifier& n, WaitMode mode, Clock::time_point deadline, Ready ready,
                        Check check, std::uint32_t spin_first, Clock::duration spin_for) noexcept {
  auto next_check = Clock::now() + kLivenessSlice;
  std::uint32_t spins = 0;
  // Check every few pauses only: each check reads lines the peer is writing.
  for (std::uint32_t i = 0; i < spin_first; i += 8) {
    if (ready()) return {};
    for (int k = 0; k < 8; ++k) cpu_relax();
  }
  if (spin_for > Clock::duration::zero()) {
    // Bounded by the budget (and the deadline): an idle reader spins once, then sleeps.
    const auto spin_end = std::min(deadline, Clock::now() + spin_for);
    for (std::uint32_t i = 1;; ++i) {
      if (ready()) return {};
      cpu_relax();
      if (i % 64 == 0 && Clock::now() >= spin_end) break;
    }
  }
  for (;;) {
    if (ready()) return {};
    if (mode == WaitMode::kPolling) {
      cpu_relax();
      // Reading the clock costs ~20 ns: do it every few hundred spins only,
      // and yield then so an oversubscribed core still runs the writer.
      if (++spins % 256 != 0) continue;
      sched_yield();
    }
    const auto now = Clock::now();
    if (now >= next_check) {
      next_check = now + kLivenessSlice;
      if (auto r = check(); !r) return r;
      if (ready()) return {};
    }
    if (now >= deadline) return Error::kTimeout;
    if (mode == WaitMode::kPolling) continue;

    n.sleepers.fetch_add(1, std::memory_order_seq_cst);
    const std::uint32_t word = n.word.load(std::memory_order_seq_cst);
    // ready() may take something (a slot): each true must end the wait.
    const bool got = ready();
    if (!got) futex_wait(n.word, word, std::min(deadline, next_check) - now);
    n.sleepers.fetch_sub(1, std::memory_order_seq_cst);
    if (got) return {};
  }
}

}  // namespace plr::shm::detail
