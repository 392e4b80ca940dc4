#include "joint_trajectory_controller.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace plr::emulator {

using ros2::GoalStatus;
using ros2::TrajectoryError;

JointTrajectoryController::JointTrajectoryController(ControllerOptions options,
                                                     std::vector<double> initial_positions)
    : options_(std::move(options)),
      q_(std::move(initial_positions)),
      qd_(q_.size(), 0.0),
      hold_(q_),
      stuck_(q_.size(), false) {}

int JointTrajectoryController::index_of(const std::string& joint) const {
  const auto it = std::find(options_.joints.begin(), options_.joints.end(), joint);
  return it == options_.joints.end() ? -1 : static_cast<int>(it - options_.joints.begin());
}

std::optional<ros2::GoalId> JointTrajectoryController::active_goal() const {
  if (!active_) return std::nullopt;
  return active_->id;
}

plr::Expected<std::optional<FinishedGoal>> JointTrajectoryController::accept(
    const ros2::GoalId& id, const ros2::TrajectoryGoal& goal) {
  const std::size_t n = options_.joints.size();
  const auto invalid = [](std::string why) { return plr::make_error(PLR_ERR_INVALID, why); };
  // The JTC takes a goal for all of its joints, in any order.
  if (goal.joint_names.size() != n)
    return invalid(fmt::format("INVALID_JOINTS: {} joints in the goal, the controller has {}",
                               goal.joint_names.size(), n));
  std::vector<int> order;
  for (const auto& name : goal.joint_names) {
    const int j = index_of(name);
    if (j < 0)
      return invalid(fmt::format("INVALID_JOINTS: no joint '{}' in this controller", name));
    if (std::find(order.begin(), order.end(), j) != order.end())
      return invalid(fmt::format("INVALID_JOINTS: joint '{}' twice", name));
    order.push_back(j);
  }
  if (goal.points.empty()) return invalid("INVALID_GOAL: no points");
  Active a;
  a.id = id;
  a.goal.joint_names = options_.joints;
  double last_t = -1.0;
  for (std::size_t i = 0; i < goal.points.size(); ++i) {
    const auto& p = goal.points[i];
    if (p.positions.size() != n || (!p.velocities.empty() && p.velocities.size() != n))
      return invalid(
          fmt::format("INVALID_GOAL: point {} has {} positions and {} velocities for {} "
                      "joints",
                      i, p.positions.size(), p.velocities.size(), n));
    if (!(p.time_s > last_t))
      return invalid(fmt::format("INVALID_GOAL: point {} at {:.3f} s is not after the one before",
                                 i, p.time_s));
    last_t = p.time_s;
    ros2::TrajectoryPoint mine;
    mine.time_s = p.time_s;
    mine.positions.resize(n);
    mine.velocities.assign(n, 0.0);
    for (std::size_t k = 0; k < n; ++k) {
      mine.positions[order[k]] = p.positions[k];
      if (!p.velocities.empty()) mine.velocities[order[k]] = p.velocities[k];
    }
    a.goal.points.push_back(std::move(mine));
  }
  // Tolerances: 0 keeps the controller's default, a negative one erases it.
  const auto tolerances = [&](const std::vector<ros2::JointTolerance>& given, double fallback,
                              bool velocity) -> plr::Expected<std::vector<double>> {
    std::vector<double> tol(n, fallback);
    for (const auto& t : given) {
      const int j = index_of(t.name);
      if (j < 0)
        return invalid(fmt::format("INVALID_GOAL: tolerance for unknown joint '{}'", t.name));
      const double v = velocity ? t.velocity : t.position;
      if (v < 0.0) tol[j] = 0.0;
      if (v > 0.0) tol[j] = v;
    }
    return tol;
  };
  auto path = tolerances(goal.path_tolerance, options_.path_tolerance, false);
  if (!path) return path.error();
  auto goal_pos = tolerances(goal.goal_tolerance, options_.goal_tolerance, false);
  if (!goal_pos) return goal_pos.error();
  auto goal_vel = tolerances(goal.goal_tolerance, options_.stopped_velocity_tolerance, true);
  if (!goal_vel) return goal_vel.error();
  a.path_tol = std::move(*path);
  a.goal_tol = std::move(*goal_pos);
  a.goal_vel_tol = std::move(*goal_vel);
  a.goal_time_tol = goal.goal_time_tolerance_s > 0.0 ? goal.goal_time_tolerance_s
                                                     : options_.goal_time_tolerance_s;

  std::optional<FinishedGoal> preempted;
  if (active_)
    preempted = finish(GoalStatus::kCanceled, TrajectoryError::kInvalidGoal,
                       "Current goal cancelled due to new incoming action.");
  a.start = q_;
  a.start_time = now_;
  frozen_until_ = now_ + late_start_s_;
  late_start_s_ = 0.0;
  active_ = std::move(a);
  return preempted;
}

std::optional<FinishedGoal> JointTrajectoryController::cancel(const ros2::GoalId& id) {
  if (!active_ || active_->id != id) return std::nullopt;
  return finish(GoalStatus::kCanceled, TrajectoryError::kSuccessful, "Goal cancelled");
}

FinishedGoal JointTrajectoryController::finish(GoalStatus status, TrajectoryError error,
                                               std::string why) {
  FinishedGoal f{active_->id, {status, error, std::move(why)}};
  active_.reset();
  // The JTC holds where the joints are when a goal ends early (and at the
  // goal when it succeeds, which is where they are then).
  hold_ = q_;
  return f;
}

std::vector<double> JointTrajectoryController::desired_at(const Active& a, double t,
                                                          std::vector<double>* velocity) const {
  const auto& pts = a.goal.points;
  const std::size_t n = q_.size();
  std::vector<double> q(n), qd(n, 0.0);
  if (t >= pts.back().time_s) {
    q = pts.back().positions;
  } else {
    // Before the first point the JTC interpolates from where the goal found the joints.
    ros2::TrajectoryPoint from{0.0, a.start, std::vector<double>(n, 0.0)};
    const ros2::TrajectoryPoint* p0 = &from;
    const ros2::TrajectoryPoint* p1 = &pts.front();
    for (std::size_t i = 0; i + 1 < pts.size() && t >= pts[i].time_s; ++i) {
      p0 = &pts[i];
      p1 = &pts[i + 1];
    }
    const double h = p1->time_s - p0->time_s;
    const double s = h > 0.0 ? std::clamp((t - p0->time_s) / h, 0.0, 1.0) : 1.0;
    // Cubic Hermite between the points' positions and velocities, as the
    // JTC's spline interpolation does for position-velocity trajectories.
    const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s;
    const double h01 = -2 * s * s * s + 3 * s * s, h11 = s * s * s - s * s;
    const double d00 = (6 * s * s - 6 * s) / h, d10 = 3 * s * s - 4 * s + 1;
    const double d01 = (-6 * s * s + 6 * s) / h, d11 = 3 * s * s - 2 * s;
    for (std::size_t j = 0; j < n; ++j) {
      q[j] = h00 * p0->positions[j] + h10 * h * p0->velocities[j] + h01 * p1->positions[j] +
             h11 * h * p1->velocities[j];
      qd[j] = d00 * p0->positions[j] + d10 * p0->velocities[j] + d01 * p1->positions[j] +
              d11 * p1->velocities[j];
    }
  }
  if (velocity != nullptr) *velocity = std::move(qd);
  return q;
}

std::optional<ros2::TrajectoryFeedback> JointTrajectoryController::feedback() const {
  if (!active_) return std::nullopt;
  ros2::TrajectoryFeedback fb;
  fb.stamp_s = now_;
  fb.joint_names = options_.joints;
  const double t = now_ - active_->start_time;
  fb.desired.time_s = fb.actual.time_s = fb.error.time_s = t;
  fb.desired.positions = desired_at(*active_, t, &fb.desired.velocities);
  fb.actual.positions = q_;
  fb.actual.velocities = qd_;
  for (std::size_t j = 0; j < q_.size(); ++j) {
    fb.error.positions.push_back(fb.desired.positions[j] - q_[j]);
    fb.error.velocities.push_back(fb.desired.velocities[j] - qd_[j]);
  }
  return fb;
}

std::optional<FinishedGoal> JointTrajectoryController::step(double dt) {
  now_ += dt;
  const std::size_t n = q_.size();
  const double t = active_ ? now_ - active_->start_time : 0.0;
  const std::vector<double> desired = active_ ? desired_at(*active_, t, nullptr) : hold_;
  const double follow = options_.lag_s > 0.0 ? 1.0 - std::exp(-dt / options_.lag_s) : 1.0;
  for (std::size_t j = 0; j < n; ++j) {
    const double before = q_[j];
    if (!stuck_[j] && now_ > frozen_until_) q_[j] += (desired[j] - q_[j]) * follow;
    qd_[j] = (q_[j] - before) / dt;
  }
  if (!active_) return std::nullopt;
  const Active& a = *active_;
  const double end = a.goal.points.back().time_s;
  if (t <= end) {
    for (std::size_t j = 0; j < n; ++j) {
      const double err = std::abs(desired[j] - q_[j]);
      if (a.path_tol[j] > 0.0 && err > a.path_tol[j])
        return finish(GoalStatus::kAborted, TrajectoryError::kPathToleranceViolated,
                      fmt::format("Aborted due to path tolerance violation: joint {} is {:.4f} "
                                  "from its reference at {:.3f} s (tolerance {:.4f})",
                                  options_.joints[j], err, t, a.path_tol[j]));
    }
    return std::nullopt;
  }
  std::string outside;
  for (std::size_t j = 0; j < n && outside.empty(); ++j) {
    const double err = std::abs(desired[j] - q_[j]);
    if (a.goal_tol[j] > 0.0 && err > a.goal_tol[j])
      outside = fmt::format("joint {} is {:.4f} from its goal (tolerance {:.4f})",
                            options_.joints[j], err, a.goal_tol[j]);
    else if (a.goal_vel_tol[j] > 0.0 && std::abs(qd_[j]) > a.goal_vel_tol[j])
      outside = fmt::format("joint {} still moves at {:.4f} (tolerance {:.4f})", options_.joints[j],
                            std::abs(qd_[j]), a.goal_vel_tol[j]);
  }
  if (outside.empty())
    return finish(GoalStatus::kSucceeded, TrajectoryError::kSuccessful,
                  "Goal successfully reached!");
  if (a.goal_time_tol > 0.0 && t > end + a.goal_time_tol)
    return finish(GoalStatus::kAborted, TrajectoryError::kGoalToleranceViolated,
                  fmt::format("Aborted due to goal tolerance violation {:.3f} s after the end: {}",
                              t - end, outside));
  return std::nullopt;
}

plr::Status JointTrajectoryController::stick_joint(const std::string& joint) {
  const int j = index_of(joint);
  if (j < 0) return plr::make_error(PLR_ERR_INVALID, "stuck_joint: no joint '" + joint + "'");
  stuck_[j] = true;
  return {};
}

plr::Status JointTrajectoryController::knock_joint(const std::string& joint, double offset) {
  const int j = index_of(joint);
  if (j < 0)
    return plr::make_error(PLR_ERR_INVALID, "tolerance_violation: no joint '" + joint + "'");
  q_[j] += offset;
  return {};
}

void JointTrajectoryController::clear_faults() {
  std::fill(stuck_.begin(), stuck_.end(), false);
  late_start_s_ = 0.0;
  frozen_until_ = 0.0;
}

}  // namespace plr::emulator
