#include "plr/ros2/wire.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstring>

namespace plr::ros2 {
namespace {

template <class Seq>
void allocate(Seq& s, std::size_t n) {
  s._length = s._maximum = static_cast<std::uint32_t>(n);
  s._release = true;
  s._buffer = nullptr;
  if (n == 0) return;
  s._buffer = static_cast<decltype(s._buffer)>(dds_alloc(n * sizeof(*s._buffer)));
  std::memset(static_cast<void*>(s._buffer), 0, n * sizeof(*s._buffer));
}

void put(dds_sequence_double& s, const std::vector<double>& v) {
  allocate(s, v.size());
  for (std::size_t i = 0; i < v.size(); ++i) s._buffer[i] = v[i];
}

void put(dds_sequence_string& s, const std::vector<std::string>& v) {
  allocate(s, v.size());
  for (std::size_t i = 0; i < v.size(); ++i) s._buffer[i] = wire_string(v[i]);
}

plr::Expected<std::vector<double>> take(const dds_sequence_double& s, const char* what) {
  if (s._length > kMaxPoints)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("{}: {} values, at most {}", what, s._length, kMaxPoints));
  std::vector<double> v(s._buffer, s._buffer + s._length);
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      return plr::make_error(PLR_ERR_INVALID, fmt::format("{}[{}]: not a finite number", what, i));
  return v;
}

plr::Expected<std::string> take(const char* s, const char* what) {
  if (s == nullptr) return std::string();
  const std::size_t n = strnlen(s, kMaxNameSize + 1);
  if (n > kMaxNameSize)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("{}: longer than {} characters", what, kMaxNameSize));
  return std::string(s, n);
}

plr::Expected<std::vector<std::string>> take(const dds_sequence_string& s, const char* what) {
  if (s._length > kMaxJoints)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("{}: {} names, at most {}", what, s._length, kMaxJoints));
  std::vector<std::string> v;
  for (std::uint32_t i = 0; i < s._length; ++i) {
    auto name = take(s._buffer[i], what);
    if (!name) return name.error();
    v.push_back(std::move(*name));
  }
  return v;
}

void put(trajectory_msgs_msg_dds__JointTrajectoryPoint_& out, const TrajectoryPoint& p) {
  put(out.positions, p.positions);
  put(out.velocities, p.velocities);
  out.time_from_start = to_duration(p.time_s);
}

plr::Expected<TrajectoryPoint> take(const trajectory_msgs_msg_dds__JointTrajectoryPoint_& in,
                                    const std::string& what) {
  TrajectoryPoint p;
  p.time_s = seconds(in.time_from_start);
  auto pos = take(in.positions, (what + ".positions").c_str());
  if (!pos) return pos.error();
  auto vel = take(in.velocities, (what + ".velocities").c_str());
  if (!vel) return vel.error();
  p.positions = std::move(*pos);
  p.velocities = std::move(*vel);
  return p;
}

void put(dds_sequence_control_msgs_msg_dds__JointTolerance_& s,
         const std::vector<JointTolerance>& v) {
  allocate(s, v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    s._buffer[i].name = wire_string(v[i].name);
    s._buffer[i].position = v[i].position;
    s._buffer[i].velocity = v[i].velocity;
    s._buffer[i].acceleration = v[i].acceleration;
  }
}

plr::Expected<std::vector<JointTolerance>> take(
    const dds_sequence_control_msgs_msg_dds__JointTolerance_& s, const char* what) {
  if (s._length > kMaxJoints)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("{}: {} entries, at most {}", what, s._length, kMaxJoints));
  std::vector<JointTolerance> v;
  for (std::uint32_t i = 0; i < s._length; ++i) {
    auto name = take(s._buffer[i].name, what);
    if (!name) return name.error();
    v.push_back({std::move(*name), s._buffer[i].position, s._buffer[i].velocity,
                 s._buffer[i].acceleration});
  }
  return v;
}

}  // namespace

char* wire_string(const std::string& s) {
  auto* c = static_cast<char*>(dds_alloc(s.size() + 1));
  std::memcpy(c, s.c_str(), s.size() + 1);
  return c;
}

builtin_interfaces_msg_dds__Duration_ to_duration(double s) {
  const double whole = std::floor(s);
  return {static_cast<std::int32_t>(whole),
          static_cast<std::uint32_t>(std::llround((s - whole) * 1e9) % 1000000000)};
}

builtin_interfaces_msg_dds__Time_ to_time(double s) {
  const auto d = to_duration(s);
  return {d.sec, d.nanosec};
}

double seconds(const builtin_interfaces_msg_dds__Duration_& d) {
  return static_cast<double>(d.sec) + static_cast<double>(d.nanosec) * 1e-9;
}

double seconds(const builtin_interfaces_msg_dds__Time_& t) {
  return static_cast<double>(t.sec) + static_cast<double>(t.nanosec) * 1e-9;
}

void encode(const TrajectoryGoal& goal, control_msgs_action_dds__FollowJointTrajectory_Goal_& out) {
  out.trajectory.header.frame_id = wire_string("");
  out.multi_dof_trajectory.header.frame_id = wire_string("");
  put(out.trajectory.joint_names, goal.joint_names);
  allocate(out.trajectory.points, goal.points.size());
  for (std::size_t i = 0; i < goal.points.size(); ++i)
    put(out.trajectory.points._buffer[i], goal.points[i]);
  put(out.path_tolerance, goal.path_tolerance);
  put(out.goal_tolerance, goal.goal_tolerance);
  out.goal_time_tolerance = to_duration(goal.goal_time_tolerance_s);
}

plr::Expected<TrajectoryGoal> decode(
    const control_msgs_action_dds__FollowJointTrajectory_Goal_& in) {
  TrajectoryGoal g;
  auto names = take(in.trajectory.joint_names, "trajectory.joint_names");
  if (!names) return names.error();
  g.joint_names = std::move(*names);
  if (in.trajectory.points._length > kMaxPoints)
    return plr::make_error(PLR_ERR_INVALID, fmt::format("trajectory.points: {} points, at most {}",
                                                        in.trajectory.points._length, kMaxPoints));
  for (std::uint32_t i = 0; i < in.trajectory.points._length; ++i) {
    auto p = take(in.trajectory.points._buffer[i], fmt::format("trajectory.points[{}]", i));
    if (!p) return p.error();
    g.points.push_back(std::move(*p));
  }
  auto path = take(in.path_tolerance, "path_tolerance");
  if (!path) return path.error();
  auto goal = take(in.goal_tolerance, "goal_tolerance");
  if (!goal) return goal.error();
  g.path_tolerance = std::move(*path);
  g.goal_tolerance = std::move(*goal);
  g.goal_time_tolerance_s = seconds(in.goal_time_tolerance);
  return g;
}

void encode(const TrajectoryFeedback& fb,
            control_msgs_action_dds__FollowJointTrajectory_Feedback_& out) {
  out.header.stamp = to_time(fb.stamp_s);
  out.header.frame_id = wire_string("");
  put(out.joint_names, fb.joint_names);
  put(out.desired, fb.desired);
  put(out.actual, fb.actual);
  put(out.error, fb.error);
}

plr::Expected<TrajectoryFeedback> decode(
    const control_msgs_action_dds__FollowJointTrajectory_Feedback_& in) {
  TrajectoryFeedback fb;
  fb.stamp_s = seconds(in.header.stamp);
  auto names = take(in.joint_names, "feedback.joint_names");
  if (!names) return names.error();
  fb.joint_names = std::move(*names);
  auto desired = take(in.desired, "feedback.desired");
  auto actual = take(in.actual, "feedback.actual");
  auto error = take(in.error, "feedback.error");
  if (!desired) return desired.error();
  if (!actual) return actual.error();
  if (!error) return error.error();
  fb.desired = std::move(*desired);
  fb.actual = std::move(*actual);
  fb.error = std::move(*error);
  return fb;
}

void encode(const JointStateSample& js, sensor_msgs_msg_dds__JointState_& out) {
  out.header.stamp = to_time(js.stamp_s);
  out.header.frame_id = wire_string("");
  put(out.name, js.names);
  put(out.position, js.position);
  put(out.velocity, js.velocity);
}

plr::Expected<JointStateSample> decode(const sensor_msgs_msg_dds__JointState_& in) {
  JointStateSample js;
  js.stamp_s = seconds(in.header.stamp);
  auto names = take(in.name, "joint_states.name");
  if (!names) return names.error();
  auto pos = take(in.position, "joint_states.position");
  if (!pos) return pos.error();
  auto vel = take(in.velocity, "joint_states.velocity");
  if (!vel) return vel.error();
  js.names = std::move(*names);
  js.position = std::move(*pos);
  js.velocity = std::move(*vel);
  if (js.position.size() != js.names.size())
    return plr::make_error(PLR_ERR_INVALID, fmt::format("joint_states: {} positions for {} names",
                                                        js.position.size(), js.names.size()));
  return js;
}

void encode(const IoCommand& io, std_msgs_msg_dds__Float64MultiArray_& out) {
  std::vector<double> v = {io.vacuum ? 1.0 : 0.0, io.conveyor ? 1.0 : 0.0};
  for (bool open : io.cups_open) v.push_back(open ? 1.0 : 0.0);
  allocate(out.layout.dim, 1);
  out.layout.dim._buffer[0].label = wire_string("io");
  out.layout.dim._buffer[0].size = static_cast<std::uint32_t>(v.size());
  out.layout.dim._buffer[0].stride = static_cast<std::uint32_t>(v.size());
  out.layout.data_offset = 0;
  put(out.data, v);
}

plr::Expected<IoCommand> decode(const std_msgs_msg_dds__Float64MultiArray_& in) {
  auto v = take(in.data, "io.data");
  if (!v) return v.error();
  if (v->size() < 2)
    return plr::make_error(
        PLR_ERR_INVALID,
        fmt::format("io.data: {} values, the vacuum and the conveyor at least", v->size()));
  for (std::size_t i = 0; i < v->size(); ++i)
    if ((*v)[i] != 0.0 && (*v)[i] != 1.0)
      return plr::make_error(PLR_ERR_INVALID,
                             fmt::format("io.data[{}]: {} is neither 0 nor 1", i, (*v)[i]));
  IoCommand io;
  io.vacuum = (*v)[0] == 1.0;
  io.conveyor = (*v)[1] == 1.0;
  for (std::size_t i = 2; i < v->size(); ++i) io.cups_open.push_back((*v)[i] == 1.0);
  return io;
}

}  // namespace plr::ros2
