// Reader for POMDPX, the factored XML format that SARSOP and DESPOT ship:
// state variables (vnamePrev/vnameCurr), observation and action variables,
// reward variables; CondProb and Func tables of type TBL with `*` and `-`
// instances and `identity` / `uniform` tables. The factored model is
// flattened into a TabularModel (states are value combinations). Errors are
// one line: "file:line: what is wrong".
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <plr/expected.hpp>

#include "plr/pomdp/read_limits.hpp"
#include "plr/pomdp/tabular_model.hpp"

namespace plr::pomdp {

plr::Expected<TabularModel> parse_pomdpx(std::string_view text, const std::string& origin,
                                         const ReadLimits& limits = {});
plr::Expected<TabularModel> read_pomdpx(const std::filesystem::path& file,
                                        const ReadLimits& limits = {});

}  // namespace plr::pomdp
