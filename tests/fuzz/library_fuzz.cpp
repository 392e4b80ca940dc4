// Fuzz target: the strategy library reader (sim/semantic/library.cpp). The
// first byte chooses whether the input is a whole file or a body the target
// frames itself: the frame's CRC would stop nearly every mutation before the
// FlatBuffers and the entries are read.
#include <plr/sim/framed_file.hpp>
#include <plr/sim/library.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  std::vector<std::uint8_t> file(data + 1, data + size);
  if (data[0] & 1) file = plr::frame(data + 1, size - 1);
  auto library = plr::sim::deserialize_library(file.data(), file.size(), "fuzz.plrl");
  if (!library) return 0;
  // What was read writes back and reads again.
  const auto again = plr::sim::serialize(*library);
  if (!plr::sim::deserialize_library(again.data(), again.size(), "again.plrl")) __builtin_trap();
  return 0;
}
