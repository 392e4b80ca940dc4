// Strategy H, the paper's hardcoded strategy: boxes below h_pile are pile,
// above it wall (ObservationParams). A pile reaching more than d_min out
// before the first wall's face (all of it, without a wall) is swept along
// the floor (Sweep(low): H has one sweep, as in the paper); else, if the
// first wall is higher than h_min, a box is picked from it, near the robot
// and high up first. The strategy_hardcoded plug-in serves
// it over the bus; offline tools call it directly.
#pragma once

#include <plr/expected.hpp>

#include <vector>

#include "plr/sim/observation.hpp"
#include "plr/sim/strategy.hpp"

namespace plr::yaml {
class Map;
}

namespace plr::sim {

struct HardcodedParams {
  double h_min = 0.5;  // m; a lower first wall is not picked from (unless nothing else is left)
  // m; a shallower pile is not swept: the bottom row left of a wall (one box
  // deep) is picked.
  double d_min = 0.6;

  // Whether the values are usable; the error names the parameter.
  plr::Status check() const;
};

// H's thresholds (`h_min`, `d_min`) and the observation classes
// (`observation`) where a config's top level gives them; a bad value is
// recorded on the map's document with its location.
void read_strategy_settings(const yaml::Map& top, HardcodedParams& h,
                            ObservationParams& observation);

// H's action for the scene in front of the robot (which must not be empty).
Action hardcoded_action(const SceneAnalysis& scene, const HardcodedParams& params);

// All 12 actions in H's order of preference: its action first, then what an
// expert falls back to when that one is not applicable or moves nothing —
// the other sides at the same height, other heights from the top down, and
// sweeps (first, if H sweeps).
std::vector<Action> hardcoded_ranking(const SceneAnalysis& scene, const HardcodedParams& params);

}  // namespace plr::sim
