// Reading model files: by extension, `.pomdpx` as POMDPX and anything else
// as Cassandra's `.pomdp` format.
#pragma once

#include <filesystem>
#include <string>

#include <plr/expected.hpp>

#include "plr/pomdp/read_limits.hpp"
#include "plr/pomdp/tabular_model.hpp"

namespace plr::pomdp {

// The whole file, or "file:1:1: cause" when it cannot be read or is larger
// than `max_bytes`.
plr::Expected<std::string> read_text_file(const std::filesystem::path& file, std::size_t max_bytes);

plr::Expected<TabularModel> load_model(const std::filesystem::path& file,
                                       const ReadLimits& limits = {});

}  // namespace plr::pomdp
