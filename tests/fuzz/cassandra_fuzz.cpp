// Any bytes given to the Cassandra reader give a model or a located error,
// never a crash, a hang or unbounded memory.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "plr/pomdp/cassandra_reader.hpp"
#include "pomdp_limits.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto m = plr::pomdp::parse_cassandra(
      std::string_view(reinterpret_cast<const char*>(data), size), "fuzz", fuzz_limits());
  if (!m && m.error().message.rfind("fuzz:", 0) != 0) __builtin_trap();
  return 0;
}
