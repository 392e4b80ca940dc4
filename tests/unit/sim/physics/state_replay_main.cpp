// Helper of state_bytes_test: continues a simulation from its bytes in a
// process of its own, so the test can compare that run with the original.
//
//   sim_physics_state_replay IN OUT STEPS
//
// Reads Snapshot bytes from IN, builds a Simulation from them, calls
// step(0.01) STEPS times and writes the final snapshot's bytes to OUT.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <vector>

#include "plr/sim/physics.hpp"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: sim_physics_state_replay IN OUT STEPS\n");
    return 2;
  }
  std::ifstream in(argv[1], std::ios::binary);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  auto snapshot = plr::sim::Snapshot::from_bytes(bytes.data(), bytes.size());
  if (!snapshot) {
    std::fprintf(stderr, "%s: %s\n", argv[1], snapshot.error().message.c_str());
    return 1;
  }
  auto sim = plr::sim::Simulation::from_snapshot(*snapshot);
  if (!sim) {
    std::fprintf(stderr, "%s: %s\n", argv[1], sim.error().message.c_str());
    return 1;
  }
  const int steps = std::atoi(argv[3]);
  for (int k = 0; k < steps; ++k) sim->step(0.01);
  const std::vector<std::uint8_t> out = sim->snapshot().to_bytes();
  std::ofstream file(argv[2], std::ios::binary);
  file.write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
  return file.good() ? 0 : 1;
}
