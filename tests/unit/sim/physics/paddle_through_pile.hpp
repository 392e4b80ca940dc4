// The scene several physics tests share: a small B1 pile and a paddle
// driven through it, fast enough to wake most of the pile.
#pragma once

#include "plr/sim/generators.hpp"
#include "plr/sim/physics.hpp"

namespace plr::sim::test {

inline World small_pile() {
  World w = generate_world(EnvFamily::kB1, 11);
  w.boxes.resize(40);
  return w;
}

// Drives the paddle through the pile from `sim`'s current time; the paddle
// stays where it stopped.
inline void drive_paddle(Simulation& sim) {
  LinkGeometry nose;
  nose.size = {0.8, 1.2, 0.1};
  for (int k = 0; k <= 80; ++k) {
    nose.pose.translation() = Eigen::Vector3d(12.5 + 0.02 * k, 0.0, 0.06);
    sim.set_robot_links({nose});
    sim.step(0.005);
  }
}

}  // namespace plr::sim::test
