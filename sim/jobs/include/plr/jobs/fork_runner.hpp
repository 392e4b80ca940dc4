// Runs each job in a child process of its own, forked from this one: the
// child inherits what this process loaded (a robot, a planner, a library)
// and the kinds it registered, runs the job's handler and sends its result
// back over a pipe in a frame. At most `workers` children at once (the
// simulation is single-threaded; a crash takes one job, not the run). A
// child that dies or passes the timeout is killed and its job tried again,
// up to max_attempts in all; then its result is the failure.
#pragma once

#include <cstdint>
#include <filesystem>

#include "plr/jobs/kinds.hpp"
#include "plr/jobs/runner.hpp"

namespace plr::jobs {

struct ForkOptions {
  unsigned workers = 1;
  double timeout_s = 3600;  // wall seconds per attempt
  unsigned max_attempts = 1;
  bool quiet = true;  // a child's stdout goes to /dev/null
  // When set, a child's stderr goes to <log_dir>/<key>.log (Store::logs()).
  std::filesystem::path log_dir;
};

class ForkRunner final : public Runner {
 public:
  ForkRunner(const Kinds& kinds, ForkOptions options) : kinds_(kinds), options_(options) {}
  void run(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo, const Done& done,
           const std::function<bool()>& stop) override;

  // Children started again after one died or timed out, over all runs.
  std::uint64_t retries() const { return retries_; }

 private:
  const Kinds& kinds_;
  ForkOptions options_;
  std::uint64_t retries_ = 0;
};

}  // namespace plr::jobs
