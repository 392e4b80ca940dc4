// plr_sim_worker: a simulation worker of the strategy generator, started
// by the job engine's ProcessRunner. Serves jobs of kind sim.action
// (plr/actions/simulation_job.hpp) over stdin and stdout (plr/jobs/worker.hpp).
// With --slurm-task it is instead one array task of a generation on Slurm:
// it makes one world's strategy (kind generator.strategy,
// truck/strategy_job.hpp) and stores it (docs/cluster.md).
#include <CLI/CLI.hpp>

#include "plr/actions/simulation_job.hpp"
#include "plr/jobs/slurm_runner.hpp"
#include "plr/jobs/worker.hpp"
#include "truck/strategy_job.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "A simulation worker of the strategy generator: serves jobs of kind sim.action on stdin "
      "and stdout; started by the generator"};
  std::string slurm_task;
  app.add_option("--slurm-task", slurm_task, "Run one Slurm array task of this batch file")
      ->group("");  // what a task runs, not for people
  CLI11_PARSE(app, argc, argv);
  plr::jobs::Kinds kinds;
  plr::actions::add_sim_action(kinds);
  if (!slurm_task.empty()) {
    plr::generator::add_strategy_job(kinds);
    return plr::jobs::run_array_task(kinds, slurm_task);
  }
  return plr::jobs::serve_jobs(kinds);
}
