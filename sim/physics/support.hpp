// Internal: which boxes hold a box up, from geometry alone (fast fidelity's
// quasi-static rule). A box rests on what its lower face touches: the floor
// and the boxes whose upper faces meet it. It is supported when its centre of
// mass lies over the support polygon, the convex hull of those contacts;
// otherwise it would tip or fall, and the physics must move it.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "broad_phase.hpp"
#include "state.hpp"

namespace plr::sim::detail {

// Into `out`: the sleeping boxes that rest on body `below` at `pose` (their
// lower faces within kSupportGap of its upper face).
void resting_on(const std::vector<Body>& bodies, const BroadPhase& broad, int below,
                const Eigen::Isometry3d& pose, std::vector<int>& out);

// Whether sleeping body `i` rests in balance on the floor and the sleeping
// boxes below it (held, awake and gone boxes hold nothing up: they move).
bool supported(const std::vector<Body>& bodies, const BroadPhase& broad, int i);

}  // namespace plr::sim::detail
