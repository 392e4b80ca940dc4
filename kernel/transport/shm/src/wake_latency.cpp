#include "plr/shm/wake_latency.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <utility>

namespace plr::shm {

Result<WakeLatencyRequest> WakeLatencyRequest::hold(std::int32_t max_us) noexcept {
  if (max_us < 0) return Error::kInvalidArgument;
  const int fd = ::open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
  if (fd < 0) return errno == EACCES || errno == EPERM ? Error::kPermission : Error::kOsError;
  // The device takes the value as a binary 32-bit integer.
  if (::write(fd, &max_us, sizeof max_us) != static_cast<ssize_t>(sizeof max_us)) {
    ::close(fd);
    return Error::kOsError;
  }
  return WakeLatencyRequest(fd, max_us);
}

WakeLatencyRequest::WakeLatencyRequest(WakeLatencyRequest&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), max_us_(other.max_us_) {}

WakeLatencyRequest& WakeLatencyRequest::operator=(WakeLatencyRequest&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    max_us_ = other.max_us_;
  }
  return *this;
}

WakeLatencyRequest::~WakeLatencyRequest() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace plr::shm
