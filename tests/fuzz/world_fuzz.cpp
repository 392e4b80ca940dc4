// Fuzz target: the world file reader (sim/world/world_io.cpp); what it
// accepts must format and read back the same.
#include <plr/sim/world_io.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto world = plr::sim::parse_world(text, "fuzz.yaml");
  if (!world) return 0;
  auto again = plr::sim::parse_world(plr::sim::format_world(*world), "formatted");
  if (!again || again->boxes.size() != world->boxes.size()) __builtin_trap();
  return 0;
}
