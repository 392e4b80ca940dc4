// What the driver writes on DDS, read back by a peer built only from the ROS 2
// interface definitions (test/ros2_reference, written from the .msg and
// .action field lists) and rmw_cyclonedds's naming rules: the DDS topic and
// type names must match for the reader to see anything at all, and the fields
// must line up for the values to come out right. This binary links nothing of
// sim/ros2.
#include "control_msgs/action/FollowJointTrajectory.h"
#include "sensor_msgs/msg/JointState.h"
#include "std_msgs/msg/Float64MultiArray.h"

#include <dds/dds.h>

#include <plr/messages.hpp>
#include <plr/testing/fake_kernel.hpp>

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <string>
#include <thread>

namespace {

using namespace std::chrono_literals;

// Topics of the action "/unloader_controller/follow_joint_trajectory" and the
// topic "/joint_states", by the rules: "rq"/"rr" + service + "Request"/"Reply",
// "rt" + topic; an action's services and topics live under "<action>/_action/".
constexpr const char* kGoalRequest =
    "rq/unloader_controller/follow_joint_trajectory/_action/send_goalRequest";
constexpr const char* kGoalReply =
    "rr/unloader_controller/follow_joint_trajectory/_action/send_goalReply";
constexpr const char* kResultRequest =
    "rq/unloader_controller/follow_joint_trajectory/_action/get_resultRequest";
constexpr const char* kResultReply =
    "rr/unloader_controller/follow_joint_trajectory/_action/get_resultReply";
constexpr const char* kJointStates = "rt/joint_states";
// The I/O, as ros2_control's forward_command_controller "io_controller" takes it.
constexpr const char* kIoCommands = "rt/io_controller/commands";
constexpr const char* kJoints[] = {"base_x", "arm_1",  "arm_2",  "arm_3",
                                   "arm_4",  "nose_1", "nose_2", "nose_3"};
constexpr double kHome[] = {0.0, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0};

// Its own DDS domain, so that tests running at the same time do not meet.
int test_domain() {
  return 100 + static_cast<int>(::getpid() % 100);
}

dds_entity_t loopback_participant(int domain) {
  const char* xml =
      R"(<CycloneDDS xmlns="https://cdds.io/config"><Domain Id="any"><General><Interfaces>)"
      R"(<NetworkInterface name="lo" multicast="false"/></Interfaces>)"
      "<AllowMulticast>false</AllowMulticast></General><Discovery>"
      "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>60"
      R"(</MaxAutoParticipantIndex><Peers><Peer Address="127.0.0.1"/></Peers></Discovery>)"
      "</Domain></CycloneDDS>";
  dds_create_domain(static_cast<dds_domainid_t>(domain), xml);
  return dds_create_participant(static_cast<dds_domainid_t>(domain), nullptr, nullptr);
}

dds_entity_t endpoint(dds_entity_t p, const char* name, const dds_topic_descriptor_t* desc,
                      bool reader) {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 10);
  const dds_entity_t t = dds_create_topic(p, desc, name, nullptr, nullptr);
  const dds_entity_t e =
      reader ? dds_create_reader(p, t, q, nullptr) : dds_create_writer(p, t, q, nullptr);
  dds_delete_qos(q);
  return e;
}

template <class T>
bool take_one(dds_entity_t reader, T& out, std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < until) {
    void* sample = &out;
    dds_sample_info_t info;
    if (dds_take(reader, &sample, &info, 1, 1) == 1 && info.valid_data) return true;
    std::this_thread::sleep_for(2ms);
  }
  return false;
}

TEST(DriverWire, WhatTheDriverSendsDecodesWithTheRos2Definitions) {
  const int domain = test_domain();
  const dds_entity_t p = loopback_participant(domain);
  ASSERT_GT(p, 0);
  const dds_entity_t goals =
      endpoint(p, kGoalRequest,
               &control_msgs_action_dds__FollowJointTrajectory_SendGoal_Request__desc, true);
  const dds_entity_t accepts =
      endpoint(p, kGoalReply,
               &control_msgs_action_dds__FollowJointTrajectory_SendGoal_Response__desc, false);
  const dds_entity_t result_calls =
      endpoint(p, kResultRequest,
               &control_msgs_action_dds__FollowJointTrajectory_GetResult_Request__desc, true);
  const dds_entity_t results =
      endpoint(p, kResultReply,
               &control_msgs_action_dds__FollowJointTrajectory_GetResult_Response__desc, false);
  const dds_entity_t states =
      endpoint(p, kJointStates, &sensor_msgs_msg_dds__JointState__desc, false);
  const dds_entity_t io =
      endpoint(p, kIoCommands, &std_msgs_msg_dds__Float64MultiArray__desc, true);
  for (dds_entity_t e : {goals, accepts, result_calls, results, states, io}) ASSERT_GT(e, 0);

  // Joint states from the "controller", so the driver's watchdog is content.
  std::atomic<bool> publishing{true};
  struct Stop {
    std::atomic<bool>& flag;
    std::thread thread;
    ~Stop() {
      flag = false;
      thread.join();
    }
  } publisher{publishing, std::thread([&] {
                char* names[8];
                for (int j = 0; j < 8; ++j) names[j] = const_cast<char*>(kJoints[j]);
                double position[8], velocity[8] = {};
                std::memcpy(position, kHome, sizeof position);
                for (std::int32_t k = 0; publishing; ++k) {
                  sensor_msgs_msg_dds__JointState_ js{};
                  js.header.stamp.sec = k / 100;
                  js.header.stamp.nanosec = static_cast<std::uint32_t>(k % 100) * 10000000u;
                  js.header.frame_id = const_cast<char*>("");
                  js.name = {8, 8, names, false};
                  js.position = {8, 8, position, false};
                  js.velocity = {8, 8, velocity, false};
                  dds_write(states, &js);
                  std::this_thread::sleep_for(10ms);
                }
              })};

  plr::testing::FakeKernel k;
  auto node =
      k.load_node(DRIVER_SO, plr::testing::NodeOptions().with_params(
                                 R"({"loopback_only": true, "world_execute": "", "domain_id": )" +
                                 std::to_string(domain) + "}"));
  ASSERT_TRUE(node);
  ASSERT_TRUE(node->configure());
  ASSERT_TRUE(node->activate());
  // Wait for the driver's first joint state, then ask for a motion of base_x.
  std::this_thread::sleep_for(300ms);
  flatbuffers::FlatBufferBuilder fbb;
  std::vector<flatbuffers::Offset<plr::msg::TrajectoryPoint>> pts;
  std::vector<double> q(kHome, kHome + 8), zero(8, 0.0);
  pts.push_back(plr::msg::CreateTrajectoryPointDirect(fbb, 0.0, &q, &zero));
  q[0] = 0.4;
  pts.push_back(plr::msg::CreateTrajectoryPointDirect(fbb, 1.5, &q, &zero));
  fbb.Finish(
      plr::msg::CreateExecuteRequest(fbb, plr::msg::CreateTrajectory(fbb, fbb.CreateVector(pts))));
  auto call = k.call_async<plr::msg::ExecuteRequest, plr::msg::ExecuteOutcome>("sim/execute", fbb);
  k.spin();

  // Before the goal, the I/O: the conveyor runs during a motion (an
  // ExecuteRequest's default), the vacuum stays off, all 20 cup valves open.
  std_msgs_msg_dds__Float64MultiArray_ command{};
  ASSERT_TRUE(take_one(io, command, 10s)) << "no I/O command on " << kIoCommands;
  ASSERT_EQ(command.data._length, 22u);
  EXPECT_EQ(command.data._buffer[0], 0.0) << "vacuum";
  EXPECT_EQ(command.data._buffer[1], 1.0) << "conveyor";
  for (std::uint32_t i = 2; i < 22; ++i) EXPECT_EQ(command.data._buffer[i], 1.0) << "cup " << i - 2;
  ASSERT_EQ(command.layout.dim._length, 1u);
  EXPECT_EQ(command.layout.dim._buffer[0].size, 22u);
  dds_sample_free(&command, &std_msgs_msg_dds__Float64MultiArray__desc, DDS_FREE_CONTENTS);

  control_msgs_action_dds__FollowJointTrajectory_SendGoal_Request_ goal{};
  ASSERT_TRUE(take_one(goals, goal, 10s)) << "no goal on " << kGoalRequest;
  const auto& traj = goal.goal.trajectory;
  ASSERT_EQ(traj.joint_names._length, 8u);
  for (int j = 0; j < 8; ++j) EXPECT_STREQ(traj.joint_names._buffer[j], kJoints[j]);
  ASSERT_EQ(traj.points._length, 2u);
  EXPECT_EQ(traj.points._buffer[1].time_from_start.sec, 1);
  EXPECT_EQ(traj.points._buffer[1].time_from_start.nanosec, 500000000u);
  ASSERT_EQ(traj.points._buffer[1].positions._length, 8u);
  EXPECT_DOUBLE_EQ(traj.points._buffer[1].positions._buffer[0], 0.4);
  EXPECT_DOUBLE_EQ(traj.points._buffer[1].positions._buffer[2], -1.0);
  EXPECT_EQ(goal.goal.path_tolerance._length, 8u);
  EXPECT_STREQ(goal.goal.path_tolerance._buffer[2].name, "arm_2");
  EXPECT_DOUBLE_EQ(goal.goal.path_tolerance._buffer[2].position, 0.1);
  EXPECT_DOUBLE_EQ(goal.goal.goal_tolerance._buffer[0].position, 0.01);
  EXPECT_EQ(goal.goal.goal_time_tolerance.sec, 1);
  EXPECT_EQ(goal.goal.multi_dof_trajectory.points._length, 0u);

  // Accept it with the request's header, as an rmw_cyclonedds server does.
  control_msgs_action_dds__FollowJointTrajectory_SendGoal_Response_ accept{};
  accept.request_header_guid = goal.request_header_guid;
  accept.request_header_sequence = goal.request_header_sequence;
  accept.accepted = true;
  ASSERT_EQ(dds_write(accepts, &accept), DDS_RETCODE_OK);
  control_msgs_action_dds__FollowJointTrajectory_GetResult_Request_ asked{};
  ASSERT_TRUE(take_one(result_calls, asked, 10s)) << "no get_result on " << kResultRequest;
  EXPECT_EQ(std::memcmp(asked.goal_id.uuid, goal.goal_id.uuid, 16), 0);
  EXPECT_EQ(asked.request_header_guid, goal.request_header_guid);
  EXPECT_GT(asked.request_header_sequence, goal.request_header_sequence);

  // SUCCEEDED (action_msgs/GoalStatus 4), error_code SUCCESSFUL.
  control_msgs_action_dds__FollowJointTrajectory_GetResult_Response_ done{};
  done.request_header_guid = asked.request_header_guid;
  done.request_header_sequence = asked.request_header_sequence;
  done.status = 4;
  done.result.error_string = const_cast<char*>("");
  ASSERT_EQ(dds_write(results, &done), DDS_RETCODE_OK);
  for (int i = 0; i < 1000 && !call.ready(); ++i) {
    k.spin();
    std::this_thread::sleep_for(5ms);
  }
  auto outcome = call.result();
  ASSERT_TRUE(outcome) << outcome.error().message;
  EXPECT_TRUE(outcome.value()->ok());

  dds_sample_free(&goal, &control_msgs_action_dds__FollowJointTrajectory_SendGoal_Request__desc,
                  DDS_FREE_CONTENTS);
  dds_sample_free(&asked, &control_msgs_action_dds__FollowJointTrajectory_GetResult_Request__desc,
                  DDS_FREE_CONTENTS);
  dds_delete(p);
}

}  // namespace
