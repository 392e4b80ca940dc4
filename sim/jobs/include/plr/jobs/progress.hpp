// A run of jobs as a command-line program shows it: a progress bar on
// stderr, one line redrawn on a terminal, a line at every tenth otherwise
// (a log file).
#pragma once

#include <plr/expected.hpp>

#include <chrono>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "plr/jobs/engine.hpp"

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

// run() for a program named `name`: says how many results `store` already
// holds, calls `prepare` when any job is to run (to load what the jobs
// inherit), shows the bar, and stops on Ctrl-C or SIGTERM (StopOnSignals),
// keeping what finished.
plr::Expected<Outcome> run_with_progress(const std::string& name, const std::vector<Job>& jobs,
                                         Runner& runner, const Store& store,
                                         const std::function<void()>& prepare = {});

}  // namespace plr::jobs
