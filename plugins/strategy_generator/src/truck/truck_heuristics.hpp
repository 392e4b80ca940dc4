// Value estimates of truck beliefs (values are negated robot seconds): the
// probability-weighted mean over the belief's particles of a per-state
// estimate. With k actions left before the horizon, n boxes left, T the
// terminal seconds per box and a a typical action's time:
//   anchor (admissible): a non-goal state needs one more action, which
//     takes at least min_action_s, and no action unloads more than m =
//     max_boxes_per_action boxes: -(min_action_s + T * max(0, n - m * k));
//   lower (an estimate of a lower bound): every remaining action wasted,
//     -(k * min_action_s + T * n);
// and the paper's three, inadmissible:
//   any box left:  -a if n > 0;
//   boxes left:    -(a * min(n, k) + T * max(0, n - k))  (a box an action);
//   highest stack: -(a * min(l, k) + T * max(0, n - k)), l = the highest
//     stack's layers (its top over a 0.45 m box).
#pragma once

#include <string>

#include "pomdp/heuristics.hpp"
#include "truck/truck_model.hpp"

namespace plr::generator {

class TruckHeuristic final : public pomdp::Heuristic {
 public:
  enum class Kind { kAnchor, kLower, kAnyBoxLeft, kBoxesLeft, kHighestStack };

  TruckHeuristic(const TruckModel& model, Kind kind) : model_(model), kind_(kind) {}
  double value(const pomdp::Belief& belief) const override;
  std::string name() const override;
  // The estimate of one state.
  double value(pomdp::StateId state) const;

 private:
  const TruckModel& model_;
  Kind kind_;
};

}  // namespace plr::generator
