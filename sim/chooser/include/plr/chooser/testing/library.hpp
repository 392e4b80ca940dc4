// Test fixture: the chooser tests' library, one strategy per world of the
// chooser's test data (plugins/strategy_chooser/test/data): a low sweep for
// the row on the floor, a mid pick for the two-column wall.
#pragma once

#include <filesystem>
#include <string>
#include <utility>

#include "plr/sim/library.hpp"
#include "plr/sim/strategy.hpp"
#include "plr/sim/world_io.hpp"

namespace plr::chooser::testing {

inline sim::Library two_world_library(const std::filesystem::path& data) {
  sim::Library library;
  for (const auto& [name, action] :
       {std::pair{"floor_row", sim::make_sweep(sim::Height::kLow)},
        {"two_columns", sim::make_pick(sim::Height::kMid, sim::Side::kLeft)}}) {
    sim::LibraryEntry e;
    e.name = name;
    e.world = sim::load_world(data / (std::string(name) + ".yaml")).value();
    e.strategy = sim::single_action(action, name);
    library.entries.push_back(std::move(e));
  }
  return library;
}

}  // namespace plr::chooser::testing
