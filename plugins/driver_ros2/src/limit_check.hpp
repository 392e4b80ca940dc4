// Joint limits checked before a trajectory is sent: positions, velocities and
// accelerations (between consecutive points) against the URDF's limits.
#pragma once

#include <plr/expected.hpp>
#include <plr/planning/plan_messages.hpp>
#include <plr/sim/robot_model.hpp>

#include <vector>

namespace plr::driver {

// `margin`: the fraction by which a velocity or acceleration may exceed its
// limit (the planner's own rounding); positions get 1e-6 of slack. The
// error names the point, the joint, the value and the limit.
plr::Status check_limits(const std::vector<planning::TimedPoint>& points,
                         const sim::RobotModel& robot, double margin);

}  // namespace plr::driver
