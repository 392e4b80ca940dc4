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
  // 0.4 m high x 0.5 m wide plate, cups on a 0.1 m grid. On the seam
  // between two typical boxes (0.4-0.55 m wide, 0.3-0.4 m high) side by side
  // or stacked, two columns or rows of cups seal on each, and on the corner
  // of four (or three) boxes two by two on each. Centred on one such box, no
  // whole cup lies on a neighbour (the outer cups straddle its edges or stay
  // on it), so a pick can take one box of a tightly packed wall: a larger
  // grid would seal on neighbours too, which a Pick of another region must
  // not take.
  Eigen::Vector2d extent{0.4, 0.5};
  int cups_x = 4;
  int cups_y = 5;
  double cup_radius = 0.03;  // m; a cup seals only with its whole rim on the face
  double cup_force = 90.0;   // N a cup holds (60 mm bellows cup, safety factor 2)
  double reach = 0.02;       // largest gap between cup face and box face that still grips
  double max_tilt = 0.26;    // rad between the plate normal and the box face normal
  // The vacuum source's limit on the cups together, N. Cardboard leaks: a
  // blower-type generator holds the full vacuum (cup_force per cup) on about
  // twelve cups sealed on cardboard; with more, the vacuum level falls and
  // the sealed cups share this force (each holds min(cup_force,
  // pump_max_force / sealed cups)). One box holds up to ~110 kg (sealed by
  // twelve cups or more); two, three or four at once sealed by four cups
  // each, ~37, ~37 and ~27 kg each.
  double pump_max_force = 1080.0;
};

}  // namespace plr::sim
