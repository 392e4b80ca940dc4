// Pictures of a library entry: the strategy tree as the paper draws one
// (an action in each node, the observation on each edge, the root on top)
// and the anytime curve (the root's bounds against time).
#pragma once

#include <string>

#include "plr/sim/library.hpp"

namespace plr::generator {

std::string strategy_svg(const sim::Strategy& strategy);
std::string anytime_svg(const sim::LibraryEntry& entry);

}  // namespace plr::generator
