#include "plr/sim/hardcoded_strategy.hpp"

#include <plr/yaml_reader.hpp>

#include <algorithm>
#include <cmath>

namespace plr::sim {

plr::Status HardcodedParams::check() const {
  if (!(h_min >= 0) || !std::isfinite(h_min))
    return plr::make_error(PLR_ERR_INVALID, "param 'h_min': must be >= 0");
  if (!(d_min >= 0) || !std::isfinite(d_min))
    return plr::make_error(PLR_ERR_INVALID, "param 'd_min': must be >= 0");
  return {};
}

namespace {

// The depth of pile a sweep clears: what lies before the first wall's face.
// Short columns standing level with the wall are stacked like it; Sweep(low)
// stops short of the wall's face and takes none of them, and a deeper sweep
// drives into the wall and brings it down onto the scoop (A2).
double sweepable_depth(const SceneAnalysis& scene) {
  if (scene.front_pile.empty()) return 0.0;
  if (scene.first_wall.empty()) return scene.pile_depth;
  return std::max(0.0, std::min(scene.pile_far_x, scene.wall_near_x) - scene.pile_near_x);
}

}  // namespace

Action hardcoded_action(const SceneAnalysis& scene, const HardcodedParams& p) {
  if (sweepable_depth(scene) > p.d_min) return make_sweep(Height::kLow);
  if (!scene.first_wall.empty() && scene.wall_height > p.h_min)
    return make_pick(scene.wall_class, scene.wall_side);
  // Only low things are left: a pile too shallow to be worth a sweep, or a
  // wall no higher than h_min. The paper leaves this case open; taking the
  // top box of what is in front always makes progress.
  if (!scene.front_pile.empty()) return make_pick(scene.pile_class, scene.pile_side);
  return make_pick(scene.wall_class, scene.wall_side);
}

std::vector<Action> hardcoded_ranking(const SceneAnalysis& scene, const HardcodedParams& p) {
  const Action first = hardcoded_action(scene, p);
  const bool sweeping = kind(first) == ActionKind::kSweep;
  // The pick H would make, for the order of the picks.
  const Action pick = sweeping ? make_pick(scene.pile_class, scene.pile_side) : first;
  std::vector<Action> picks;
  for (Height h : {height(pick), Height::kHigh, Height::kMid, Height::kLow})
    for (Side s : {side(pick), Side::kCenter, Side::kLeft, Side::kRight}) {
      const Action a = make_pick(h, s);
      if (std::find(picks.begin(), picks.end(), a) == picks.end()) picks.push_back(a);
    }
  std::vector<Action> sweeps;
  for (Height h :
       {sweeping ? height(first) : Height::kLow, Height::kLow, Height::kMid, Height::kHigh}) {
    const Action a = make_sweep(h);
    if (std::find(sweeps.begin(), sweeps.end(), a) == sweeps.end()) sweeps.push_back(a);
  }
  std::vector<Action> out = sweeping ? sweeps : picks;
  const auto& rest = sweeping ? picks : sweeps;
  out.insert(out.end(), rest.begin(), rest.end());
  return out;
}

void read_strategy_settings(const yaml::Map& top, HardcodedParams& h,
                            ObservationParams& observation) {
  if (auto v = top.find("h_min").number(0, 10)) h.h_min = *v;
  if (auto v = top.find("d_min").number(0, 20)) h.d_min = *v;
  const yaml::Node obs = top.find("observation");
  if (!obs.present()) return;
  auto o = ObservationParams::from_json(obs.to_json());
  if (o)
    observation = *o;
  else
    obs.error(o.error().message);
}

}  // namespace plr::sim
