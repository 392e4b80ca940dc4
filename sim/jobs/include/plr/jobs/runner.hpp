// What runs jobs: in this process, in child processes, on workers
// elsewhere (a cluster's scheduler). The engine (engine.hpp) hands a runner
// the jobs whose results are not stored, and stores what it reports.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "plr/jobs/job.hpp"

namespace plr::jobs {

class Runner {
 public:
  virtual ~Runner() = default;
  // Called in the thread that called run(), once per job, as each ends.
  using Done = std::function<void(std::size_t index, Result result)>;
  // Runs jobs[i] for each i in `todo`, reporting each through `done`.
  // Returns once all are reported, or soon after `stop()` turns true, with
  // the jobs still running ended and not reported.
  virtual void run(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                   const Done& done, const std::function<bool()>& stop) = 0;
};

}  // namespace plr::jobs
