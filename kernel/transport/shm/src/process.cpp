#include "process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/syscall.h>
#include <unistd.h>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <utility>

namespace plr::shm {

namespace {

struct StatFields {
  char state = 0;
  std::uint64_t start_time = 0;
};

// /proc/<pid>/stat: "pid (comm) state ppid ... starttime(22) ..."; comm may
// contain spaces and parentheses, so parse from the last ')'.
bool read_stat(pid_t pid, StatFields& out) noexcept {
  char path[64];
  std::snprintf(path, sizeof path, "/proc/%d/stat", static_cast<int>(pid));
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  char buf[1024];
  const ssize_t n = ::read(fd, buf, sizeof buf - 1);
  ::close(fd);
  if (n <= 0) return false;
  buf[n] = '\0';
  const char* p = std::strrchr(buf, ')');
  if (p == nullptr || p[1] != ' ') return false;
  p += 2;
  out.state = *p;
  // After ')' come fields 3.. ; starttime is field 22, i.e. 19 spaces on.
  for (int field = 3; field < 22; ++field) {
    p = std::strchr(p, ' ');
    if (p == nullptr) return false;
    ++p;
  }
  char* end = nullptr;
  out.start_time = std::strtoull(p, &end, 10);
  return end != p;
}

}  // namespace

ProcessStamp ProcessStamp::self() noexcept {
  return of(::getpid());
}

ProcessStamp ProcessStamp::of(pid_t pid) noexcept {
  StatFields f;
  if (pid <= 0 || !read_stat(pid, f)) return ProcessStamp{pid, 0};
  return ProcessStamp{pid, f.start_time};
}

bool ProcessStamp::alive() const noexcept {
  if (pid <= 0) return false;
  if (::kill(pid, 0) != 0 && errno == ESRCH) return false;
  StatFields f;
  if (!read_stat(pid, f)) return false;
  if (f.state == 'Z' || f.state == 'X') return false;
  return start_time == 0 || f.start_time == start_time;
}

namespace detail {

PeerWatch::PeerWatch(const ProcessStamp& peer, const std::atomic<std::uint32_t>* closed) noexcept
    : peer_(peer), closed_(closed) {
  if (peer_.pid <= 0) return;
  const int fd = static_cast<int>(::syscall(SYS_pidfd_open, peer_.pid, 0));
  if (fd < 0) return;
  // The pid may have been reused before we opened it: keep the fd only if it
  // names the stamped process.
  if (ProcessStamp::of(peer_.pid).start_time == peer_.start_time) {
    pidfd_ = fd;
  } else {
    ::close(fd);
    peer_.pid = -1;  // already gone
  }
}

PeerWatch::PeerWatch(PeerWatch&& o) noexcept
    : peer_(o.peer_), closed_(o.closed_), pidfd_(std::exchange(o.pidfd_, -1)) {}

PeerWatch& PeerWatch::operator=(PeerWatch&& o) noexcept {
  if (this != &o) {
    if (pidfd_ >= 0) ::close(pidfd_);
    peer_ = o.peer_;
    closed_ = o.closed_;
    pidfd_ = std::exchange(o.pidfd_, -1);
  }
  return *this;
}

PeerWatch::~PeerWatch() {
  if (pidfd_ >= 0) ::close(pidfd_);
}

Result<void> PeerWatch::check() const noexcept {
  if (closed_ != nullptr && closed_->load(std::memory_order_acquire) != 0) {
    return Error::kClosed;
  }
  if (peer_.pid == 0) return {};
  if (pidfd_ >= 0) {
    // A pidfd turns readable when the process exits (zombies included).
    pollfd p{pidfd_, POLLIN, 0};
    if (::poll(&p, 1, 0) == 0) return {};
    return Error::kPeerDead;
  }
  if (!peer_.alive()) return Error::kPeerDead;
  return {};
}

}  // namespace detail
}  // namespace plr::shm
