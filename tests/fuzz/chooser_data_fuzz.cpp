// Fuzz target: the chooser's training data set reader
// (sim/chooser/training/data_set.cpp), what a training run
// reads back when it resumes. The first byte chooses whether the input is a
// whole file or a body the target frames itself, past the frame's CRC.
#include <plr/sim/framed_file.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "plr/chooser/training/data_set.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  std::vector<std::uint8_t> file(data + 1, data + size);
  if (data[0] & 1) file = plr::frame(data + 1, size - 1);
  (void)plr::chooser::read_data_set(file.data(), file.size(), "fuzz.plrd");
  return 0;
}
