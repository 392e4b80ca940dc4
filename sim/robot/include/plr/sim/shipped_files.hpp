// Data that ships with PLR (the robot's URDF, its lattice primitives), found
// relative to the binary that asks, so a build tree and an installed tree
// both work without absolute paths baked in.
#pragma once

#include <plr/expected.hpp>

#include <filesystem>
#include <string_view>

namespace plr::sim {

// `relative` under the data folder (e.g. "robots/unloader.urdf"). Looks in
// $PLR_DATA_DIR, then share/plr next to the binary holding this code
// (<bin>/../share/plr, <lib>/plugins/../../share/plr), then next to the
// running program. The error names the places it looked.
plr::Expected<std::filesystem::path> shipped_file(std::string_view relative);

}  // namespace plr::sim
