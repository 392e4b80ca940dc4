// A robot's joint trajectory controller as ros2_control runs it, emulated in
// its own process and reached only over DDS with ROS 2's types and names
// (sim/ros2): the FollowJointTrajectory action server and joint_states, and
// the I/O outputs a forward_command_controller would set. Its clock runs
// `time_scale` times faster than the wall clock; faults are requested on a
// std_msgs/String topic (see README.md).
#include "joint_trajectory_controller.hpp"

#include <plr/actions/unloader_simulation.hpp>
#include <plr/interface.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>
#include <plr/ros2/domain.hpp>
#include <plr/ros2/names.hpp>
#include <plr/ros2/wire.hpp>
#include <plr/sim/robot_model.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <deque>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

namespace plr::emulator {
namespace {

using Clock = std::chrono::steady_clock;
namespace cm = ::plr::ros2;

// Finished goals kept for a late get_result and for the status array.
constexpr std::size_t kKeptResults = 16;

ros2::GoalId goal_id_of(const unique_identifier_msgs_msg_dds__UUID_& u) {
  ros2::GoalId id{};
  std::memcpy(id.data(), u.uuid, id.size());
  return id;
}

class ControllerEmulatorNode : public Node {
 public:
  using Node::Node;
  ~ControllerEmulatorNode() override { close(); }

 protected:
  Status on_configure() override {
    params().allow_only({"action", "joint_states", "fault_topic", "io_commands", "domain_id",
                         "loopback_only", "time_scale", "lag_s", "period_s", "initial_positions"});
    action_ = params().get<std::string>("action", "/unloader_controller/follow_joint_trajectory");
    joint_states_ = params().get<std::string>("joint_states", "/joint_states");
    fault_topic_ = params().get<std::string>("fault_topic", "/unloader_controller/inject_fault");
    io_topic_ = params().get<std::string>("io_commands", "/io_controller/commands");
    for (const auto& [key, name] :
         {std::pair{"action", action_}, std::pair{"joint_states", joint_states_},
          std::pair{"fault_topic", fault_topic_}, std::pair{"io_commands", io_topic_}})
      if (auto ok = cm::check_name(name); !ok)
        return make_error(PLR_ERR_INVALID, fmt::format("param '{}': {}", key, ok.error().message));
    const auto domain = params().get<int>("domain_id", 0);
    scale_ = params().get<double>("time_scale", 1.0);
    options_.lag_s = params().get<double>("lag_s", 0.02);
    period_ = params().get<double>("period_s", 0.01);
    for (const auto& [name, value, lo, hi] : {std::tuple{"time_scale", scale_, 0.1, 100.0},
                                              std::tuple{"lag_s", options_.lag_s, 0.0, 1.0},
                                              std::tuple{"period_s", period_, 0.001, 0.1}})
      if (!(value >= lo && value <= hi))
        return make_error(
            PLR_ERR_INVALID,
            fmt::format("param '{}': must be between {} and {}, got {}", name, lo, hi, value));
    if (domain < 0 || domain > 232)
      return make_error(PLR_ERR_INVALID,
                        fmt::format("param 'domain_id': must be 0 to 232, got {}", domain));
    options_.joints.assign(sim::kJointNames.begin(), sim::kJointNames.end());
    const sim::JointVector home = actions::home_configuration();
    initial_.assign(home.data(), home.data() + home.size());
    if (params().has("initial_positions")) {
      initial_ = params().get<std::vector<double>>("initial_positions", {});
      if (initial_.size() != options_.joints.size())
        return make_error(PLR_ERR_INVALID,
                          fmt::format("param 'initial_positions': {} values for {} joints",
                                      initial_.size(), options_.joints.size()));
    }
    auto p = cm::open_participant(static_cast<std::uint32_t>(domain),
                                  params().get<bool>("loopback_only", false));
    if (!p) return p.error();
    participant_ = *p;
    return open_endpoints();
  }

  Status on_activate() override {
    controller_.emplace(options_, initial_);
    running_ = true;
    thread_ = std::thread([this] { run(); });
    return {};
  }

  Status on_deactivate() override {
    running_ = false;
    if (thread_.joinable()) thread_.join();
    return {};
  }

  Status on_cleanup() override {
    close();
    return {};
  }

 private:
  dds_entity_t reader(const std::string& name, const dds_topic_descriptor_t* desc, dds_qos_t* qos) {
    const dds_entity_t t = dds_create_topic(participant_, desc, name.c_str(), nullptr, nullptr);
    const dds_entity_t r = t < 0 ? t : dds_create_reader(participant_, t, qos, nullptr);
    dds_delete_qos(qos);
    return r;
  }
  dds_entity_t writer(const std::string& name, const dds_topic_descriptor_t* desc, dds_qos_t* qos) {
    const dds_entity_t t = dds_create_topic(participant_, desc, name.c_str(), nullptr, nullptr);
    const dds_entity_t w = t < 0 ? t : dds_create_writer(participant_, t, qos, nullptr);
    dds_delete_qos(qos);
    return w;
  }

  Status open_endpoints() {
    const auto a = cm::action_topics(action_);
    goal_req_ = reader(a.send_goal_request,
                       &control_msgs_action_dds__FollowJointTrajectory_SendGoal_Request__desc,
                       cm::default_qos());
    goal_rep_ = writer(a.send_goal_reply,
                       &control_msgs_action_dds__FollowJointTrajectory_SendGoal_Response__desc,
                       cm::default_qos());
    result_req_ = reader(a.get_result_request,
                         &control_msgs_action_dds__FollowJointTrajectory_GetResult_Request__desc,
                         cm::default_qos());
    result_rep_ = writer(a.get_result_reply,
                         &control_msgs_action_dds__FollowJointTrajectory_GetResult_Response__desc,
                         cm::default_qos());
    cancel_req_ = reader(a.cancel_goal_request, &action_msgs_srv_dds__CancelGoal_Request__desc,
                         cm::default_qos());
    cancel_rep_ = writer(a.cancel_goal_reply, &action_msgs_srv_dds__CancelGoal_Response__desc,
                         cm::default_qos());
    feedback_ =
        writer(a.feedback, &control_msgs_action_dds__FollowJointTrajectory_FeedbackMessage__desc,
               cm::default_qos());
    status_ = writer(a.status, &action_msgs_msg_dds__GoalStatusArray__desc, cm::status_qos());
    joint_state_ = writer(cm::topic_name(joint_states_), &sensor_msgs_msg_dds__JointState__desc,
                          cm::default_qos());
    fault_ =
        reader(cm::topic_name(fault_topic_), &std_msgs_msg_dds__String__desc, cm::default_qos());
    // As a forward_command_controller for the I/O, which takes the last command on joining.
    io_ = reader(cm::topic_name(io_topic_), &std_msgs_msg_dds__Float64MultiArray__desc,
                 cm::status_qos());
    for (dds_entity_t e : {goal_req_, goal_rep_, result_req_, result_rep_, cancel_req_, cancel_rep_,
                           feedback_, status_, joint_state_, fault_, io_})
      if (e < 0)
        return make_error(PLR_ERR_INTERNAL, fmt::format("DDS endpoint for action '{}': {}", action_,
                                                        dds_strretcode(e)));
    waitset_ = dds_create_waitset(participant_);
    for (dds_entity_t r : {goal_req_, result_req_, cancel_req_, fault_, io_}) {
      const dds_entity_t cond = dds_create_readcondition(r, DDS_ANY_STATE);
      dds_waitset_attach(waitset_, cond, 0);
    }
    return {};
  }

  void close() {
    (void)on_deactivate();
    if (participant_ > 0) dds_delete(participant_);
    participant_ = 0;
  }

  // The controller's loop: requests as they come, and a control step every
  // period_ of controller time (period_ / scale_ of wall time).
  void run() {
    const auto t0 = Clock::now();
    std::uint64_t steps = 0;
    publish_status();
    while (running_) {
      const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
      const auto due = static_cast<std::uint64_t>(wall * scale_ / period_);
      // A stalled process does not replay everything it missed at once.
      if (due > steps + 100) steps = due - 100;
      for (; steps < due; ++steps) {
        if (auto done = controller_->step(period_)) finished(*done);
        publish_state();
      }
      serve_requests();
      const double next_wall = static_cast<double>(steps + 1) * period_ / scale_;
      const auto wait = std::chrono::duration<double>(next_wall - wall);
      dds_waitset_wait(waitset_, nullptr, 0,
                       std::max<dds_duration_t>(
                           0, std::chrono::duration_cast<std::chrono::nanoseconds>(wait).count()));
    }
  }

  template <class T, class F>
  void take_all(dds_entity_t r, F&& handle) {
    void* samples[16] = {};
    dds_sample_info_t infos[16];
    for (;;) {
      const int n = dds_take(r, samples, infos, 16, 16);
      if (n <= 0) return;
      for (int i = 0; i < n; ++i)
        if (infos[i].valid_data) handle(*static_cast<const T*>(samples[i]));
      dds_return_loan(r, samples, n);
    }
  }

  void serve_requests() {
    take_all<control_msgs_action_dds__FollowJointTrajectory_SendGoal_Request_>(
        goal_req_, [&](const auto& req) { send_goal(req); });
    take_all<control_msgs_action_dds__FollowJointTrajectory_GetResult_Request_>(
        result_req_, [&](const auto& req) {
          waiting_.push_back({goal_id_of(req.goal_id), req.client_guid, req.sequence_number});
        });
    take_all<action_msgs_srv_dds__CancelGoal_Request_>(cancel_req_,
                                                       [&](const auto& req) { cancel_goal(req); });
    take_all<std_msgs_msg_dds__String_>(fault_,
                                        [&](const auto& m) { inject(m.data ? m.data : ""); });
    take_all<std_msgs_msg_dds__Float64MultiArray_>(io_, [&](const auto& m) { set_io(m); });
    answer_waiting();
  }

  // The I/O outputs follow the last command; each change is logged.
  void set_io(const std_msgs_msg_dds__Float64MultiArray_& m) {
    auto io = cm::decode(m);
    if (!io) return log().warn("I/O command on {} refused: {}", io_topic_, io.error().message);
    if (io_state_ == *io) return;
    io_state_ = *io;
    log().info("I/O: vacuum {}, conveyor {}, {} of {} cup valves open", io->vacuum ? "on" : "off",
               io->conveyor ? "running" : "stopped",
               std::count(io->cups_open.begin(), io->cups_open.end(), true), io->cups_open.size());
  }

  void send_goal(const control_msgs_action_dds__FollowJointTrajectory_SendGoal_Request_& req) {
    const auto id = goal_id_of(req.goal_id);
    bool accepted = false;
    if (auto goal = cm::decode(req.goal); !goal) {
      log().warn("goal {} rejected: {}", cm::to_string(id), goal.error().message);
    } else if (auto a = controller_->accept(id, *goal); !a) {
      log().warn("goal {} rejected: {}", cm::to_string(id), a.error().message);
    } else {
      accepted = true;
      if (*a) finished(**a);
      accepted_.insert(id);
    }
    control_msgs_action_dds__FollowJointTrajectory_SendGoal_Response_ rep{};
    rep.client_guid = req.client_guid;
    rep.sequence_number = req.sequence_number;
    rep.accepted = accepted;
    rep.stamp = cm::to_time(controller_->now());
    dds_write(goal_rep_, &rep);
    publish_status();
  }

  void cancel_goal(const action_msgs_srv_dds__CancelGoal_Request_& req) {
    const auto id = goal_id_of(req.goal_info.goal_id);
    // A zero id cancels every goal (action_msgs/CancelGoal).
    const bool all = id == ros2::GoalId{};
    std::optional<FinishedGoal> done;
    if (auto active = controller_->active_goal(); active && (all || *active == id))
      done = controller_->cancel(*active);
    cm::Wire<action_msgs_srv_dds__CancelGoal_Response_> rep(
        &action_msgs_srv_dds__CancelGoal_Response__desc);
    rep.msg.client_guid = req.client_guid;
    rep.msg.sequence_number = req.sequence_number;
    rep.msg.return_code = done ? 0 : 2;  // ERROR_NONE, ERROR_UNKNOWN_GOAL_ID
    if (done) {
      rep.msg.goals_canceling._buffer = static_cast<action_msgs_msg_dds__GoalInfo_*>(
          dds_alloc(sizeof(action_msgs_msg_dds__GoalInfo_)));
      rep.msg.goals_canceling._length = rep.msg.goals_canceling._maximum = 1;
      rep.msg.goals_canceling._release = true;
      std::memcpy(rep.msg.goals_canceling._buffer[0].goal_id.uuid, done->id.data(), 16);
      rep.msg.goals_canceling._buffer[0].stamp = cm::to_time(controller_->now());
    }
    dds_write(cancel_rep_, &rep.msg);
    if (done) finished(*done);
  }

  void inject(const char* text) {
    const std::string request(text, strnlen(text, ros2::kMaxNameSize + 1));
    if (request.size() > ros2::kMaxNameSize)
      return log().warn("fault request on {}: longer than {} characters, ignored", fault_topic_,
                        ros2::kMaxNameSize);
    std::istringstream in(request);
    std::string kind, joint;
    in >> kind;
    Status ok;
    if (kind == "drop_feedback") {
      dropping_ = true;
    } else if (kind == "stuck_joint" && (in >> joint)) {
      ok = controller_->stick_joint(joint);
    } else if (double offset = 0.0; kind == "tolerance_violation" && (in >> joint >> offset)) {
      ok = controller_->knock_joint(joint, offset);
    } else if (double delay = 0.0; kind == "late_start" && (in >> delay) && delay >= 0.0) {
      controller_->delay_next_start(delay);
    } else if (kind == "clear") {
      dropping_ = false;
      controller_->clear_faults();
    } else {
      ok = make_error(PLR_ERR_INVALID, "");
    }
    if (!ok)
      log().warn(
          "fault request '{}' on {}: not understood ({}expected drop_feedback, stuck_joint "
          "<joint>, tolerance_violation <joint> <offset>, late_start <s> or clear)",
          request, fault_topic_, ok.error().message.empty() ? "" : ok.error().message + "; ");
    else
      log().info("fault injected: {}", request);
  }

  void finished(const FinishedGoal& done) {
    log().info("goal {} {}: {} {}", cm::to_string(done.id), cm::to_string(done.result.status),
               cm::to_string(done.result.error), done.result.error_string);
    results_.push_back(done);
    if (results_.size() > kKeptResults) results_.pop_front();
    publish_status();
    answer_waiting();
  }

  void answer_waiting() {
    for (auto it = waiting_.begin(); it != waiting_.end();) {
      const FinishedGoal* done = nullptr;
      for (const auto& r : results_)
        if (r.id == it->id) done = &r;
      const bool known = done != nullptr || accepted_.count(it->id) > 0;
      if (done == nullptr && known) {
        ++it;
        continue;
      }
      cm::Wire<control_msgs_action_dds__FollowJointTrajectory_GetResult_Response_> rep(
          &control_msgs_action_dds__FollowJointTrajectory_GetResult_Response__desc);
      rep.msg.client_guid = it->client_guid;
      rep.msg.sequence_number = it->sequence;
      rep.msg.status =
          static_cast<std::int8_t>(done ? done->result.status : ros2::GoalStatus::kUnknown);
      rep.msg.result.error_code = static_cast<std::int32_t>(
          done ? done->result.error : ros2::TrajectoryError::kInvalidGoal);
      rep.msg.result.error_string =
          cm::wire_string(done ? done->result.error_string : "unknown goal");
      dds_write(result_rep_, &rep.msg);
      if (done) accepted_.erase(it->id);
      it = waiting_.erase(it);
    }
  }

  void publish_status() {
    std::vector<std::pair<ros2::GoalId, ros2::GoalStatus>> list;
    for (const auto& r : results_) list.emplace_back(r.id, r.result.status);
    if (auto a = controller_->active_goal()) list.emplace_back(*a, ros2::GoalStatus::kExecuting);
    cm::Wire<action_msgs_msg_dds__GoalStatusArray_> m(&action_msgs_msg_dds__GoalStatusArray__desc);
    auto& seq = m.msg.status_list;
    seq._length = seq._maximum = static_cast<std::uint32_t>(list.size());
    seq._release = true;
    seq._buffer = list.empty() ? nullptr
                               : static_cast<action_msgs_msg_dds__GoalStatus_*>(
                                     dds_alloc(list.size() * sizeof(*seq._buffer)));
    for (std::size_t i = 0; i < list.size(); ++i) {
      std::memset(&seq._buffer[i], 0, sizeof(seq._buffer[i]));
      std::memcpy(seq._buffer[i].goal_info.goal_id.uuid, list[i].first.data(), 16);
      seq._buffer[i].status = static_cast<std::int8_t>(list[i].second);
    }
    dds_write(status_, &m.msg);
  }

  void publish_state() {
    if (dropping_) return;
    ros2::JointStateSample js{controller_->now(), controller_->joints(), controller_->positions(),
                              controller_->velocities()};
    cm::Wire<sensor_msgs_msg_dds__JointState_> m(&sensor_msgs_msg_dds__JointState__desc);
    cm::encode(js, m.msg);
    dds_write(joint_state_, &m.msg);
    if (auto fb = controller_->feedback()) {
      cm::Wire<control_msgs_action_dds__FollowJointTrajectory_FeedbackMessage_> f(
          &control_msgs_action_dds__FollowJointTrajectory_FeedbackMessage__desc);
      std::memcpy(f.msg.goal_id.uuid, controller_->active_goal()->data(), 16);
      cm::encode(*fb, f.msg.feedback);
      dds_write(feedback_, &f.msg);
    }
  }

  struct Waiting {
    ros2::GoalId id{};
    std::uint64_t client_guid = 0;
    std::int64_t sequence = 0;
  };

  std::string action_, joint_states_, fault_topic_;
  ControllerOptions options_;
  std::vector<double> initial_;
  double scale_ = 1.0, period_ = 0.01;
  dds_entity_t participant_ = 0, waitset_ = 0, io_ = 0;
  std::string io_topic_;
  cm::IoCommand io_state_;
  dds_entity_t goal_req_ = 0, goal_rep_ = 0, result_req_ = 0, result_rep_ = 0, cancel_req_ = 0,
               cancel_rep_ = 0, feedback_ = 0, status_ = 0, joint_state_ = 0, fault_ = 0;
  std::optional<JointTrajectoryController> controller_;
  std::deque<FinishedGoal> results_;
  std::set<ros2::GoalId> accepted_;  // goals whose result is not out yet
  std::vector<Waiting> waiting_;
  bool dropping_ = false;
  std::atomic<bool> running_{false};
  std::thread thread_;
};

}  // namespace
}  // namespace plr::emulator

PLR_PLUGIN(plr::emulator::ControllerEmulatorNode, "controller_emulator", "0.1.0",
           PLR_KIND_SIMULATOR,
           "A ros2_control joint trajectory controller emulated over DDS with ROS 2 types")
// It speaks ROS 2 types over its own DDS participant, not on the bus.
PLR_INTERFACE()
