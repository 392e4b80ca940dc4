// Process-shared futex wait/wake on a 32-bit word in shared memory.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>

namespace plr::shm::detail {

// Sleeps while word == expected, at most for timeout (spurious wake-ups allowed).
void futex_wait(std::atomic<std::uint32_t>& word, std::uint32_t expected,
                std::chrono::nanoseconds timeout) noexcept;
void futex_wake_all(std::atomic<std::uint32_t>& word) noexcept;

inline void cpu_relax() noexcept {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

}  // namespace plr::shm::detail
