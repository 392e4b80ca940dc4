// Bridge from the robot model (robot_model.hpp) to the physics: the robot's
// collision shapes at a configuration, as kinematic shapes for
// Simulation::set_robot_links, and its suction plate.
#pragma once

#include <string>
#include <vector>

#include "plr/sim/physics.hpp"
#include "plr/sim/robot_model.hpp"

namespace plr::sim {

// Every collision box and cylinder of every link at q (spheres become boxes
// of the same extent), in link order. Shapes of `conveyor_link` carry a belt
// running at `belt_speed` towards the robot (the link's -x) that hands boxes
// to the body conveyor; shapes of `feeder_link` carry one that feeds it (the
// scoop's belt, telescoping out of the conveyor). Shapes of `body_link` carry
// the body conveyor, which takes what lands on the robot's body (a box fallen
// from a sweep onto the base) out to the trailer's rear. When the scoop's leading
// edge is near the floor, a thin lip continues it down to the floor (after
// the feeder's shape): what lets the scoop get under boxes.
std::vector<LinkGeometry> robot_link_geometry(const RobotModel& model, const JointVector& q,
                                              double belt_speed = 0.0,
                                              const std::string& conveyor_link = "nose_conveyor",
                                              const std::string& feeder_link = "nose_scoop",
                                              const std::string& body_link = "base_link");

// The suction plate at q: the model's plate frame has its normal along +x,
// the physics' along +z. Cup layout and forces come from `cups`.
SuctionPlate suction_plate_at(const RobotModel& model, const JointVector& q,
                              const SuctionPlate& cups = {});

}  // namespace plr::sim
