#include "plr/sim/hardcoded_strategy.hpp"

#include <cmath>

namespace plr::sim {

plr::Status HardcodedParams::check() const {
  if (!(h_min >= 0) || !std::isfinite(h_min))
    return plr::make_error(PLR_ERR_INVALID, "param 'h_min': must be >= 0");
  if (!(d_min >= 0) || !std::isfinite(d_min))
    return plr::make_error(PLR_ERR_INVALID, "param 'd_min': must be >= 0");
  return {};
}

Action hardcoded_action(const SceneAnalysis& scene, const HardcodedParams& p) {
  if (!scene.front_pile.empty() && scene.pile_depth > p.d_min) return make_sweep(scene.pile_class);
  if (!scene.first_wall.empty() && scene.wall_height > p.h_min)
    return make_pick(scene.wall_class, scene.wall_side);
  // Only low things are left: a pile too shallow to be worth a sweep, or a
  // wall no higher than h_min. The paper leaves this case open; taking the
  // top box of what is in front always makes progress.
  if (!scene.front_pile.empty()) return make_pick(scene.pile_class, scene.pile_side);
  return make_pick(scene.wall_class, scene.wall_side);
}

}  // namespace plr::sim
