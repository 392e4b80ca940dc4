// The trailer's occupancy as an OctoMap octree (the static part of the
// perceived world W that planners collide against, e.g. through fcl::OcTree).
#pragma once

#include <octomap/OcTree.h>

#include <memory>
#include <vector>

#include "plr/sim/world.hpp"

namespace plr::sim {

struct OctreeOptions {
  double resolution = 0.05;      // m, leaf size
  double wall_thickness = 0.05;  // m, modelled outside the inner volume
  double floor_behind = 5.0;     // m of floor behind the open rear, where the robot stands
};

// Floor, ceiling, both side walls and the front wall as occupied leaves; the
// rear (x = 0) stays open and the floor goes on behind it. The inner volume
// is not marked (unknown), which is what a sensor sees before looking inside.
// Every size must be positive (floor_behind may be 0); the one trailer shell
// that planners, the simulator and tests collide against.
std::unique_ptr<octomap::OcTree> build_trailer_octree(const Trailer& trailer,
                                                      const OctreeOptions& options = {});

// Marks the volume of each box occupied (for consumers that want one octree
// holding everything; planners usually keep boxes as separate shapes).
void add_boxes_to_octree(octomap::OcTree& tree, const std::vector<Box>& boxes);

}  // namespace plr::sim
