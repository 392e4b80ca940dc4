#include "plr/ros2/names.hpp"

#include <fmt/format.h>

#include <cctype>

namespace plr::ros2 {

plr::Status check_name(const std::string& name) {
  const auto bad = [&](const std::string& why) {
    return plr::make_error(PLR_ERR_INVALID, fmt::format("ROS 2 name '{}': {}", name, why));
  };
  if (name.size() < 2 || name.size() > 200) return bad("must be 2 to 200 characters");
  if (name.front() != '/') return bad("must start with '/' (fully qualified)");
  bool token_start = true;
  for (std::size_t i = 1; i < name.size(); ++i) {
    const auto c = static_cast<unsigned char>(name[i]);
    if (c == '/') {
      if (token_start) return bad(fmt::format("empty token at {}", i));
      token_start = true;
      continue;
    }
    if (!(std::isalnum(c) || c == '_'))
      return bad(fmt::format("character '{}' at {} is not a letter, digit or '_'", name[i], i));
    if (token_start && std::isdigit(c))
      return bad(fmt::format("token at {} starts with a digit", i));
    token_start = false;
  }
  if (token_start) return bad("ends with '/'");
  return {};
}

std::string topic_name(const std::string& ros_name) {
  return "rt" + ros_name;
}
std::string request_topic_name(const std::string& service) {
  return "rq" + service + "Request";
}
std::string reply_topic_name(const std::string& service) {
  return "rr" + service + "Reply";
}

ActionTopics action_topics(const std::string& action_name) {
  const std::string a = action_name + "/_action/";
  return {request_topic_name(a + "send_goal"),
          reply_topic_name(a + "send_goal"),
          request_topic_name(a + "get_result"),
          reply_topic_name(a + "get_result"),
          request_topic_name(a + "cancel_goal"),
          reply_topic_name(a + "cancel_goal"),
          topic_name(a + "feedback"),
          topic_name(a + "status")};
}

}  // namespace plr::ros2
