// The job engine's one pool of worker processes. A worker serves one job at
// a time over its stdin and stdout (worker.hpp). It is either a program
// started with posix_spawn (it loads what it needs once: a robot, a planner)
// or a child forked from this process that serves `kinds` (it inherits what
// this process loaded). With process_per_job each job gets a fresh worker: a
// forked one sees this process as it is when the job starts, and a crash
// takes one job. A worker that dies, sends garbage or passes the timeout is
// killed and started again, and its job handed out anew, up to max_attempts
// in all; then its result is the failure, naming the cause (and the log).
#pragma once

#include <plr/expected.hpp>

#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "plr/jobs/kinds.hpp"
#include "plr/jobs/runner.hpp"

namespace plr::jobs {

struct ProcessOptions {
  std::vector<std::string> command;  // the worker program and its arguments, or
  const Kinds* kinds = nullptr;      // when set, forked workers serving these
  unsigned workers = 1;
  double timeout_s = 3600;  // wall seconds per attempt
  unsigned max_attempts = 3;
  bool process_per_job = false;
  // When set, a forked worker's stderr during a job goes to <log_dir>/<key>.log.
  std::filesystem::path log_dir;
};

class ProcessRunner final : public Runner {
 public:
  // Checks the options; starts a program's workers at once (an error names
  // the program and the cause), forked ones when there is work.
  static plr::Expected<std::unique_ptr<ProcessRunner>> create(ProcessOptions options);
  ~ProcessRunner() override;

  void run(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo, const Done& done,
           const std::function<bool()>& stop) override;

  // The workers' process ids (-1: down).
  std::vector<pid_t> pids() const;
  // Workers started again after one died, timed out or was stopped.
  std::uint64_t restarts() const { return restarts_; }
  // Jobs handed out again after their worker was lost.
  std::uint64_t retries() const { return retries_; }

 private:
  struct Worker;
  explicit ProcessRunner(ProcessOptions options);
  plr::Status start(Worker& w);
  void bury(Worker& w, int* status = nullptr);

  ProcessOptions options_;
  std::vector<std::unique_ptr<Worker>> workers_;
  std::uint64_t restarts_ = 0, retries_ = 0, next_id_ = 1;
};

}  // namespace plr::jobs
