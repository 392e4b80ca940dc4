// A progress bar on stderr for a run of jobs: one line redrawn on a
// terminal, a line at every tenth otherwise (a log file).
#pragma once

#include <chrono>
#include <cstddef>
#include <string>

namespace plr::jobs {

class ProgressBar {
 public:
  ProgressBar(std::string name, std::size_t total);
  // One more job done; `what` names it.
  void step(const std::string& what);
  // Ends the redrawn line.
  void finish();

 private:
  std::string name_;
  std::size_t total_, done_ = 0;
  bool tty_;
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace plr::jobs
