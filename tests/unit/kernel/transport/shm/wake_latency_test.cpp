// The PM QoS request is really held: the kernel's aggregate CPU latency target
// (read back from the device) is the request while it lives, and returns to
// what it was once the request is gone.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <optional>

#include "plr/shm/wake_latency.hpp"

namespace plr::shm {
namespace {

std::optional<std::int32_t> current_target() {
  const int fd = ::open("/dev/cpu_dma_latency", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  std::int32_t v = 0;
  const bool ok = ::read(fd, &v, sizeof v) == static_cast<ssize_t>(sizeof v);
  ::close(fd);
  return ok ? std::optional(v) : std::nullopt;
}

TEST(WakeLatency, ARequestHoldsTheTargetWhileItLives) {
  const auto before = current_target();
  if (!before) GTEST_SKIP() << "no readable /dev/cpu_dma_latency on this machine";
  auto r = WakeLatencyRequest::hold(0);
  if (!r && r.error() == Error::kPermission)
    GTEST_SKIP() << "/dev/cpu_dma_latency is not writable by this user (root's by default)";
  ASSERT_TRUE(r) << to_string(r.error());
  EXPECT_EQ(current_target(), 0);
  {
    WakeLatencyRequest moved = std::move(*r);
    EXPECT_EQ(moved.max_us(), 0);
    EXPECT_EQ(current_target(), 0);
  }
  EXPECT_EQ(current_target(), before);
}

TEST(WakeLatency, ANegativeBoundIsRefused) {
  auto r = WakeLatencyRequest::hold(-1);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), Error::kInvalidArgument);
}

}  // namespace
}  // namespace plr::shm
