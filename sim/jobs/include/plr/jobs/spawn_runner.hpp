// Runs jobs on worker programs it starts (posix_spawn) and keeps: each
// serves one job at a time over its stdin and stdout (worker.hpp), so a
// program that loads much (a robot, a planner) loads it once. A worker
// that dies, sends garbage or passes the timeout is killed and started
// again, and its job handed out anew, up to max_attempts in all; then its
// result is the failure.
#pragma once

#include <plr/expected.hpp>

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "plr/jobs/runner.hpp"

namespace plr::jobs {

struct SpawnOptions {
  std::vector<std::string> command;  // the worker program and its arguments
  unsigned workers = 1;
  double timeout_s = 3600;  // wall seconds per attempt
  unsigned max_attempts = 3;
};

class SpawnRunner final : public Runner {
 public:
  // Starts the workers; an error names the program and the cause.
  static plr::Expected<std::unique_ptr<SpawnRunner>> create(SpawnOptions options);
  ~SpawnRunner() override;

  void run(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo, const Done& done,
           const std::function<bool()>& stop) override;

  // The workers' process ids (-1: down).
  std::vector<pid_t> pids() const;
  // Workers started again after one died, timed out or was stopped.
  std::uint64_t restarts() const { return restarts_; }

 private:
  struct Worker;
  explicit SpawnRunner(SpawnOptions options);
  plr::Status spawn(Worker& w);
  void bury(Worker& w);

  SpawnOptions options_;
  std::vector<std::unique_ptr<Worker>> workers_;
  std::uint64_t restarts_ = 0, next_id_ = 1;
};

}  // namespace plr::jobs
