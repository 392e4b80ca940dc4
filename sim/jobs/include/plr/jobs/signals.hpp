// Ctrl-C and SIGTERM during a run of jobs: while a StopOnSignals lives, they
// ask the run to stop (RunOptions::stop) instead of ending the process, so
// that the results finished so far stay in the store.
#pragma once

#include <signal.h>

namespace plr::jobs {

class StopOnSignals {
 public:
  StopOnSignals();
  ~StopOnSignals();
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;

  // Whether SIGINT or SIGTERM came since construction.
  bool operator()() const;
  // The signal that came (0: none).
  int signal() const;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

}  // namespace plr::jobs
