// Fuzz target: the URDF reader (sim/robot/robot_model.cpp: bounds, TinyXML,
// urdfdom and the robot's own checks).
#include <plr/sim/robot_model.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto robot = plr::sim::RobotModel::from_urdf_string(
      std::string(reinterpret_cast<const char*>(data), size), "fuzz.urdf");
  if (robot) (void)robot->links().size();
  return 0;
}
