// spin_until: true as soon as the flag is set, false once the budget is spent.
#include <plr/spin_wait.hpp>

#include <gtest/gtest.h>

#include <thread>

namespace plr {
namespace {

using namespace std::chrono_literals;

TEST(SpinWait, ASetFlagNeedsNoBudget) {
  const std::atomic<bool> flag{true};
  EXPECT_TRUE(spin_until(flag, 0ns));
}

TEST(SpinWait, AFlagNobodySetsSpendsTheBudget) {
  const std::atomic<bool> flag{false};
  EXPECT_FALSE(spin_until(flag, 0ns));
  EXPECT_FALSE(spin_until(flag, 100us));
}

TEST(SpinWait, AFlagSetByAnotherThreadEndsTheSpin) {
  std::atomic<bool> flag{false};
  std::thread setter([&] { flag.store(true, std::memory_order_release); });
  // A budget no machine runs out of before the thread is scheduled.
  EXPECT_TRUE(spin_until(flag, 60s));
  setter.join();
}

}  // namespace
}  // namespace plr
