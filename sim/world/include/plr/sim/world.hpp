// The world of an unloading job: a trailer and the boxes in it.
//
// Frame (shared by sim, planners and executor): x runs along the trailer axis
// from the open rear (x = 0) towards the front wall (x = depth); y is lateral,
// centred (-width/2 .. width/2); z is up from the floor (z = 0). The robot
// starts behind the trailer (x < 0) and drives in along +x. Units: m, kg, s.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace plr::sim {

struct Trailer {
  double width = 2.5;
  double height = 2.7;
  double depth = 16.0;
};

struct Box {
  std::uint32_t id = 0;
  Eigen::Vector3d size{0.4, 0.4, 0.4};  // full extents along the box's own axes
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // centre of the box
  double mass = 0.0;  // kg; 0 where unknown (the perceived state W)
};

// W^t when masses are filled in, W when they are zero.
struct World {
  Trailer trailer;
  std::vector<Box> boxes;
};

}  // namespace plr::sim
