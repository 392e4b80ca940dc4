// Fuzz target: the MCAP reader behind `plr replay` (kernel/record), on a
// hostile file: every record length, string, chunk size and compressed
// frame comes from the input. It must return an error or the messages, never
// read outside the input or allocate past its limits.
#include "mcap_reader.hpp"

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace {
volatile std::size_t sink;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  plr::kernel::mcap::Contents contents;
  plr::kernel::mcap::ReaderLimits limits;
  limits.max_chunk_bytes = 1u << 20;
  (void)plr::kernel::mcap::read(
      std::string_view(reinterpret_cast<const char*>(data), size), "fuzz",
      [](const plr::kernel::mcap::MessageRecord& m) {
        sink = sink + m.data.size() + m.channel->topic.size();
      },
      contents, limits);
  return 0;
}
