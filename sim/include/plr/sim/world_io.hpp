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
// unknown keys are errors, at most 100'000 boxes. Reading a bad file throws
// WorldFileError with the first problem as one line, "file:line:col: key: cause"
// (world.yaml:12:5: boxes[3].size: must have exactly 3 items, got 2).
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

#include "plr/sim/world.hpp"

namespace plr::sim {

class WorldFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Parses a world from YAML text; `origin` names the source in error messages.
World parse_world(const std::string& text, const std::string& origin);
World load_world(const std::filesystem::path& file);

std::string format_world(const World& world);
// Atomic (plr::write_file_atomically), so a reader never sees half a world.
// Throws WorldFileError naming the file on I/O errors.
void save_world(const World& world, const std::filesystem::path& file);

}  // namespace plr::sim
