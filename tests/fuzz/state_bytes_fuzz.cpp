// Fuzz target: the simulation state bytes (Snapshot::from_bytes), what a
// checkpoint on disk and a simulation worker's request hold. Bytes are
// refused with a "sim state: " message, or they make a state that writes
// back to the same bytes' meaning and that steps. Seeds: corpus/state_bytes,
// written by state_bytes_seeds_main.cpp.
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
