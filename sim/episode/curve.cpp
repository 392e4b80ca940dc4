#include "plr/episode/curve.hpp"

#include <algorithm>

namespace plr::episode {

void Curve::add(double start_s, std::uint32_t boxes, const actions::Outcome& outcome) {
  const double end_s = start_s + outcome.robot_time_s;
  const std::uint32_t after = boxes + outcome.boxes;
  std::vector<double> at = outcome.unloaded_at_s;
  std::sort(at.begin(), at.end());
  for (double t : at)
    if (boxes < after) points_.push_back({std::min(start_s + t, end_s), ++boxes});
  points_.push_back({end_s, after});
}

}  // namespace plr::episode
