// Simulates requests in this process: the action model on the Simbody
// simulation with the ARA* lattice planner (what a worker process runs, and
// the generator itself when it has no workers). And the Simulator interface
// the truck model hands its batches to.
#pragma once

#include <plr/expected.hpp>

#include <memory>
#include <vector>

#include "plr/actions/action_model.hpp"
#include "plr/sim/observation.hpp"
#include "plr/sim/robot_model.hpp"
#include "plr/sim/world.hpp"
#include "truck/sim_work.hpp"

namespace plr::generator {

// Runs batches of requests. The outcome of request i is the i-th result,
// and it depends only on the request: not on which worker ran it, when, or
// how many there are.
class Simulator {
 public:
  virtual ~Simulator() = default;
  virtual std::vector<plr::Expected<SimOutcome>> run(const std::vector<SimRequest>& batch) = 0;
  virtual int workers() const = 0;
  // Workers simulating now (for a progress display; any thread).
  virtual int busy() const = 0;
};

class ActionRunner {
 public:
  // Loads the shipped robot and lattice.
  static plr::Expected<std::unique_ptr<ActionRunner>> create(
      const sim::ObservationParams& observation);
  ~ActionRunner();

  plr::Expected<SimOutcome> run(const SimRequest& request);
  // The starting state of a particle: `truth` (with the particle's masses)
  // at rest, the robot at home, nothing learnt; and how it looks.
  plr::Expected<SimOutcome> start(const sim::World& truth);

  const actions::ActionModel& model() const;

 private:
  struct Impl;
  explicit ActionRunner(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Runs each batch one request after the other in this process.
class LocalSimulator final : public Simulator {
 public:
  explicit LocalSimulator(ActionRunner& runner) : runner_(runner) {}
  std::vector<plr::Expected<SimOutcome>> run(const std::vector<SimRequest>& batch) override;
  int workers() const override { return 1; }
  int busy() const override { return busy_; }

 private:
  ActionRunner& runner_;
  int busy_ = 0;
};

}  // namespace plr::generator
