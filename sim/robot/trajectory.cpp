#include "plr/sim/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace plr::sim {
namespace {

struct ScalarLimits {
  double speed = std::numeric_limits<double>::infinity();
  double accel = std::numeric_limits<double>::infinity();
};

// Limits on ds/dt and d2s/dt2 for s in [0, 1] along a -> b.
ScalarLimits path_limits(const JointVector& a, const JointVector& b, const Limits& limits) {
  ScalarLimits s;
  for (int j = 0; j < kNumJoints; ++j) {
    const double d = std::abs(b[j] - a[j]);
    if (d < 1e-12) continue;
    s.speed = std::min(s.speed, limits[j].velocity / d);
    s.accel = std::min(s.accel, limits[j].acceleration / d);
  }
  return s;
}

}  // namespace

double segment_duration(const JointVector& a, const JointVector& b, const Limits& limits) {
  const ScalarLimits s = path_limits(a, b, limits);
  if (!std::isfinite(s.speed)) return 0.0;
  if (s.speed * s.speed / s.accel >= 1.0) return 2.0 * std::sqrt(1.0 / s.accel);
  return 1.0 / s.speed + s.speed / s.accel;
}

Trajectory Trajectory::from_waypoints(const std::vector<JointVector>& waypoints,
                                      const Limits& limits) {
  if (waypoints.empty()) throw std::invalid_argument("Trajectory: no waypoints");
  Trajectory t;
  t.waypoints_ = waypoints;
  t.start_times_.push_back(0.0);
  for (std::size_t i = 0; i + 1 < waypoints.size(); ++i) {
    const ScalarLimits s = path_limits(waypoints[i], waypoints[i + 1], limits);
    Profile p;
    if (std::isfinite(s.speed)) {
      p.accel = s.accel;
      if (s.speed * s.speed / s.accel >= 1.0) {
        // Triangular: accelerate to the middle, then brake.
        p.accel_time = std::sqrt(1.0 / s.accel);
        p.duration = 2.0 * p.accel_time;
        p.peak_speed = s.accel * p.accel_time;
      } else {
        p.accel_time = s.speed / s.accel;
        p.duration = 1.0 / s.speed + p.accel_time;
        p.peak_speed = s.speed;
      }
    }
    t.profiles_.push_back(p);
    t.start_times_.push_back(t.start_times_.back() + p.duration);
  }
  return t;
}

TrajectorySample Trajectory::sample(double t) const {
  TrajectorySample out;
  if (waypoints_.empty()) return out;
  t = std::clamp(t, 0.0, duration());
  // Segment containing t (the last one for t == duration()).
  std::size_t i =
      std::upper_bound(start_times_.begin(), start_times_.end(), t) - start_times_.begin();
  i = std::clamp<std::size_t>(i, 1, profiles_.size()) - 1;
  if (profiles_.empty()) {
    out.position = waypoints_.front();
    return out;
  }
  const Profile& p = profiles_[i];
  const JointVector d = waypoints_[i + 1] - waypoints_[i];
  const double tau = std::clamp(t - start_times_[i], 0.0, p.duration);
  double s = 1.0, sd = 0.0, sdd = 0.0;
  if (p.duration > 0.0) {
    const double cruise_end = p.duration - p.accel_time;
    if (tau < p.accel_time) {
      s = 0.5 * p.accel * tau * tau;
      sd = p.accel * tau;
      sdd = p.accel;
    } else if (tau <= cruise_end) {
      s = 0.5 * p.accel * p.accel_time * p.accel_time + p.peak_speed * (tau - p.accel_time);
      sd = p.peak_speed;
    } else {
      const double left = p.duration - tau;
      s = 1.0 - 0.5 * p.accel * left * left;
      sd = p.accel * left;
      sdd = -p.accel;
    }
  }
  out.position = waypoints_[i] + d * std::clamp(s, 0.0, 1.0);
  out.velocity = d * sd;
  out.acceleration = d * sdd;
  return out;
}

std::vector<std::pair<double, TrajectorySample>> Trajectory::sampled(double dt) const {
  std::vector<std::pair<double, TrajectorySample>> out;
  if (waypoints_.empty() || !(dt > 0.0)) return out;
  const double total = duration();
  for (int k = 0; k * dt < total; ++k) out.emplace_back(k * dt, sample(k * dt));
  out.emplace_back(total, sample(total));
  return out;
}

}  // namespace plr::sim
