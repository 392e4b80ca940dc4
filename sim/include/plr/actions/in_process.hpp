// The action model's backend for offline work: the simulation and a planner
// in this process, called directly (no bus). What generation, training and
// evaluation run thousands of actions on.
#pragma once

#include <memory>

#include "plr/actions/backend.hpp"
#include "plr/planning/planner.hpp"

namespace plr::actions {

class InProcessBackend final : public Backend {
 public:
  // Both must outlive the backend; the planner's robot is the simulation's.
  InProcessBackend(UnloaderSimulation& simulation, planning::Planner& planner);
  ~InProcessBackend() override;

  plr::Expected<Perceived> observe() override;
  plr::Expected<planning::DecodedPlanResponse> plan(const planning::PlanQuery& query,
                                                    const sim::World& world) override;
  plr::Expected<Executed> execute(const Motion& motion) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace plr::actions
