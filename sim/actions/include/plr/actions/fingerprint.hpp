// The action model's fingerprint, recorded in a strategy library so that a
// library (and a chooser trained on it) made with another action model can
// be told stale. kActionModelVersion is raised whenever an action's outcome
// changes on purpose (planning, grasping, timing); the robot's shipped files
// (its URDF and planning lattice) are hashed as they are.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <string>

namespace plr::actions {

inline constexpr std::uint32_t kActionModelVersion = 3;

// "v2-3f2a09c1": the version and a CRC-32 of the shipped robot files.
plr::Expected<std::string> action_model_fingerprint();

}  // namespace plr::actions
