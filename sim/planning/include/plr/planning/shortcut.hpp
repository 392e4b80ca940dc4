// Path shortcutting for any planner whose paths take detours (a lattice's
// staircase, a sampler's zigzag).
#pragma once

#include <vector>

#include "plr/sim/collision.hpp"

namespace plr::planning {

// Greedy and deterministic: drops waypoints inside straight runs, then from
// each kept waypoint jumps to the farthest later one reachable by a valid
// straight joint-space motion.
std::vector<sim::JointVector> shortcut_path(const std::vector<sim::JointVector>& path,
                                            const sim::CollisionChecker& checker);

}  // namespace plr::planning
