// The simulator's state as a WorldState message: what the robot perceives (W,
// no masses) or the true state (W^t).
#pragma once

#include <plr/messages.hpp>
#include <plr/sim/robot_model.hpp>
#include <plr/sim/world.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace plr::simulator {

struct RobotState {
  sim::JointVector q = sim::JointVector::Zero();
  std::vector<std::uint32_t> held;
};

// `octree`: OctoMap binary of the trailer shell, built once per world.
void build_world_state(flatbuffers::FlatBufferBuilder& fbb, const sim::World& world,
                       const RobotState& robot, const std::string& octree, double resolution,
                       std::uint32_t boxes_unloaded, bool true_state, std::int64_t stamp_ns);

std::string trailer_octree_bytes(const sim::Trailer& trailer, double resolution);

}  // namespace plr::simulator
