// The driver's side of a ros2_control joint trajectory controller over DDS:
// a FollowJointTrajectory action client (send_goal, get_result, cancel_goal,
// feedback) and a joint_states reader, with ROS 2's types and names
// (sim/ros2). A thread takes what arrives; callers wait on it.
#pragma once

#include <plr/expected.hpp>
#include <plr/ros2/follow_joint_trajectory.hpp>
#include <plr/ros2/io_command.hpp>

#include <dds/dds.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace plr::driver {

using WallClock = std::chrono::steady_clock;

struct ClientOptions {
  std::string action = "/unloader_controller/follow_joint_trajectory";
  std::string joint_states = "/joint_states";
  // Where the I/O commands go (plr/ros2/io_command.hpp); empty: nowhere.
  std::string io_commands = "/io_controller/commands";
  std::uint32_t domain_id = 0;
  bool loopback_only = false;
};

struct ReceivedState {
  ros2::JointStateSample sample;
  WallClock::time_point received;
};

class ControllerClient {
 public:
  ControllerClient() = default;
  ~ControllerClient() { close(); }
  ControllerClient(const ControllerClient&) = delete;
  ControllerClient& operator=(const ControllerClient&) = delete;

  plr::Status open(const ClientOptions& options);
  void close();

  std::optional<ReceivedState> latest_state() const;
  // Joint states are numbered as they arrive; the driver records a motion as
  // the samples between two numbers (the last 100000 are kept).
  std::uint64_t states_received() const;
  std::vector<ros2::JointStateSample> states_since(std::uint64_t first) const;

  // Sends a goal and waits for the controller to accept it; an error when it
  // rejects it or does not answer within `timeout`.
  plr::Status send_goal(const ros2::GoalId& id, const ros2::TrajectoryGoal& goal,
                        std::chrono::milliseconds timeout);
  // Asks for the goal's result (answered when the goal ends).
  plr::Status request_result(const ros2::GoalId& id);
  std::optional<ros2::TrajectoryResult> result(const ros2::GoalId& id) const;
  std::optional<ros2::TrajectoryFeedback> feedback(const ros2::GoalId& id) const;
  // Cancels the goal: the controller holds the joints where they are.
  plr::Status cancel(const ros2::GoalId& id);
  // Sends the I/O command once an I/O controller subscribes (it gets the
  // last one on joining, too); an error when none does within `timeout`.
  // Nothing to do without an `io_commands` topic.
  plr::Status send_io(const ros2::IoCommand& io, std::chrono::milliseconds timeout);
  // Drops what is kept of a goal that is over.
  void forget(const ros2::GoalId& id);
  // Returns when something arrived, or after `d`.
  void wait(std::chrono::milliseconds d) const;

 private:
  void run();
  void take_all();
  // Until `writer` has a subscriber and `reader` (unless 0) a publisher.
  bool wait_matched(dds_entity_t writer, dds_entity_t reader, std::chrono::milliseconds timeout);

  ClientOptions options_;
  dds_entity_t participant_ = 0, waitset_ = 0;
  dds_entity_t goal_req_ = 0, goal_rep_ = 0, result_req_ = 0, result_rep_ = 0, cancel_req_ = 0,
               cancel_rep_ = 0, feedback_ = 0, joint_states_ = 0, io_ = 0;
  std::uint64_t client_guid_ = 0;
  std::atomic<std::int64_t> sequence_{0};

  mutable std::mutex m_;
  mutable std::condition_variable cv_;
  std::deque<ros2::JointStateSample> states_;
  std::uint64_t states_first_ = 0;  // number of states_.front()
  std::optional<ReceivedState> latest_;
  std::map<std::int64_t, bool> accepted_;  // send_goal sequence -> accepted
  std::map<ros2::GoalId, ros2::TrajectoryResult> results_;
  std::map<std::int64_t, ros2::GoalId> result_calls_;
  std::map<ros2::GoalId, ros2::TrajectoryFeedback> feedback_of_;

  std::atomic<bool> running_{false};
  std::thread thread_;
};

}  // namespace plr::driver
