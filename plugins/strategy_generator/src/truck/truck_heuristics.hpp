// Value estimates of truck beliefs (values are negated robot seconds): the
// probability-weighted mean over the belief's particles of a per-state
// estimate. With k actions left before the horizon, n boxes left, T the
// terminal seconds per box and a a typical action's time:
//   anchor (admissible): at most u = min(n, m * k) boxes leave before the
//     horizon (m = max_boxes_per_action), each taking at least r =
//     min_seconds_per_box, and a non-goal state needs one more action of
//     at least min_action_s: -(max(min_action_s, r * u) + T * (n - u));
//   lower (an estimate of a lower bound): every remaining action wasted,
//     -(k * min_action_s + T * n);
// and the paper's three, inadmissible:
//   any box left:  -a if n > 0;
//   boxes left:    -(a * min(n, k) + T * max(0, n - k))  (a box an action);
//   highest stack: -(a * min(l, k) + T * max(0, n - k)), l = the highest
//     stack's layers (its top over a 0.45 m box).
#pragma once

#include <string>

#include "plr/pomdp/heuristics.hpp"
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
