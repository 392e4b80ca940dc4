// A Linux PM QoS request on how long an idle CPU may take to wake up
// (/dev/cpu_dma_latency), held while the object lives.
//
// Why: a blocked reader's core sits idle; the futex wake-up that hands it a
// message pays that idle state's exit. On a VM whose idle state is a real halt
// (no guest halt-polling), that exit dominates a cross-core wake-up: 13-16 us
// against 2-3 us with a request of 0, which keeps idle cores polling. The
// price is power and a busy-looking CPU on idle cores: a deployment choice
// (config `cpu_wake_latency_us`), not a default.
#pragma once

#include <cstdint>

#include "plr/shm/types.hpp"

namespace plr::shm {

class WakeLatencyRequest {
 public:
  // kPermission without write access to the device (it is root's by default).
  static Result<WakeLatencyRequest> hold(std::int32_t max_us) noexcept;

  WakeLatencyRequest(WakeLatencyRequest&& other) noexcept;
  WakeLatencyRequest& operator=(WakeLatencyRequest&& other) noexcept;
  WakeLatencyRequest(const WakeLatencyRequest&) = delete;
  WakeLatencyRequest& operator=(const WakeLatencyRequest&) = delete;
  ~WakeLatencyRequest();

  std::int32_t max_us() const noexcept { return max_us_; }

 private:
  WakeLatencyRequest(int fd, std::int32_t max_us) noexcept : fd_(fd), max_us_(max_us) {}
  int fd_ = -1;  // the request lasts as long as this descriptor is open
  std::int32_t max_us_ = 0;
};

}  // namespace plr::shm
