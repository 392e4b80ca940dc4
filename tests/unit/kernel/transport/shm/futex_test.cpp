// The futex word: a waiter sleeps while the word holds what it expects, and a
// wake-up (or its timeout) ends the sleep; a word that changed is not slept on.
#include "futex.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace plr::shm::detail {
namespace {

using namespace std::chrono_literals;

TEST(Futex, AWordThatChangedIsNotSleptOn) {
  std::atomic<std::uint32_t> word{1};
  // Expects 0 but finds 1: returns at once, whatever the timeout.
  futex_wait(word, 0, std::chrono::hours(1));
  SUCCEED();
}

TEST(Futex, AWakeEndsTheSleep) {
  std::atomic<std::uint32_t> word{0};
  std::atomic<bool> woke{false};
  std::thread sleeper([&] {
    while (word.load() == 0) futex_wait(word, 0, std::chrono::hours(1));
    woke = true;
  });
  word.store(1);
  futex_wake_all(word);
  sleeper.join();
  EXPECT_TRUE(woke);
}

TEST(Futex, TheTimeoutEndsTheSleep) {
  std::atomic<std::uint32_t> word{0};
  futex_wait(word, 0, 20ms);  // nobody wakes it: only the timeout returns
  EXPECT_EQ(word.load(), 0u);
}

}  // namespace
}  // namespace plr::shm::detail
