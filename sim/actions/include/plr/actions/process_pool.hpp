// Long offline jobs made of many independent runs (benchmarks, the
// evaluation): each run in a child process of its own, forked, at most
// `workers` at once (the simulation is single-threaded; a crash takes one
// run, not the job), its result written atomically to a file of its own as
// it finishes. A run whose file exists is not run again, so a job stopped
// at any moment and started again runs only what is missing.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace plr::actions {

struct PoolRun {
  std::string name;  // for progress lines
  std::filesystem::path result;
};

struct PoolOptions {
  unsigned workers = 1;
  double timeout_s = 3600;  // wall seconds; a run past it is killed
  bool quiet = true;        // the children's stdout goes to /dev/null
};

// The runs whose result file is missing.
std::vector<PoolRun> missing_runs(const std::vector<PoolRun>& runs);

// Runs `work(i)` for each runs[i] in a child process and writes what it
// returns to runs[i].result. A child that exits without a result, dies or
// passes the timeout leaves `failed(i, why, wall_s)` there instead. `done(i)`
// is called in this process as each run ends. Returns on the first error
// writing a result file (its message), after killing the running children.
std::string run_in_processes(
    const std::vector<PoolRun>& runs, const PoolOptions& options,
    const std::function<nlohmann::json(std::size_t)>& work,
    const std::function<nlohmann::json(std::size_t, const std::string&, double)>& failed,
    const std::function<void(std::size_t)>& done = {});

}  // namespace plr::actions
