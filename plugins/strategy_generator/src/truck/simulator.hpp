// Where the generator's batches of simulations run: jobs of kind
// sim.action (plr/actions/simulation_job.hpp) on a runner of the job
// engine (in this process, local worker processes, remote workers:
// truck/worker_runner.hpp), their results kept in a store when one is given
// so that a generation killed and started again simulates nothing twice.
#pragma once

#include <plr/expected.hpp>

#include <atomic>
#include <string>
#include <vector>

#include "plr/actions/simulation_job.hpp"
#include "plr/jobs/runner.hpp"
#include "plr/jobs/store.hpp"

namespace plr::generator {

using actions::kEmptyObservation;
using actions::SimOutcome;
using actions::SimRequest;
using actions::StateBytes;

struct Simulated {
  plr::Expected<SimOutcome> outcome = SimOutcome{};
  bool stored = false;  // read from the store, not simulated now
};

// Runs batches of requests. The outcome of request i is the i-th result,
// and it depends only on the request: not on which worker ran it, when, or
// how many there are.
class Simulator {
 public:
  // `runner` must outlive the simulator; `workers`: how many jobs it runs at once.
  Simulator(plr::jobs::Runner& runner, int workers, std::string observation_json)
      : runner_(runner), workers_(workers), observation_json_(std::move(observation_json)) {}

  // The fidelity the jobs ask the workers for (a setting of the run; the
  // results of each level are kept under their own keys).
  void set_fidelity(sim::Fidelity fidelity) { fidelity_ = fidelity; }
  sim::Fidelity fidelity() const { return fidelity_; }

  // The store, if any, is read before and written as each result comes.
  std::vector<Simulated> run(const std::vector<SimRequest>& batch,
                             const plr::jobs::Store* store = nullptr);
  int workers() const { return workers_; }
  // Workers simulating now (for a progress display; any thread).
  int busy() const;

  // The key of a request's result in a store: work_key() in hex.
  static std::string key(const SimRequest& request, sim::Fidelity fidelity);

 private:
  plr::jobs::Runner& runner_;
  int workers_;
  std::string observation_json_;
  sim::Fidelity fidelity_ = sim::Fidelity::kFull;
  std::atomic<int> running_{0};
};

}  // namespace plr::generator
