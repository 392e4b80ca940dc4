// Why each box still in the trailer at the end of a run is there.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "plr/actions/action_model.hpp"

namespace plr::episode {

enum class LeftReason {
  kGivenUp,     // grasped and lost again and again
  kUnplanned,   // a pick point exists, but no motion to it was found
  kOnRobot,     // lying on the robot, off the trailer's floor
  kBehind,      // wholly behind the robot's front edge: fallen beside or behind the base
  kNoFace,      // no face the vertical plate can seal on (tilted on an edge)
  kOutOfReach,  // even alone in the trailer, the arm cannot reach a face
  kBlocked,     // pickable alone: other boxes stand in the way
};
const char* to_string(LeftReason reason);

struct LeftBox {
  std::uint32_t id = 0;
  LeftReason reason = LeftReason::kBlocked;
  std::string detail;
};

// The boxes of `world`, each with its reason, from what the run learnt
// (`memory`) and the geometry (each box tried alone with every Pick region).
std::vector<LeftBox> boxes_left(const sim::World& world, const sim::JointVector& q,
                                const actions::Memory& memory, const actions::ActionModel& model);
std::map<std::string, std::uint32_t> count_by_reason(const std::vector<LeftBox>& left);

}  // namespace plr::episode
