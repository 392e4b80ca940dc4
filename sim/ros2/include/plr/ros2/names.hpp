// ROS 2 names as rmw_cyclonedds puts them on DDS, so that a ROS 2 node and a
// plain Cyclone DDS participant find each other: a topic "/ns/name" is the DDS
// topic "rt/ns/name"; a service's request and reply topics are
// "rq/<name>Request" and "rr/<name>Reply"; an action "/x" is the services
// "/x/_action/send_goal", "get_result", "cancel_goal" and the topics
// "/x/_action/feedback", "status". Type names are "<pkg>::msg::dds_::<Type>_"
// (the IDL in sim/ros2/idl follows that rule).
#pragma once

#include <plr/expected.hpp>

#include <string>

namespace plr::ros2 {

// Checks a fully qualified ROS 2 name ("/a/b_c"): a leading '/', tokens of
// letters, digits and '_' that do not start with a digit, no empty token.
// The error names the name and what is wrong.
plr::Status check_name(const std::string& name);

std::string topic_name(const std::string& ros_name);         // "rt" + name
std::string request_topic_name(const std::string& service);  // "rq" + name + "Request"
std::string reply_topic_name(const std::string& service);    // "rr" + name + "Reply"

struct ActionTopics {
  std::string send_goal_request, send_goal_reply;
  std::string get_result_request, get_result_reply;
  std::string cancel_goal_request, cancel_goal_reply;
  std::string feedback, status;
};
ActionTopics action_topics(const std::string& action_name);

}  // namespace plr::ros2
