// Any bytes given to the POMDPX reader give a model or a located error,
// never a crash, a hang or unbounded memory.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "pomdp/pomdpx_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  plr::pomdp::ReadLimits limits;
  limits.max_states = 2000;
  limits.max_actions = 64;
  limits.max_observations = 64;
  limits.max_state_actions = 20000;
  limits.max_entries = 200000;
  const auto m = plr::pomdp::parse_pomdpx(
      std::string_view(reinterpret_cast<const char*>(data), size), "fuzz", limits);
  if (!m && m.error().message.rfind("fuzz:", 0) != 0) __builtin_trap();
  return 0;
}
