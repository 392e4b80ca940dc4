// The generator's runner of the job engine: local worker processes (the
// plr_sim_worker program, each a ProcessRunner of one worker: restart of a
// dead worker, timeout, retry) and remote workers (a call of a kernel's
// `sim/simulate` service carrying the job engine's messages, served by the
// simulation_worker plug-in), all fed from one queue: a job goes to
// whichever slot is free. A remote call that fails (no provider, its kernel
// gone, a timeout) hands its job out anew, so the results are those of the
// jobs alone.
#pragma once

#include <plr/expected.hpp>

#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "plr/jobs/process_runner.hpp"
#include "plr/jobs/runner.hpp"

namespace plr::generator {

// A job sent to a remote worker: a service call in flight.
class RemoteCall {
 public:
  virtual ~RemoteCall() = default;
  // Whether the answer, or the call's failure, has come (any thread).
  virtual bool done() const = 0;
  // The answer (a JobReply, plr/jobs/messages.hpp), or why the call failed.
  virtual plr::Expected<plr::jobs::Bytes> take() = 0;
};
// Sends a JobRequest (plr/jobs/messages.hpp) to some remote worker.
using RemoteSend = std::function<std::unique_ptr<RemoteCall>(const plr::jobs::Bytes& request)>;

struct WorkerOptions {
  plr::jobs::ProcessOptions local;  // local.workers processes of local.command (0: none)
  // Jobs kept in flight with remote workers, and how they are sent.
  unsigned remote_workers = 0;
  RemoteSend remote_send;
  // A remote slot whose call failed rests this long before it takes work again.
  double remote_retry_s = 2.0;
};

class WorkerRunner final : public plr::jobs::Runner {
 public:
  // Starts the local workers; an error names the program and the cause.
  static plr::Expected<std::unique_ptr<WorkerRunner>> create(WorkerOptions options);
  ~WorkerRunner() override;

  void run(const std::vector<plr::jobs::Job>& jobs, const std::vector<std::size_t>& todo,
           const Done& done, const std::function<bool()>& stop) override;

  int workers() const { return static_cast<int>(local_.size() + options_.remote_workers); }
  // Process ids of the local workers (tests kill one mid-run).
  std::vector<pid_t> pids() const;
  // Local workers started again after dying.
  std::uint64_t restarts() const;
  // Jobs the remote workers answered, and remote calls that failed.
  std::uint64_t remote_done() const { return remote_done_.load(std::memory_order_relaxed); }
  std::uint64_t remote_failures() const { return remote_failures_.load(std::memory_order_relaxed); }

 private:
  struct Batch;
  explicit WorkerRunner(WorkerOptions options) : options_(std::move(options)) {}
  void serve_local(plr::jobs::ProcessRunner& local, Batch& batch);
  void serve_remote(Batch& batch);

  WorkerOptions options_;
  std::vector<std::unique_ptr<plr::jobs::ProcessRunner>> local_;
  std::atomic<std::uint64_t> remote_done_{0}, remote_failures_{0}, next_id_{1};
};

}  // namespace plr::generator
