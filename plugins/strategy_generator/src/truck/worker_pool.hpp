// Simulation workers: processes on this machine (the plr_sim_worker
// program), each fed one request at a time over a pipe in the frames of
// sim_work.hpp. A batch's requests go to whichever worker is free; a worker
// that dies (killed, crashed) is started again and its request handed out
// anew, so the results are those of the requests alone.
//
// The frames are the only contract: anything that carries them to a worker
// and back (a socket, a kernel service over DDS) can stand in for the pipe.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "truck/action_runner.hpp"

namespace plr::generator {

struct WorkerPoolOptions {
  std::string command;  // the worker program
  int workers = 2;
  std::string observation_json = "{}";
  // A request whose worker died this many times is given up (an error): a
  // request that kills every worker must not stop the generator forever.
  int max_attempts = 3;
};

class WorkerPool final : public Simulator {
 public:
  // Starts the workers; an error names the program and the cause.
  static plr::Expected<std::unique_ptr<WorkerPool>> create(const WorkerPoolOptions& options);
  ~WorkerPool() override;

  std::vector<plr::Expected<SimOutcome>> run(const std::vector<SimRequest>& batch) override;
  int workers() const override { return options_.workers; }
  int busy() const override { return busy_.load(std::memory_order_relaxed); }

  // Process ids of the workers (tests kill one mid-run).
  std::vector<pid_t> pids() const;
  // Workers started again after dying.
  std::uint64_t restarts() const { return restarts_.load(std::memory_order_relaxed); }

 private:
  struct Worker;
  explicit WorkerPool(WorkerPoolOptions options);
  plr::Status spawn(Worker& w);
  void bury(Worker& w);

  WorkerPoolOptions options_;
  std::vector<std::unique_ptr<Worker>> workers_;
  std::atomic<int> busy_{0};
  std::atomic<std::uint64_t> restarts_{0};
  std::uint64_t next_id_ = 1;
};

}  // namespace plr::generator
