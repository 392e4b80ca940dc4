// A checkpoint on disk, so a restarted simulator process resumes where the
// run was at the last action boundary: the true world (a world file) plus the
// robot and the unloading count. Both files are written atomically.
#pragma once

#include "world_message.hpp"

#include <plr/expected.hpp>
#include <plr/sim/world.hpp>

#include <filesystem>
#include <optional>
#include <string>

namespace plr::simulator {

struct Checkpoint {
  sim::World world;
  RobotState robot;
  double sim_time = 0;
  std::uint32_t boxes_total = 0;
  std::uint32_t boxes_unloaded = 0;
};

// The folder's bytes once written.
Expected<std::uint64_t> save_checkpoint(const std::filesystem::path& dir, const Checkpoint& c);
// nullopt when the folder holds no checkpoint; an error for a damaged one.
Expected<std::optional<Checkpoint>> load_checkpoint(const std::filesystem::path& dir);

}  // namespace plr::simulator
