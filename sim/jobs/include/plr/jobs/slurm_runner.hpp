// Runs jobs as Slurm job arrays (docs/cluster.md). Each batch of jobs not yet
// in the store is written beside the store (batches/<n>.batch, the jobs'
// requests in array order) and submitted as one array per thousand jobs;
// task i runs the program's task command, which reads job i of the batch,
// exits at once when its result is already stored, and otherwise runs it and
// writes its result to the store itself (the store is on a filesystem the
// nodes share). The submitting process follows the store and the scheduler:
// a result that appears is reported; a task that leaves the queue without
// one (failed, timed out, preempted, cancelled) is submitted again, up to
// max_attempts; a stop cancels every array this runner submitted.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "plr/jobs/kinds.hpp"
#include "plr/jobs/runner.hpp"
#include "plr/jobs/store.hpp"
#include "plr/jobs/this_process.hpp"

namespace plr::jobs {

struct SlurmOptions {
  std::string partition;                 // sbatch --partition, when set
  std::string account;                   // sbatch --account, when set
  std::string time_limit;                // sbatch --time per task (e.g. "02:00:00"), when set
  unsigned max_parallel = 0;             // the array's %N; 0: as many as the scheduler gives
  std::vector<std::string> sbatch_args;  // passed to sbatch as they are
  unsigned max_attempts = 3;             // submissions per job, the first included
  double poll_s = 1.0;                   // between looks at the store and squeue
  std::string job_name = "plr";
};

// What the scheduler did, for the report.
struct SlurmStats {
  std::uint64_t arrays = 0;  // sbatch calls
  std::uint64_t tasks = 0;   // array tasks submitted, resubmissions included
  std::uint64_t resubmitted = 0;
  std::map<std::string, std::uint64_t> ended_without_result;  // by Slurm state
  double first_running_s = -1;  // first submission to the first task seen running
  double wall_s = 0;
};

// The stats as the reports write them.
nlohmann::json to_json(const SlurmStats& stats);

class SlurmRunner final : public Runner {
 public:
  // `task_command`: the program and arguments that run one array task; the
  // runner appends the batch file (see run_array_task).
  SlurmRunner(const Store& store, std::vector<std::string> task_command, SlurmOptions options)
      : store_(store), command_(std::move(task_command)), options_(std::move(options)) {}
  void run(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo, const Done& done,
           const std::function<bool()>& stop) override;

  const SlurmStats& stats() const { return stats_; }

 private:
  const Store& store_;
  std::vector<std::string> command_;
  SlurmOptions options_;
  SlurmStats stats_;
};

// The task side, in the program named by task_command: runs job
// $SLURM_ARRAY_TASK_ID of `batch_file` with `kinds` and stores its result,
// its stderr going to the store's log of that job. `prepare` loads what the
// job needs, only when it is to run. Returns the exit code.
int run_array_task(const Kinds& kinds, const std::filesystem::path& batch_file,
                   const std::function<void()>& prepare = {});

}  // namespace plr::jobs
