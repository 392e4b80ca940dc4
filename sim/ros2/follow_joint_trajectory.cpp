#include "plr/ros2/follow_joint_trajectory.hpp"

namespace plr::ros2 {

const char* to_string(GoalStatus s) {
  switch (s) {
    case GoalStatus::kUnknown:
      return "UNKNOWN";
    case GoalStatus::kAccepted:
      return "ACCEPTED";
    case GoalStatus::kExecuting:
      return "EXECUTING";
    case GoalStatus::kCanceling:
      return "CANCELING";
    case GoalStatus::kSucceeded:
      return "SUCCEEDED";
    case GoalStatus::kCanceled:
      return "CANCELED";
    case GoalStatus::kAborted:
      return "ABORTED";
  }
  return "UNKNOWN";
}

const char* to_string(TrajectoryError e) {
  switch (e) {
    case TrajectoryError::kSuccessful:
      return "SUCCESSFUL";
    case TrajectoryError::kInvalidGoal:
      return "INVALID_GOAL";
    case TrajectoryError::kInvalidJoints:
      return "INVALID_JOINTS";
    case TrajectoryError::kOldHeaderTimestamp:
      return "OLD_HEADER_TIMESTAMP";
    case TrajectoryError::kPathToleranceViolated:
      return "PATH_TOLERANCE_VIOLATED";
    case TrajectoryError::kGoalToleranceViolated:
      return "GOAL_TOLERANCE_VIOLATED";
  }
  return "UNKNOWN_ERROR";
}

std::string to_string(const GoalId& id) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string s;
  for (auto b : id) {
    s += kHex[b >> 4];
    s += kHex[b & 15];
  }
  return s;
}

}  // namespace plr::ros2
