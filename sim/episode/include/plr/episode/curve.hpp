// The unloading curve: boxes unloaded against robot time (execution and
// modelled planning, so the same run gives the same curve on any machine).
#pragma once

#include <cstdint>
#include <vector>

#include "plr/actions/action_model.hpp"

namespace plr::episode {

struct CurvePoint {
  double robot_time_s = 0;
  std::uint32_t boxes = 0;
};

// A step where each box left, and a point at each action's end with the
// count the world's state says.
class Curve {
 public:
  // An action that began at `start_s` with `boxes` unloaded.
  void add(double start_s, std::uint32_t boxes, const actions::Outcome& outcome);
  const std::vector<CurvePoint>& points() const { return points_; }

 private:
  std::vector<CurvePoint> points_;
};

}  // namespace plr::episode
