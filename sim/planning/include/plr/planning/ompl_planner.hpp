// RRTConnect (OMPL) with shortcutting behind the planner contract
// (plr/planning/planner.hpp), for comparison and as an alternative plug-in.
//
// Joint modes (M1, M2, M3, M5) plan in the mode's joint space; pose goals
// become goal states from the arm IK (M2: at several base positions). M4
// plans the plate's progress along its line (states map to configurations
// through the IK). M6 and starts in collision are the contract's escape.
//
// Reproducible per query: OMPL's RNG::setSeed only seeds the process-wide
// sequence from which every RNG instance draws its seed, so results would
// depend on how many RNGs were made before. Instead the query's state
// sampler gets a local seed from the query, and the random shortcutting is
// our own on a generator seeded the same way (OMPL's PathSimplifier keeps its
// RNG private). A query's max_expansions bounds RRTConnect's iterations.
#pragma once

#include <cstdint>

#include "plr/planning/planner.hpp"

namespace plr::ompl_planner {

struct Options {
  // RRTConnect's step (in the planning space's units); 0 lets OMPL choose.
  double range = 0.0;
  // Mixed with a hash of each query into the seed of that query's sampler
  // and shortcutting, so the same query always gives the same path.
  std::uint32_t seed = 1;
};

class OmplPlanner final : public planning::Planner {
 public:
  explicit OmplPlanner(const Options& options = {});
  std::string name() const override { return "rrtconnect"; }

 protected:
  planning::PlanResult do_plan(const planning::PlanQuery& query,
                               sim::CollisionChecker& checker) override;

 private:
  Options options_;
};

}  // namespace plr::ompl_planner
