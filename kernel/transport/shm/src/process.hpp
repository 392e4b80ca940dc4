// Liveness of a peer process: pidfd when the kernel allows it (one poll, no
// /proc parsing), else kill(pid, 0) + start time from /proc.
#pragma once

#include <atomic>
#include <cstdint>

#include "plr/shm/types.hpp"

namespace plr::shm::detail {

class PeerWatch {
 public:
  PeerWatch() = default;
  // closed: the segment's clean-close flag (may be null).
  PeerWatch(const ProcessStamp& peer, const std::atomic<std::uint32_t>* closed) noexcept;
  PeerWatch(PeerWatch&& o) noexcept;
  PeerWatch& operator=(PeerWatch&& o) noexcept;
  PeerWatch(const PeerWatch&) = delete;
  PeerWatch& operator=(const PeerWatch&) = delete;
  ~PeerWatch();

  // kClosed if the peer closed cleanly, kPeerDead if it is gone.
  Result<void> check() const noexcept;
  static Result<void> check_fn(const void* self) noexcept {
    return static_cast<const PeerWatch*>(self)->check();
  }

 private:
  ProcessStamp peer_{};
  const std::atomic<std::uint32_t>* closed_ = nullptr;
  int pidfd_ = -1;
};

}  // namespace plr::shm::detail
