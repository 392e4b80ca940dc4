// Simulation workers: processes on this machine (the plr_sim_worker
// program), each fed one request at a time over a pipe in the frames of
// plr/actions/simulation_job.hpp; and workers on other machines, reached by
// a call of their kernel's `sim/simulate` service (the simulation_worker
// plug-in) carrying the same frames. A batch's requests go to whichever
// worker is free; a worker that dies (killed, crashed, its kernel gone) is
// started again or left to come back, and its request handed out anew, so
// the results are those of the requests alone.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "truck/simulator.hpp"

namespace plr::generator {

// A job sent to a worker on another machine: a service call in flight.
class RemoteJob {
 public:
  virtual ~RemoteJob() = default;
  // Whether the answer, or the call's failure, has come (any thread).
  virtual bool done() const = 0;
  // The answer's frame (without a size), or why the call failed.
  virtual plr::Expected<std::vector<std::uint8_t>> take() = 0;
};
// Sends the job frame `fbb` holds to some remote worker.
using RemoteSend = std::function<std::unique_ptr<RemoteJob>(const flatbuffers::FlatBufferBuilder&)>;

struct WorkerPoolOptions {
  std::string command;  // the worker program
  int workers = 2;      // local processes
  std::string observation_json = "{}";
  // A request whose worker died this many times is given up (an error): a
  // request that kills every worker must not stop the generator forever.
  int max_attempts = 3;
  // Jobs kept in flight with remote workers, and how they are sent.
  int remote_workers = 0;
  RemoteSend remote_send;
  // A remote slot whose call failed (no provider, its kernel gone, a
  // timeout) rests this long before it takes work again.
  double remote_retry_s = 2.0;
};

class WorkerPool final : public Simulator {
 public:
  // Starts the workers; an error names the program and the cause.
  static plr::Expected<std::unique_ptr<WorkerPool>> create(const WorkerPoolOptions& options);
  ~WorkerPool() override;

  std::vector<plr::Expected<SimOutcome>> run(const std::vector<SimRequest>& batch) override;
  int workers() const override { return options_.workers + options_.remote_workers; }
  int busy() const override { return busy_.load(std::memory_order_relaxed); }

  // Process ids of the workers (tests kill one mid-run).
  std::vector<pid_t> pids() const;
  // Workers started again after dying.
  std::uint64_t restarts() const { return restarts_.load(std::memory_order_relaxed); }
  // Jobs the remote workers answered, and remote calls that failed.
  std::uint64_t remote_done() const { return remote_done_.load(std::memory_order_relaxed); }
  std::uint64_t remote_failures() const { return remote_failures_.load(std::memory_order_relaxed); }

 private:
  struct Worker;
  struct RemoteSlot;
  explicit WorkerPool(WorkerPoolOptions options);
  plr::Status spawn(Worker& w);
  void bury(Worker& w);

  WorkerPoolOptions options_;
  std::vector<std::unique_ptr<Worker>> workers_;
  std::vector<std::unique_ptr<RemoteSlot>> remote_;
  std::atomic<int> busy_{0};
  std::atomic<std::uint64_t> restarts_{0};
  std::atomic<std::uint64_t> remote_done_{0}, remote_failures_{0};
  std::uint64_t next_id_ = 1;
};

}  // namespace plr::generator
