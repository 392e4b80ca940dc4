// A process of its own that removes a run's shared memory when the main
// process dies, whatever kills it (kill -9 of main and hosts together left
// every segment behind until the next run). It waits on a pipe only main
// writes to: a byte means main cleaned up itself, end-of-file that it died.
#pragma once

#include <sys/types.h>
#include <string>

namespace plr::kernel {

class SegmentWatchdog {
 public:
  // Forks: make it while the process has one thread, so the child may run
  // ordinary code. Without a pipe or a fork there is no watchdog.
  explicit SegmentWatchdog(const std::string& run_id);
  // Main removed the segments: the watchdog ends at once.
  ~SegmentWatchdog();
  SegmentWatchdog(const SegmentWatchdog&) = delete;
  SegmentWatchdog& operator=(const SegmentWatchdog&) = delete;

 private:
  int fd_ = -1;
  pid_t pid_ = -1;
};

}  // namespace plr::kernel
