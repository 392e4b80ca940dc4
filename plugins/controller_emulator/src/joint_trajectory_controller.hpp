// What ros2_control's joint trajectory controller does with a
// FollowJointTrajectory goal, on simulated joints: validation, one active
// goal (a new one preempts it), path and goal tolerances, goal time
// tolerance, abort holding position, the result codes. The joints follow the
// reference with a first-order lag. Faults can be injected. No DDS and no
// clock here: step() advances controller time, so tests are deterministic.
#pragma once

#include <plr/expected.hpp>
#include <plr/ros2/follow_joint_trajectory.hpp>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace plr::emulator {

struct ControllerOptions {
  std::vector<std::string> joints;
  double lag_s = 0.02;  // time constant of each joint's tracking, controller s (0: none)
  // The controller's defaults, used where a goal leaves a tolerance at 0
  // (as the JTC's constraints.* parameters; 0 means unchecked).
  double path_tolerance = 0.0;
  double goal_tolerance = 0.0;
  double goal_time_tolerance_s = 0.0;
  double stopped_velocity_tolerance = 0.01;
};

struct FinishedGoal {
  ros2::GoalId id{};
  ros2::TrajectoryResult result;
};

class JointTrajectoryController {
 public:
  JointTrajectoryController(ControllerOptions options, std::vector<double> initial_positions);

  // Accepts a valid goal, preempting the active one (returned, CANCELED with
  // INVALID_GOAL as the JTC does). An invalid goal is rejected: the error
  // says why; the active goal goes on.
  plr::Expected<std::optional<FinishedGoal>> accept(const ros2::GoalId& id,
                                                    const ros2::TrajectoryGoal& goal);
  // Cancels the active goal if it is `id`: the joints hold where they are.
  std::optional<FinishedGoal> cancel(const ros2::GoalId& id);
  // Advances controller time by dt; returns the goal that ended in it.
  std::optional<FinishedGoal> step(double dt);

  double now() const { return now_; }
  const std::vector<double>& positions() const { return q_; }
  const std::vector<double>& velocities() const { return qd_; }
  const std::vector<std::string>& joints() const { return options_.joints; }
  std::optional<ros2::GoalId> active_goal() const;
  // Desired, actual and error of the active goal (feedback), if any.
  std::optional<ros2::TrajectoryFeedback> feedback() const;

  // Faults: a joint that no longer moves; a knock that moves a joint by
  // `offset` at once; joints that start moving only `delay_s` after the next
  // goal is accepted; clear_faults() ends them.
  plr::Status stick_joint(const std::string& joint);
  plr::Status knock_joint(const std::string& joint, double offset);
  void delay_next_start(double delay_s) { late_start_s_ = delay_s; }
  void clear_faults();

 private:
  struct Active {
    ros2::GoalId id{};
    ros2::TrajectoryGoal goal;  // joints in the controller's order
    std::vector<double> start;  // positions when accepted
    double start_time = 0.0;
    std::vector<double> path_tol, goal_tol, goal_vel_tol;
    double goal_time_tol = 0.0;
  };

  std::vector<double> desired_at(const Active& a, double t, std::vector<double>* velocity) const;
  FinishedGoal finish(ros2::GoalStatus status, ros2::TrajectoryError error, std::string why);
  int index_of(const std::string& joint) const;

  ControllerOptions options_;
  double now_ = 0.0;
  std::vector<double> q_, qd_;
  std::vector<double> hold_;
  std::optional<Active> active_;
  std::vector<bool> stuck_;
  double late_start_s_ = 0.0;
  double frozen_until_ = 0.0;
};

}  // namespace plr::emulator
