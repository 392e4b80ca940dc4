// The robot's I/O as one command, in the form ros2_control's
// forward_command_controller takes on "/<controller>/commands"
// (std_msgs/msg/Float64MultiArray): data[0] the vacuum (1 on, 0 off),
// data[1] the nose conveyor (1 running, 0 stopped), then one value per
// suction cup valve (1 open, 0 closed), row by row up the plate
// (sim::SuctionPlate). A GPIO controller whose interfaces are listed in that
// order drives them.
#pragma once

#include <vector>

namespace plr::ros2 {

struct IoCommand {
  bool vacuum = false;
  bool conveyor = false;
  std::vector<bool> cups_open;

  bool operator==(const IoCommand&) const = default;
};

}  // namespace plr::ros2
