// Fuzz target: the pipeline config reader (kernel/core/pipeline_config.cpp),
// with an override, must end in a config or an error (one line a problem).
#include "pipeline_config.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto config = plr::kernel::parse_pipeline_config(text, "fuzz.yaml");
  if (config) {
    for (const auto& n : config->nodes) (void)plr::kernel::check_name(n.name, "node");
    (void)plr::kernel::printable(config->pipeline);
  }
  (void)plr::kernel::parse_pipeline_config(text, "fuzz.yaml", {{"nodes.a.params.k", text}});
  return 0;
}
