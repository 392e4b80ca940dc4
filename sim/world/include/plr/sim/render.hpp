// SVG pictures of a world: side view (x right, z up) and top view (x right,
// y up), boxes coloured by mass (light = light, dark red = heavy; grey where
// the mass is unknown), optional robot shapes drawn on top.
#pragma once

#include <plr/expected.hpp>

#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <vector>

#include "plr/sim/world.hpp"

namespace plr::sim {

enum class View { kSide, kTop };

// An oriented box to draw over the world (e.g. a robot link's bounding box).
struct Overlay {
  Eigen::Vector3d size{0.1, 0.1, 0.1};
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

struct RenderOptions {
  double pixels_per_metre = 60.0;
  double x_min = -3.0;  // shows the robot's approach behind the trailer
  std::vector<Overlay> robot;
  std::string title;
};

std::string render_svg(const World& world, View view, const RenderOptions& options = {});
// Atomic write (plr::write_file_atomically); the error names the file.
Status write_svg(const std::filesystem::path& file, const World& world, View view,
                 const RenderOptions& options = {});

}  // namespace plr::sim
