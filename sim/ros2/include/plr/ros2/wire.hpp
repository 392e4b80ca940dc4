// Between the values of follow_joint_trajectory.hpp and the C structs idlc
// generates from sim/ros2/idl. Encoding fills a struct with memory of
// dds_alloc, which Wire<T> frees (DDS_FREE_CONTENTS); decoding checks sizes
// against the bounds and names what is wrong.
#pragma once

#include <plr/expected.hpp>
#include <plr/ros2/follow_joint_trajectory.hpp>
#include <plr/ros2/io_command.hpp>

#include <control_msgs.h>
#include <sensor_msgs.h>
#include <std_msgs.h>

namespace plr::ros2 {

// A generated struct that owns its contents.
template <class T>
class Wire {
 public:
  explicit Wire(const dds_topic_descriptor_t* desc) : desc_(desc) {}
  ~Wire() { dds_sample_free(&msg, desc_, DDS_FREE_CONTENTS); }
  Wire(const Wire&) = delete;
  Wire& operator=(const Wire&) = delete;
  T msg{};

 private:
  const dds_topic_descriptor_t* desc_;
};

builtin_interfaces_msg_dds__Duration_ to_duration(double s);
builtin_interfaces_msg_dds__Time_ to_time(double s);
double seconds(const builtin_interfaces_msg_dds__Duration_& d);
double seconds(const builtin_interfaces_msg_dds__Time_& t);

void encode(const TrajectoryGoal& goal, control_msgs_action_dds__FollowJointTrajectory_Goal_& out);
plr::Expected<TrajectoryGoal> decode(
    const control_msgs_action_dds__FollowJointTrajectory_Goal_& in);

void encode(const TrajectoryFeedback& fb,
            control_msgs_action_dds__FollowJointTrajectory_Feedback_& out);
plr::Expected<TrajectoryFeedback> decode(
    const control_msgs_action_dds__FollowJointTrajectory_Feedback_& in);

void encode(const JointStateSample& js, sensor_msgs_msg_dds__JointState_& out);
plr::Expected<JointStateSample> decode(const sensor_msgs_msg_dds__JointState_& in);

void encode(const IoCommand& io, std_msgs_msg_dds__Float64MultiArray_& out);
// Refuses values other than 0 and 1, and fewer than the vacuum and conveyor.
plr::Expected<IoCommand> decode(const std_msgs_msg_dds__Float64MultiArray_& in);

// A string of dds_alloc memory (freed with its struct).
char* wire_string(const std::string& s);

}  // namespace plr::ros2
