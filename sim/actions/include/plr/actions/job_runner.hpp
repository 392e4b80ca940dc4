// Runs simulation jobs (simulation_job.hpp) in this process: the action
// model on a Rig (the Simbody simulation with the ARA* lattice planner).
// What a worker process or a worker service runs, and the strategy
// generator itself when it has no workers.
#pragma once

#include <plr/expected.hpp>

#include <memory>
#include <string>

#include "plr/actions/rig.hpp"
#include "plr/actions/simulation_job.hpp"
#include "plr/sim/observation.hpp"
#include "plr/sim/world.hpp"

namespace plr::actions {

class JobRunner {
 public:
  // Loads the shipped robot and lattice.
  static plr::Expected<std::unique_ptr<JobRunner>> create(
      const sim::ObservationParams& observation);
  // ... with the observation parameters as a frame carries them (JSON text).
  static plr::Expected<std::unique_ptr<JobRunner>> create(const std::string& observation_json);

  plr::Expected<SimOutcome> run(const SimRequest& request);
  // The starting state of a particle: `truth` (with the particle's masses)
  // at rest, the robot at home, nothing learnt; and how it looks.
  plr::Expected<SimOutcome> start(const sim::World& truth);

  const ActionModel& model() const { return rig_->model(); }

 private:
  explicit JobRunner(std::unique_ptr<Rig> rig) : rig_(std::move(rig)) {}
  // Looks at the simulation's state after `memory`'s actions.
  plr::Expected<SimOutcome> describe(const Memory& memory);

  std::unique_ptr<Rig> rig_;
};

}  // namespace plr::actions
