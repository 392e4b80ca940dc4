// The robot's suction gripper: a grid of cups on its plate. The simulator
// grips with it; the executor counts the cups a plate pose puts on a face.
// These defaults are the one place the plate's size is set: the URDF's
// `plate` link (sim/robots/unloader.urdf) has the same outline (a test
// checks it) and actions::Geometry derives its plate extents from them.
#pragma once

#include <Eigen/Geometry>

namespace plr::sim {

struct SuctionPlate {
  // Centre of the cup face; local +z points out of the plate towards what it grips.
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  // Cup field, local x (up the plate) and y (across it), m: the robot's
  // 0.5 m high x 0.6 m wide plate. Centred on the seam between two typical
  // boxes (0.4-0.55 m wide, 0.3-0.4 m high) side by side or stacked, it
  // puts two or more rows or columns of cups on each; centred on one box,
  // its outer cups mostly fall beside it.
  Eigen::Vector2d extent{0.5, 0.6};
  int cups_x = 4;            // 0.125 m pitch
  int cups_y = 6;            // 0.1 m pitch
  double cup_radius = 0.03;  // m; a cup seals only with its whole rim on the face
  double cup_force = 90.0;   // N a cup holds (60 mm bellows cup, safety factor 2)
  double reach = 0.02;       // largest gap between cup face and box face that still grips
  double max_tilt = 0.26;    // rad between the plate normal and the box face normal
  // The vacuum source's limit on the cups together, N. Cardboard leaks: a
  // blower-type generator holds the full vacuum (cup_force per cup) on about
  // six cups sealed on cardboard; with more, the vacuum level falls and the
  // sealed cups share this force (each holds min(cup_force, pump_max_force /
  // sealed cups)). One box of up to ~55 kg holds; two at once hold ~27 kg
  // each, three ~18 kg each.
  double pump_max_force = 540.0;
};

}  // namespace plr::sim
