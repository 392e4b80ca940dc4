// Reader for Cassandra's `.pomdp` text format (discount, values, states,
// actions, observations, start, T/O/R lines with `*` wildcards, rows,
// matrices, `identity` and `uniform`). Errors are one line:
// "file:line:column: what is wrong".
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <plr/expected.hpp>

#include "plr/pomdp/read_limits.hpp"
#include "plr/pomdp/tabular_model.hpp"

namespace plr::pomdp {

plr::Expected<TabularModel> parse_cassandra(std::string_view text, const std::string& origin,
                                            const ReadLimits& limits = {});
plr::Expected<TabularModel> read_cassandra(const std::filesystem::path& file,
                                           const ReadLimits& limits = {});

}  // namespace plr::pomdp
