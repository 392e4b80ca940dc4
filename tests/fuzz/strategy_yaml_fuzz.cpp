// Fuzz target: the strategy YAML reader (sim/semantic/strategy.cpp); what it
// accepts must survive the binary form and walking its tree.
#include <plr/sim/strategy.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto s =
      plr::sim::parse_yaml(std::string(reinterpret_cast<const char*>(data), size), "fuzz.yaml");
  if (!s) return 0;
  const auto bytes = plr::sim::serialize(*s);
  if (!plr::sim::deserialize(bytes.data(), bytes.size(), "serialized")) __builtin_trap();
  (void)plr::sim::format_yaml(*s);
  return 0;
}
