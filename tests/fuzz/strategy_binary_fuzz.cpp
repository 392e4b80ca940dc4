// Fuzz target: the strategy binary reader (identifier "PLRS", verified
// FlatBuffers) and the message form the bus carries.
#include <plr/sim/strategy.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto s = plr::sim::deserialize(data, size, "fuzz.plrs");
  if (!s) return 0;
  (void)plr::sim::format_yaml(*s);
  (void)plr::sim::serialize(*s);
  return 0;
}
