// The job engine's runners side by side on the same batch: child processes
// of this one (local) and a Slurm job array on a single-node cluster this
// benchmark starts from Debian's packages (needs root; tests/common/
// slurm_cluster.hpp). Each job sleeps a fixed time, so what is left of the
// wall time is the runner's: per job, and from the first submission to the
// first task running.
//
//   bench_jobs [--quick] [--json] [--jobs N] [--task-ms MS] [--rounds R]
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "bench_cli.hpp"
#include "bench_util.hpp"
#include "plr/jobs/engine.hpp"
#include "plr/jobs/process_runner.hpp"
#include "plr/jobs/slurm_runner.hpp"
#include "slurm_cluster.hpp"

namespace {

namespace fs = std::filesystem;
namespace jobs = plr::jobs;
using Clock = std::chrono::steady_clock;

constexpr const char* kKind = "bench.sleep";

jobs::Kinds sleep_kind() {
  jobs::Kinds kinds;
  kinds.add(kKind, [](const jobs::Bytes& input) -> plr::Expected<jobs::Bytes> {
    std::this_thread::sleep_for(std::chrono::milliseconds(std::stol(jobs::to_text(input))));
    return input;
  });
  return kinds;
}

std::vector<jobs::Job> batch(unsigned n, unsigned task_ms) {
  std::vector<jobs::Job> all;
  for (unsigned i = 0; i < n; ++i)
    all.push_back({kKind, fmt::format("job-{:04}", i), jobs::to_bytes(std::to_string(task_ms))});
  return all;
}

struct Round {
  double wall_s = 0, per_job_s = 0, first_running_s = -1;
  bool ok = false;
};

// Runs the batch into a fresh store; per job: the wall time past what
// `workers` sleeping jobs would take.
Round measure(jobs::Runner& runner, const fs::path& store_dir, unsigned n, unsigned task_ms,
              unsigned workers) {
  fs::remove_all(store_dir);
  auto store = jobs::Store::open(store_dir);
  Round r;
  if (!store) return r;
  const auto t0 = Clock::now();
  auto outcome = jobs::run(batch(n, task_ms), runner, &*store);
  r.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  const double ideal = std::ceil(static_cast<double>(n) / workers) * task_ms / 1000.0;
  r.per_job_s = (r.wall_s - ideal) / n;
  r.ok = outcome && !outcome->stopped && outcome->ran == n;
  if (r.ok)
    for (const auto& result : outcome->results) r.ok = r.ok && result.ok;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The job engine's local and Slurm runners on one batch of sleeping jobs"};
  bool json = false, quick = false;
  unsigned n = 40, task_ms = 500, rounds = 3;
  std::string task_batch;
  plr::bench::add_json_flag(app, json);
  plr::bench::add_quick_flag(app, quick, "16 jobs, 2 rounds");
  app.add_option("--jobs", n, "Jobs per batch")->check(CLI::Range(1u, 1000u));
  app.add_option("--task-ms", task_ms, "How long each job sleeps")->check(CLI::Range(0u, 60000u));
  app.add_option("--rounds", rounds, "Batches per runner (medians are reported)")
      ->check(CLI::Range(1u, 50u));
  app.add_option("--task", task_batch, "(Slurm's array task: run one job of this batch file)");
  plr::bench::parse_or_exit(app, argc, argv);
  const jobs::Kinds kinds = sleep_kind();
  if (!task_batch.empty()) return jobs::run_array_task(kinds, task_batch);
  if (quick) {
    n = 16;
    rounds = 2;
  }

  const unsigned workers = std::max(1u, std::thread::hardware_concurrency());
  const fs::path dir = fs::temp_directory_path() / fmt::format("plr-bench-jobs-{}", ::getpid());
  plr::bench::Progress progress("bench_jobs", 2 * rounds);

  std::vector<double> local_wall, local_per_job;
  auto local = jobs::ProcessRunner::create({{}, &kinds, workers, 600, 1, true, {}});
  if (!local) {
    std::fprintf(stderr, "bench_jobs: %s\n", local.error().message.c_str());
    return 1;
  }
  for (unsigned i = 0; i < rounds; ++i) {
    const Round r = measure(**local, dir / "local", n, task_ms, workers);
    if (!r.ok) {
      std::fprintf(stderr, "bench_jobs: a local job failed\n");
      return 1;
    }
    local_wall.push_back(r.wall_s);
    local_per_job.push_back(r.per_job_s);
    progress.step("local");
  }

  plr::slurm_test::SlurmCluster cluster;
  const std::string why = cluster.start();
  std::vector<double> slurm_wall, slurm_per_job, first_running;
  if (why.empty()) {
    char self[4096] = {};
    const ssize_t len = ::readlink("/proc/self/exe", self, sizeof self - 1);
    const std::string exe(self, len > 0 ? static_cast<std::size_t>(len) : 0);
    for (unsigned i = 0; i < rounds; ++i) {
      jobs::SlurmOptions options;
      options.max_parallel = workers;
      options.poll_s = 0.2;
      options.job_name = "bench_jobs";
      fs::remove_all(dir / "slurm");
      auto store = jobs::Store::open(dir / "slurm");
      if (!store) return 1;
      jobs::SlurmRunner slurm(*store, {exe, "--task"}, options);
      const Round r = measure(slurm, dir / "slurm", n, task_ms, workers);
      if (!r.ok) {
        std::fprintf(stderr, "bench_jobs: a Slurm task failed (logs in %s)\n",
                     (dir / "slurm").c_str());
        return 1;
      }
      slurm_wall.push_back(r.wall_s);
      slurm_per_job.push_back(r.per_job_s);
      first_running.push_back(slurm.stats().first_running_s);
      progress.step("slurm");
    }
  } else {
    std::fprintf(stderr, "bench_jobs: no Slurm figures: %s\n", why.c_str());
  }
  progress.finish();
  cluster.stop();
  fs::remove_all(dir);

  using plr::bench::median;
  const double ratio = median(slurm_per_job) / median(local_per_job);
  if (json) {
    nlohmann::json j{
        {"jobs", n},
        {"task_ms", task_ms},
        {"workers", workers},
        {"rounds", rounds},
        {"local", {{"wall_s", median(local_wall)}, {"overhead_per_job_s", median(local_per_job)}}}};
    if (!slurm_wall.empty())
      j["slurm"] = {{"wall_s", median(slurm_wall)},
                    {"overhead_per_job_s", median(slurm_per_job)},
                    {"submit_to_first_running_s", median(first_running)},
                    {"overhead_ratio_to_local", ratio}};
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("%u jobs of %u ms on %u workers, medians of %u rounds\n\n", n, task_ms, workers,
              rounds);
  std::printf("%-8s %10s %22s %28s\n", "runner", "wall s", "overhead per job s",
              "submit to first running s");
  std::printf("%-8s %10.2f %22.3f %28s\n", "local", median(local_wall), median(local_per_job), "-");
  if (!slurm_wall.empty())
    std::printf("%-8s %10.2f %22.3f %28.2f\n", "slurm", median(slurm_wall), median(slurm_per_job),
                median(first_running));
  if (!slurm_wall.empty())
    std::printf("\nSlurm's overhead per job: %.1fx the local runner's\n", ratio);
  return 0;
}
