#include "controller_client.hpp"

#include <plr/ros2/domain.hpp>
#include <plr/ros2/names.hpp>
#include <plr/ros2/wire.hpp>

#include <fmt/format.h>

#include <cstring>
#include <random>

namespace plr::driver {
namespace {

constexpr std::size_t kKeptStates = 100000;

// With ROS 2's default QoS unless `qos` is given (taken over).
dds_entity_t endpoint(dds_entity_t participant, const std::string& name,
                      const dds_topic_descriptor_t* desc, bool is_reader,
                      dds_qos_t* qos = ros2::default_qos()) {
  const dds_entity_t t = dds_create_topic(participant, desc, name.c_str(), nullptr, nullptr);
  if (t < 0) {
    dds_delete_qos(qos);
    return t;
  }
  const dds_entity_t e = is_reader ? dds_create_reader(participant, t, qos, nullptr)
                                   : dds_create_writer(participant, t, qos, nullptr);
  dds_delete_qos(qos);
  return e;
}

ros2::GoalId goal_id_of(const unique_identifier_msgs_msg_dds__UUID_& u) {
  ros2::GoalId id{};
  std::memcpy(id.data(), u.uuid, id.size());
  return id;
}

template <class T, class F>
void take_each(dds_entity_t reader, F&& handle) {
  void* samples[32] = {};
  dds_sample_info_t infos[32];
  for (;;) {
    const int n = dds_take(reader, samples, infos, 32, 32);
    if (n <= 0) return;
    for (int i = 0; i < n; ++i)
      if (infos[i].valid_data) handle(*static_cast<const T*>(samples[i]));
    dds_return_loan(reader, samples, n);
  }
}

}  // namespace

plr::Status ControllerClient::open(const ClientOptions& options) {
  options_ = options;
  std::vector<std::pair<const char*, std::string>> names = {{"action", options.action},
                                                            {"joint_states", options.joint_states}};
  if (!options.io_commands.empty()) names.emplace_back("io_commands", options.io_commands);
  for (const auto& [key, name] : names)
    if (auto ok = ros2::check_name(name); !ok)
      return plr::make_error(PLR_ERR_INVALID,
                             fmt::format("param '{}': {}", key, ok.error().message));
  auto p = ros2::open_participant(options.domain_id, options.loopback_only);
  if (!p) return p.error();
  participant_ = *p;
  const auto a = ros2::action_topics(options.action);
  goal_req_ =
      endpoint(participant_, a.send_goal_request,
               &control_msgs_action_dds__FollowJointTrajectory_SendGoal_Request__desc, false);
  goal_rep_ =
      endpoint(participant_, a.send_goal_reply,
               &control_msgs_action_dds__FollowJointTrajectory_SendGoal_Response__desc, true);
  result_req_ =
      endpoint(participant_, a.get_result_request,
               &control_msgs_action_dds__FollowJointTrajectory_GetResult_Request__desc, false);
  result_rep_ =
      endpoint(participant_, a.get_result_reply,
               &control_msgs_action_dds__FollowJointTrajectory_GetResult_Response__desc, true);
  cancel_req_ = endpoint(participant_, a.cancel_goal_request,
                         &action_msgs_srv_dds__CancelGoal_Request__desc, false);
  cancel_rep_ = endpoint(participant_, a.cancel_goal_reply,
                         &action_msgs_srv_dds__CancelGoal_Response__desc, true);
  feedback_ = endpoint(participant_, a.feedback,
                       &control_msgs_action_dds__FollowJointTrajectory_FeedbackMessage__desc, true);
  joint_states_ = endpoint(participant_, ros2::topic_name(options.joint_states),
                           &sensor_msgs_msg_dds__JointState__desc, true);
  // The last I/O command stays with the writer: a controller that (re)joins gets it.
  if (!options.io_commands.empty())
    io_ = endpoint(participant_, ros2::topic_name(options.io_commands),
                   &std_msgs_msg_dds__Float64MultiArray__desc, false, ros2::status_qos());
  for (dds_entity_t e : {goal_req_, goal_rep_, result_req_, result_rep_, cancel_req_, cancel_rep_,
                         feedback_, joint_states_, io_})
    if (e < 0) {
      close();
      return plr::make_error(PLR_ERR_INTERNAL, fmt::format("DDS endpoint for action '{}': {}",
                                                           options.action, dds_strretcode(e)));
    }
  waitset_ = dds_create_waitset(participant_);
  for (dds_entity_t r : {goal_rep_, result_rep_, cancel_rep_, feedback_, joint_states_})
    dds_waitset_attach(waitset_, dds_create_readcondition(r, DDS_ANY_STATE), 0);
  // rmw_cyclonedds names a client by (part of) its writer's GUID; any
  // 64-bit value unique on the domain does, and a random one is.
  std::random_device rd;
  client_guid_ = (static_cast<std::uint64_t>(rd()) << 32) ^ rd();
  running_ = true;
  thread_ = std::thread([this] { run(); });
  return {};
}

void ControllerClient::close() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  if (participant_ > 0) dds_delete(participant_);
  participant_ = 0;
}

void ControllerClient::run() {
  while (running_) {
    dds_waitset_wait(waitset_, nullptr, 0, DDS_MSECS(20));
    take_all();
  }
}

void ControllerClient::take_all() {
  bool any = false;
  take_each<sensor_msgs_msg_dds__JointState_>(joint_states_, [&](const auto& m) {
    auto js = ros2::decode(m);
    if (!js) return;
    std::lock_guard lock(m_);
    latest_ = ReceivedState{*js, WallClock::now()};
    states_.push_back(std::move(*js));
    if (states_.size() > kKeptStates) {
      states_.pop_front();
      ++states_first_;
    }
    any = true;
  });
  take_each<control_msgs_action_dds__FollowJointTrajectory_SendGoal_Response_>(
      goal_rep_, [&](const auto& m) {
        if (m.client_guid != client_guid_) return;
        std::lock_guard lock(m_);
        accepted_[m.sequence_number] = m.accepted;
        any = true;
      });
  take_each<control_msgs_action_dds__FollowJointTrajectory_GetResult_Response_>(
      result_rep_, [&](const auto& m) {
        if (m.client_guid != client_guid_) return;
        std::lock_guard lock(m_);
        const auto call = result_calls_.find(m.sequence_number);
        if (call == result_calls_.end()) return;
        results_[call->second] = {static_cast<ros2::GoalStatus>(m.status),
                                  static_cast<ros2::TrajectoryError>(m.result.error_code),
                                  m.result.error_string ? m.result.error_string : ""};
        result_calls_.erase(call);
        any = true;
      });
  take_each<action_msgs_srv_dds__CancelGoal_Response_>(cancel_rep_, [](const auto&) {});
  take_each<control_msgs_action_dds__FollowJointTrajectory_FeedbackMessage_>(
      feedback_, [&](const auto& m) {
        auto fb = ros2::decode(m.feedback);
        if (!fb) return;
        std::lock_guard lock(m_);
        feedback_of_[goal_id_of(m.goal_id)] = std::move(*fb);
        any = true;
      });
  if (any) cv_.notify_all();
}

std::optional<ReceivedState> ControllerClient::latest_state() const {
  std::lock_guard lock(m_);
  return latest_;
}

std::uint64_t ControllerClient::states_received() const {
  std::lock_guard lock(m_);
  return states_first_ + states_.size();
}

std::vector<ros2::JointStateSample> ControllerClient::states_since(std::uint64_t first) const {
  std::lock_guard lock(m_);
  const std::uint64_t from = std::max(first, states_first_) - states_first_;
  if (from >= states_.size()) return {};
  return {states_.begin() + static_cast<std::ptrdiff_t>(from), states_.end()};
}

bool ControllerClient::wait_matched(dds_entity_t writer, dds_entity_t reader,
                                    std::chrono::milliseconds timeout) {
  const auto until = WallClock::now() + timeout;
  for (;;) {
    dds_publication_matched_status_t pub{};
    dds_subscription_matched_status_t sub{};
    dds_get_publication_matched_status(writer, &pub);
    if (reader != 0) dds_get_subscription_matched_status(reader, &sub);
    if (pub.current_count > 0 && (reader == 0 || sub.current_count > 0)) return true;
    if (WallClock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

plr::Status ControllerClient::send_io(const ros2::IoCommand& io,
                                      std::chrono::milliseconds timeout) {
  if (options_.io_commands.empty()) return {};
  // PLR_ERR_STATE, as the driver's other refusals: UNAVAILABLE would tell
  // the executor that its simulator restarted.
  if (!wait_matched(io_, 0, timeout))
    return plr::make_error(PLR_ERR_STATE,
                           fmt::format("no I/O controller subscribes to '{}' on ROS 2 domain {}",
                                       options_.io_commands, options_.domain_id));
  ros2::Wire<std_msgs_msg_dds__Float64MultiArray_> msg(&std_msgs_msg_dds__Float64MultiArray__desc);
  ros2::encode(io, msg.msg);
  if (const dds_return_t rc = dds_write(io_, &msg.msg); rc < 0)
    return plr::make_error(PLR_ERR_INTERNAL, fmt::format("writing the I/O command to '{}': {}",
                                                         options_.io_commands, dds_strretcode(rc)));
  return {};
}

plr::Status ControllerClient::send_goal(const ros2::GoalId& id, const ros2::TrajectoryGoal& goal,
                                        std::chrono::milliseconds timeout) {
  // A request sent before the server's endpoints are matched is lost, as
  // its reply would be: wait for both.
  if (!wait_matched(goal_req_, goal_rep_, timeout) ||
      !wait_matched(result_req_, result_rep_, timeout))
    return plr::make_error(PLR_ERR_UNAVAILABLE,
                           fmt::format("no controller serves action '{}' on ROS 2 domain {}",
                                       options_.action, options_.domain_id));
  ros2::Wire<control_msgs_action_dds__FollowJointTrajectory_SendGoal_Request_> req(
      &control_msgs_action_dds__FollowJointTrajectory_SendGoal_Request__desc);
  const std::int64_t seq = ++sequence_;
  req.msg.client_guid = client_guid_;
  req.msg.sequence_number = seq;
  std::memcpy(req.msg.goal_id.uuid, id.data(), id.size());
  ros2::encode(goal, req.msg.goal);
  if (const dds_return_t rc = dds_write(goal_req_, &req.msg); rc < 0)
    return plr::make_error(PLR_ERR_INTERNAL, fmt::format("send_goal to '{}': {}", options_.action,
                                                         dds_strretcode(rc)));
  std::unique_lock lock(m_);
  if (!cv_.wait_for(lock, timeout, [&] { return accepted_.count(seq) > 0; }))
    return plr::make_error(PLR_ERR_TIMEOUT, fmt::format("controller '{}' did not answer the goal "
                                                        "within {} ms",
                                                        options_.action, timeout.count()));
  const bool ok = accepted_[seq];
  accepted_.erase(seq);
  if (!ok)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("controller '{}' rejected the goal", options_.action));
  return {};
}

plr::Status ControllerClient::request_result(const ros2::GoalId& id) {
  control_msgs_action_dds__FollowJointTrajectory_GetResult_Request_ req{};
  const std::int64_t seq = ++sequence_;
  req.client_guid = client_guid_;
  req.sequence_number = seq;
  std::memcpy(req.goal_id.uuid, id.data(), id.size());
  {
    std::lock_guard lock(m_);
    result_calls_[seq] = id;
  }
  if (const dds_return_t rc = dds_write(result_req_, &req); rc < 0)
    return plr::make_error(PLR_ERR_INTERNAL, fmt::format("get_result from '{}': {}",
                                                         options_.action, dds_strretcode(rc)));
  return {};
}

std::optional<ros2::TrajectoryResult> ControllerClient::result(const ros2::GoalId& id) const {
  std::lock_guard lock(m_);
  const auto it = results_.find(id);
  if (it == results_.end()) return std::nullopt;
  return it->second;
}

std::optional<ros2::TrajectoryFeedback> ControllerClient::feedback(const ros2::GoalId& id) const {
  std::lock_guard lock(m_);
  const auto it = feedback_of_.find(id);
  if (it == feedback_of_.end()) return std::nullopt;
  return it->second;
}

plr::Status ControllerClient::cancel(const ros2::GoalId& id) {
  action_msgs_srv_dds__CancelGoal_Request_ req{};
  req.client_guid = client_guid_;
  req.sequence_number = ++sequence_;
  std::memcpy(req.goal_info.goal_id.uuid, id.data(), id.size());
  if (const dds_return_t rc = dds_write(cancel_req_, &req); rc < 0)
    return plr::make_error(PLR_ERR_INTERNAL, fmt::format("cancel_goal to '{}': {}", options_.action,
                                                         dds_strretcode(rc)));
  return {};
}

void ControllerClient::forget(const ros2::GoalId& id) {
  std::lock_guard lock(m_);
  results_.erase(id);
  feedback_of_.erase(id);
  std::erase_if(result_calls_, [&](const auto& call) { return call.second == id; });
}

void ControllerClient::wait(std::chrono::milliseconds d) const {
  std::unique_lock lock(m_);
  cv_.wait_for(lock, d);
}

}  // namespace plr::driver
