// Fuzz target: the lattice and motion-primitive reader
// (sim/planning/lattice/lattice_config.cpp).
#include <plr/planning/lattice_config.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)plr::planning::LatticeConfig::from_string(
      std::string(reinterpret_cast<const char*>(data), size), "fuzz.yaml");
  return 0;
}
