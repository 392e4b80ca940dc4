// RRTConnect (OMPL) with shortcutting on the same collision checker and the
// same query/result types as the ARA* lattice planner, for comparison and as
// an alternative plug-in.
//
// Joint modes (M1, M2, M3, M5) plan in the mode's joint space; pose goals
// become goal states from the arm IK (M2: at several base positions). M4
// plans the plate's progress along its line (states map to configurations
// through the IK). M6 is not a sampling problem: starts in collision are
// reported as kStartInvalid and M6 queries as kInvalidRequest.
#pragma once

#include <cstdint>

#include "plr/sim/plan_types.hpp"

namespace plr::ompl_planner {

struct Options {
  // RRTConnect's step (in the planning space's units); 0 lets OMPL choose.
  double range = 0.0;
  // Seeds OMPL's global RNG the first time a Planner is made in a process
  // (OMPL allows this once), so runs are repeatable.
  std::uint32_t seed = 1;
};

class Planner {
 public:
  explicit Planner(const Options& options = {});
  sim::PlanResult plan(const sim::PlanQuery& query, sim::CollisionChecker& checker);

 private:
  Options options_;
};

}  // namespace plr::ompl_planner
