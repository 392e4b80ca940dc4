// Fuzz target: the chooser's model reader (sim/chooser/model.cpp) and a
// decision with what it read. The first byte chooses whether the input is a
// whole file or a body the target frames itself, past the frame's CRC.
#include <plr/chooser/model.hpp>
#include <plr/sim/framed_file.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  std::vector<std::uint8_t> file(data + 1, data + size);
  if (data[0] & 1) file = plr::frame(data + 1, size - 1);
  auto model = plr::chooser::Model::deserialize(file.data(), file.size(), "fuzz.plrm");
  if (!model) return 0;
  (void)model->decide(plr::chooser::Features{});
  const auto again = model->serialize();
  if (!plr::chooser::Model::deserialize(again.data(), again.size(), "again.plrm")) __builtin_trap();
  return 0;
}
