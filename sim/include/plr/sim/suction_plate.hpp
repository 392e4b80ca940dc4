// The robot's suction gripper: a grid of cups on its plate. The simulator
// grips with it; the executor counts the cups a plate pose puts on a face.
#pragma once

#include <Eigen/Geometry>

namespace plr::sim {

struct SuctionPlate {
  // Centre of the cup face; local +z points out of the plate towards what it grips.
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  // Cup field, local x and y (m): the robot's 0.4 m x 0.5 m plate.
  Eigen::Vector2d extent{0.4, 0.5};
  int cups_x = 4;
  int cups_y = 3;
  double cup_radius = 0.03;  // m; a cup seals only with its whole rim on the face
  double cup_force = 90.0;   // N a cup holds (60 mm bellows cup, safety factor 2)
  double reach = 0.02;       // largest gap between cup face and box face that still grips
  double max_tilt = 0.26;    // rad between the plate normal and the box face normal
};

}  // namespace plr::sim
