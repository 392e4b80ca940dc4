// Hand-made worlds for the chooser's tests: boxes given by their bounds.
#pragma once

#include "plr/sim/world.hpp"

namespace plr::chooser::test {

// An axis-aligned box filling [x0, x1] x [y0, y1] x [z0, z1].
inline void add_box(sim::World& w, double x0, double x1, double y0, double y1, double z0,
                    double z1) {
  sim::Box b;
  b.id = static_cast<std::uint32_t>(w.boxes.size() + 1);
  b.size = {x1 - x0, y1 - y0, z1 - z0};
  b.pose.translation() = Eigen::Vector3d((x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2);
  w.boxes.push_back(b);
}

// The lateral bounds of grid column c in the default 2.5 m trailer.
inline double column_y0(int c) {
  return -1.25 + 0.25 * c;
}

}  // namespace plr::chooser::test
