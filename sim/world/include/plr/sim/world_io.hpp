// World files: a trailer and its boxes in YAML.
//
//   format: plr-world
//   version: 1
//   trailer: {width: 2.5, height: 2.7, depth: 16}
//   boxes:
//     - {id: 1, size: [0.4, 0.4, 0.3], position: [15.8, 0, 0.15],
//        orientation: [1, 0, 0, 0], mass: 7.5}   # quaternion w, x, y, z
//
// Masses may be 0 (a perceived world W). Read with plr/yaml_reader.hpp:
// unknown keys are errors, at most 100'000 boxes. The error of a bad file is
// its first problem as one line, "file:line:col: key: cause"
// (world.yaml:12:5: boxes[3].size: must have exactly 3 items, got 2).
#pragma once

#include <plr/expected.hpp>

#include <filesystem>
#include <string>

#include "plr/sim/world.hpp"

namespace plr::sim {

// Parses a world from YAML text; `origin` names the source in error messages.
Expected<World> parse_world(const std::string& text, const std::string& origin);
Expected<World> load_world(const std::filesystem::path& file);

std::string format_world(const World& world);
// Atomic (plr::write_file_atomically), so a reader never sees half a world.
// The error names the file and the cause.
Status save_world(const World& world, const std::filesystem::path& file);

}  // namespace plr::sim
