#include "segment_watchdog.hpp"

#include <plr/shm/segments.hpp>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cerrno>
#include <csignal>

namespace plr::kernel {

SegmentWatchdog::SegmentWatchdog(const std::string& run_id) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return;
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[1]);
    // Not the terminal's nor a caller's pipe: whoever reads main's output
    // sees its end when main ends.
    if (const int null = ::open("/dev/null", O_RDWR); null >= 0)
      for (int fd : {0, 1, 2}) ::dup2(null, fd);
    // Nothing else of main's stays open in it (the --log pipe and file).
    if (fds[0] > 3) ::close_range(3, static_cast<unsigned>(fds[0]) - 1, 0);
    ::close_range(static_cast<unsigned>(fds[0]) + 1, ~0U, 0);
    ::setsid();  // Ctrl-C of the terminal is for main, not for this
    for (int s : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) std::signal(s, SIG_IGN);
    char c = 0;
    ssize_t n = 0;
    while ((n = ::read(fds[0], &c, 1)) < 0 && errno == EINTR) {
    }
    if (n == 0) {
      // Hosts die with main (PR_SET_PDEATHSIG); one may still be making a segment.
      (void)shm::remove_run_segments(run_id);
      ::sleep(1);
      (void)shm::remove_run_segments(run_id);
    }
    ::_exit(0);
  }
  ::close(fds[0]);
  if (pid < 0) {
    ::close(fds[1]);
    return;
  }
  fd_ = fds[1];
  pid_ = pid;
}

SegmentWatchdog::~SegmentWatchdog() {
  if (fd_ < 0) return;
  const char done = 1;
  (void)!::write(fd_, &done, 1);
  ::close(fd_);
  ::waitpid(pid_, nullptr, 0);
}

}  // namespace plr::kernel
