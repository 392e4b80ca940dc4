// Writes a few valid simulation states (Snapshot bytes) into a folder: the
// seed corpus of fuzz_state_bytes (tests/fuzz/corpus/state_bytes).
//
//   fuzz_state_bytes_seeds DIR
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "plr/sim/generators.hpp"
#include "plr/sim/physics.hpp"

namespace {

using plr::sim::Simulation;

bool write(const std::string& path, const Simulation& sim) {
  const std::vector<std::uint8_t> bytes = sim.snapshot().to_bytes();
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  return out.good();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_state_bytes_seeds DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  plr::sim::World pile = plr::sim::generate_world(plr::sim::EnvFamily::kB1, 3);
  pile.boxes.resize(6);
  Simulation sim(pile);
  bool ok = write(dir + "/fresh.psim", sim);
  // Robot shapes (a box with a belt, a cylinder), a plate holding a box,
  // boxes falling: every part of the state filled in.
  plr::sim::LinkGeometry belt, post;
  belt.size = {1.0, 0.8, 0.05};
  belt.pose.translation() = Eigen::Vector3d(6.0, 0.0, 0.3);
  belt.belt_speed = 0.5;
  post.shape = plr::sim::LinkGeometry::Shape::kCylinder;
  post.size = {0.1, 0.1, 1.0};
  post.pose.translation() = Eigen::Vector3d(14.0, 1.0, 0.5);
  sim.set_robot_links({belt, post});
  plr::sim::SuctionPlate plate;
  const plr::sim::Box& top = pile.boxes[0];
  plate.pose = Eigen::Translation3d(top.pose.translation() +
                                    Eigen::Vector3d(0.0, 0.0, 0.5 * top.size.z() + 0.001)) *
               Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX());
  sim.set_suction_plate(plate);
  sim.suction_on();
  sim.step(0.05);
  ok = ok && write(dir + "/moving.psim", sim);
  sim.settle(2.0);
  ok = ok && write(dir + "/resting.psim", sim);
  if (!ok) std::fprintf(stderr, "fuzz_state_bytes_seeds: cannot write to %s\n", dir.c_str());
  return ok ? 0 : 1;
}
