#include "truck/truck_heuristics.hpp"

#include <algorithm>
#include <cmath>

namespace plr::generator {

namespace {
constexpr double kLayerM = 0.45;  // a typical box's height
}  // namespace

double TruckHeuristic::value(pomdp::StateId id) const {
  if (model_.is_terminal(id)) return 0.0;
  const TruckModel::State& s = model_.state(id);
  const TruckOptions& o = model_.options();
  const double k = std::max(1, o.horizon - s.depth);
  const double n = s.boxes_left;
  const double beyond = o.seconds_per_box * std::max(0.0, n - k);
  switch (kind_) {
    case Kind::kAnchor: {
      const double reachable = std::min(n, o.max_boxes_per_action * k);
      return -(std::max(o.min_action_s, o.min_seconds_per_box * reachable) +
               o.seconds_per_box * (n - reachable));
    }
    case Kind::kLower:
      return -(k * o.min_action_s + o.seconds_per_box * n);
    case Kind::kAnyBoxLeft:
      return -o.action_s;
    case Kind::kBoxesLeft:
      return -(o.action_s * std::min(n, k) + beyond);
    case Kind::kHighestStack: {
      const double layers = std::max(1.0, std::ceil(s.highest_stack_m / kLayerM));
      return -(o.action_s * std::min(layers, k) + beyond);
    }
  }
  return 0.0;
}

double TruckHeuristic::value(const pomdp::Belief& belief) const {
  double v = 0.0, w = 0.0;
  for (const pomdp::Particle& p : belief.particles()) {
    v += p.weight * value(p.state);
    w += p.weight;
  }
  return w > 0 ? v / w : 0.0;
}

std::string TruckHeuristic::name() const {
  switch (kind_) {
    case Kind::kAnchor:
      return "anchor";
    case Kind::kLower:
      return "lower";
    case Kind::kAnyBoxLeft:
      return "any-box-left";
    case Kind::kBoxesLeft:
      return "boxes-left";
    case Kind::kHighestStack:
      return "highest-stack";
  }
  return "?";
}

}  // namespace plr::generator
