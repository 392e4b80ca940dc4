// plr_sim_worker: a simulation worker of the strategy generator, started
// by the job engine's ProcessRunner. Serves jobs of kind sim.action
// (plr/actions/simulation_job.hpp) over stdin and stdout (plr/jobs/worker.hpp).
#include <CLI/CLI.hpp>

#include "plr/actions/simulation_job.hpp"
#include "plr/jobs/worker.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "A simulation worker of the strategy generator: serves jobs of kind sim.action on stdin "
      "and stdout; started by the generator"};
  CLI11_PARSE(app, argc, argv);
  plr::jobs::Kinds kinds;
  plr::actions::add_sim_action(kinds);
  return plr::jobs::serve_jobs(kinds);
}
