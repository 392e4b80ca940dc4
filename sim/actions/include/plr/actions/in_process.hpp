// The action model's backend for offline work: the simulation and a planner
// in this process, called directly (no bus). What generation, training and
// evaluation run thousands of actions on.
//
// Planning queries share one collision checker, given each query's world
// (CollisionChecker::set_world: the trailer part stays, box objects are
// reused by id), instead of one built per query; the answers are the same.
#pragma once

#include <cstdint>
#include <memory>

#include "plr/actions/backend.hpp"
#include "plr/planning/planner.hpp"

namespace plr::actions {

struct InProcessOptions {
  // false: a new collision checker per planning query (what this backend
  // did before; for comparisons).
  bool reuse_checker = true;
};

// Where the backend's wall time goes (s, summed since construction or the
// last reset_stats()).
struct InProcessStats {
  std::uint64_t queries = 0;
  std::uint64_t motions = 0;
  double checker_s = 0.0;  // building or updating the collision world
  double plan_s = 0.0;     // Planner::plan
  double sample_s = 0.0;   // sampling the trajectories for the motions
  double execute_s = 0.0;  // the simulation running the motions
  double observe_s = 0.0;  // perceiving the world
};

class InProcessBackend final : public Backend {
 public:
  // Both must outlive the backend; the planner's robot is the simulation's.
  InProcessBackend(UnloaderSimulation& simulation, planning::Planner& planner,
                   InProcessOptions options = {});
  ~InProcessBackend() override;

  plr::Expected<Perceived> observe() override;
  plr::Expected<planning::DecodedPlanResponse> plan(const planning::PlanQuery& query,
                                                    const sim::World& world) override;
  plr::Expected<Executed> execute(const Motion& motion) override;

  const InProcessStats& stats() const;
  void reset_stats();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace plr::actions
