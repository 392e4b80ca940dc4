#include "limit_check.hpp"

#include <fmt/format.h>

#include <cmath>

namespace plr::driver {

plr::Status check_limits(const std::vector<planning::TimedPoint>& points,
                         const sim::RobotModel& robot, double margin) {
  const auto refuse = [&](std::size_t i, int j, const std::string& what) {
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("trajectory point {} (t={:.3f} s), joint {}: {}", i,
                                       points[i].time_s, sim::kJointNames[j], what));
  };
  if (points.empty()) return plr::make_error(PLR_ERR_INVALID, "trajectory: no points");
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& p = points[i];
    if (i > 0 && !(p.time_s > points[i - 1].time_s))
      return plr::make_error(PLR_ERR_INVALID,
                             fmt::format("trajectory point {}: time {:.3f} s is not after {:.3f} s",
                                         i, p.time_s, points[i - 1].time_s));
    for (int j = 0; j < sim::kNumJoints; ++j) {
      const sim::JointLimits& l = robot.limits(j);
      const double q = p.position[j], v = p.velocity[j];
      if (!std::isfinite(q) || !std::isfinite(v)) return refuse(i, j, "not a finite number");
      if (q < l.lower - 1e-6 || q > l.upper + 1e-6)
        return refuse(i, j,
                      fmt::format("position {:.4f} outside its limits [{:.4f}, {:.4f}]", q, l.lower,
                                  l.upper));
      if (std::abs(v) > l.velocity * (1.0 + margin))
        return refuse(i, j, fmt::format("velocity {:.4f} beyond its limit {:.4f}", v, l.velocity));
      if (i > 0) {
        const double a = (v - points[i - 1].velocity[j]) / (p.time_s - points[i - 1].time_s);
        if (std::abs(a) > l.acceleration * (1.0 + margin))
          return refuse(
              i, j, fmt::format("acceleration {:.4f} beyond its limit {:.4f}", a, l.acceleration));
      }
    }
  }
  return {};
}

}  // namespace plr::driver
