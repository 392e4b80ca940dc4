// control_msgs/action/FollowJointTrajectory as values: the goal a driver
// sends, the feedback and result a joint trajectory controller answers with,
// and their codes (the constants of the .action and of action_msgs/GoalStatus).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace plr::ros2 {

// Bounds on what a peer may send: larger messages are refused, not stored.
inline constexpr std::size_t kMaxJoints = 64;
inline constexpr std::size_t kMaxPoints = 100000;
inline constexpr std::size_t kMaxNameSize = 256;

enum class GoalStatus : std::int8_t {
  kUnknown = 0,
  kAccepted = 1,
  kExecuting = 2,
  kCanceling = 3,
  kSucceeded = 4,
  kCanceled = 5,
  kAborted = 6,
};

// FollowJointTrajectory_Result error_code.
enum class TrajectoryError : std::int32_t {
  kSuccessful = 0,
  kInvalidGoal = -1,
  kInvalidJoints = -2,
  kOldHeaderTimestamp = -3,
  kPathToleranceViolated = -4,
  kGoalToleranceViolated = -5,
};

const char* to_string(GoalStatus s);
const char* to_string(TrajectoryError e);

using GoalId = std::array<std::uint8_t, 16>;
std::string to_string(const GoalId& id);  // hex

struct TrajectoryPoint {
  double time_s = 0.0;  // time_from_start
  std::vector<double> positions;
  std::vector<double> velocities;  // empty or one per joint
};

// JointTolerance: 0 leaves the controller's default, -1 erases it.
struct JointTolerance {
  std::string name;
  double position = 0.0;
  double velocity = 0.0;
  double acceleration = 0.0;
};

struct TrajectoryGoal {
  std::vector<std::string> joint_names;
  std::vector<TrajectoryPoint> points;
  std::vector<JointTolerance> path_tolerance;
  std::vector<JointTolerance> goal_tolerance;
  double goal_time_tolerance_s = 0.0;
};

struct TrajectoryResult {
  GoalStatus status = GoalStatus::kUnknown;
  TrajectoryError error = TrajectoryError::kSuccessful;
  std::string error_string;
};

struct TrajectoryFeedback {
  double stamp_s = 0.0;
  std::vector<std::string> joint_names;
  TrajectoryPoint desired, actual, error;
};

struct JointStateSample {
  double stamp_s = 0.0;
  std::vector<std::string> names;
  std::vector<double> position;
  std::vector<double> velocity;
};

}  // namespace plr::ros2
