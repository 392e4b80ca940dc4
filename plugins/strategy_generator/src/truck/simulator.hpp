// Where the generator's batches of simulation jobs run: the Simulator
// interface the truck model hands its batches to, and the simulator that
// runs them one after the other in this process.
#pragma once

#include <plr/expected.hpp>

#include <vector>

#include "plr/actions/job_runner.hpp"
#include "plr/actions/simulation_job.hpp"

namespace plr::generator {

using actions::JobRunner;
using actions::kEmptyObservation;
using actions::SimOutcome;
using actions::SimRequest;
using actions::StateBytes;

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

// Runs each batch one request after the other in this process.
class LocalSimulator final : public Simulator {
 public:
  explicit LocalSimulator(JobRunner& runner) : runner_(runner) {}
  std::vector<plr::Expected<SimOutcome>> run(const std::vector<SimRequest>& batch) override;
  int workers() const override { return 1; }
  int busy() const override { return busy_; }

 private:
  JobRunner& runner_;
  int busy_ = 0;
};

}  // namespace plr::generator
