// libFuzzer target for Snapshot::from_bytes (built with -DPLR_FUZZ=ON and
// clang). Bytes are refused with a "sim state: " message, or they make a
// state that writes back to the same bytes' meaning and that steps.
//
//   sim_physics_state_seeds corpus/   # a few valid states to start from
//   sim_physics_state_bytes_fuzz corpus/ -max_total_time=120
#include <cstdlib>
#include <vector>

#include "plr/sim/physics.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto snapshot = plr::sim::Snapshot::from_bytes(data, size);
  if (!snapshot) {
    if (snapshot.error().message.rfind("sim state: ", 0) != 0) std::abort();
    return 0;
  }
  const std::vector<std::uint8_t> bytes = snapshot.value().to_bytes();
  const auto again = plr::sim::Snapshot::from_bytes(bytes.data(), bytes.size());
  if (!again || again.value().to_bytes() != bytes) std::abort();
  // Stepping builds Simbody's system for the awake boxes: keep inputs cheap.
  if (snapshot.value().world().boxes.size() <= 64) {
    auto sim = plr::sim::Simulation::from_snapshot(snapshot.value());
    if (!sim) std::abort();
    sim.value().step(0.002);
  }
  return 0;
}
