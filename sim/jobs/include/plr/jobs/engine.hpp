// The job engine: runs a batch of jobs on a runner, skipping those whose
// result the store already holds and storing each new result as it comes,
// so that a run stopped at any moment and started again runs only what is
// missing. docs/jobs.md.
#pragma once

#include <plr/expected.hpp>

#include <cstddef>
#include <functional>
#include <vector>

#include "plr/jobs/job.hpp"
#include "plr/jobs/runner.hpp"
#include "plr/jobs/store.hpp"

namespace plr::jobs {

struct RunOptions {
  // Once the store is read, before any job runs: how many results it
  // held and how many jobs are to run.
  std::function<void(std::size_t stored, std::size_t to_run)> on_start;
  // Asked between events; true ends the run early (signals.hpp).
  std::function<bool()> stop;
  // Each result as it comes and is stored (not those read from the store).
  std::function<void(const Result&)> on_done;
};

struct Outcome {
  std::vector<Result> results;  // in the jobs' order
  std::size_t stored = 0;       // read from the store
  std::size_t ran = 0;          // run now
  bool stopped = false;         // ended early: the results not run say so
};

// `store` may be null: nothing is read or kept. The error is about the
// batch (a key that is no file name, a key twice, a result that cannot be
// written), not about a job: a job's failure is its result.
plr::Expected<Outcome> run(const std::vector<Job>& jobs, Runner& runner, const Store* store,
                           const RunOptions& options = {});

}  // namespace plr::jobs
