// Time parameterisation of joint-space paths within velocity and
// acceleration limits.
//
// Each path segment is a straight line in joint space executed rest to rest
// with a trapezoidal (or triangular) speed profile; all joints are
// synchronised, so the slowest joint sets the segment's duration and the
// robot stays on the straight segment the collision checker verified.
#pragma once

#include <array>
#include <vector>

#include "plr/sim/robot_model.hpp"

namespace plr::sim {

using Limits = std::array<JointLimits, kNumJoints>;

// Rest-to-rest duration of the straight segment a -> b (s).
double segment_duration(const JointVector& a, const JointVector& b, const Limits& limits);

struct TrajectorySample {
  JointVector position = JointVector::Zero();
  JointVector velocity = JointVector::Zero();
  JointVector acceleration = JointVector::Zero();
};

class Trajectory {
 public:
  Trajectory() = default;
  // Throws std::invalid_argument if `waypoints` is empty.
  static Trajectory from_waypoints(const std::vector<JointVector>& waypoints, const Limits& limits);

  bool empty() const { return waypoints_.empty(); }
  double duration() const { return start_times_.empty() ? 0.0 : start_times_.back(); }
  const std::vector<JointVector>& waypoints() const { return waypoints_; }
  // Time at which waypoint i is reached.
  double waypoint_time(std::size_t i) const { return start_times_[i]; }
  // State at time t, clamped to [0, duration()].
  TrajectorySample sample(double t) const;
  // Samples every dt from 0, plus the final state.
  std::vector<std::pair<double, TrajectorySample>> sampled(double dt) const;

 private:
  struct Profile {
    double accel_time = 0.0;  // of the path parameter s in [0, 1]
    double duration = 0.0;
    double peak_speed = 0.0;  // ds/dt
    double accel = 0.0;       // d2s/dt2
  };
  std::vector<JointVector> waypoints_;
  std::vector<Profile> profiles_;    // one per segment
  std::vector<double> start_times_;  // one per waypoint
};

}  // namespace plr::sim
