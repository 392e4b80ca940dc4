#include <octomap/octomap.h>
#include <plr/sim/unaligned.hpp>

#include <cmath>
#include <mutex>
#include <optional>
#include <plr/messages.hpp>
#include <sstream>
#include <string>
#include <string_view>

#include "plr/planning/plan_messages.hpp"

namespace plr::planning {

using sim::Box;
using sim::kNumJoints;
using sim::PlateTarget;
namespace {

// The decoder stops at the first bad field; decode_plan_request() turns it
// into the error it returns.
struct BadField {
  std::string what;
};

[[noreturn]] void bad(const std::string& field, const std::string& why) {
  throw BadField{"PlanRequest." + field + ": " + why};
}

JointVector to_joint_vector(const flatbuffers::Vector<double>* v, const char* field) {
  if (v == nullptr || v->size() != kNumJoints) {
    bad(field, "needs 8 joint values, got " + std::to_string(v == nullptr ? 0 : v->size()));
  }
  JointVector q;
  for (int i = 0; i < kNumJoints; ++i)
    q[i] = sim::element(*v, static_cast<flatbuffers::uoffset_t>(i));
  return q;
}

Eigen::Isometry3d to_pose(const plr::msg::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.position().x(), p.position().y(), p.position().z());
  const auto& o = p.orientation();
  Eigen::Quaterniond q(o.w(), o.x(), o.y(), o.z());
  if (q.norm() < 1e-9) q = Eigen::Quaterniond::Identity();
  t.linear() = q.normalized().toRotationMatrix();
  return t;
}

plr::msg::Pose to_msg(const PlateTarget& t) {
  // The plate is vertical: its orientation is the yaw of its normal.
  const Eigen::Quaterniond q(Eigen::AngleAxisd(t.yaw, Eigen::Vector3d::UnitZ()));
  return {plr::msg::Vec3(t.position.x(), t.position.y(), t.position.z()),
          plr::msg::Quat(q.x(), q.y(), q.z(), q.w())};
}

plr::msg::Pose to_msg(const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d p = pose.translation();
  const Eigen::Quaterniond q(pose.linear());
  return {plr::msg::Vec3(p.x(), p.y(), p.z()), plr::msg::Quat(q.x(), q.y(), q.z(), q.w())};
}

plr::msg::PlanStatus to_msg(PlanStatus s) {
  switch (s) {
    case PlanStatus::kSolved:
      return plr::msg::PlanStatus::Solved;
    case PlanStatus::kTimeout:
      return plr::msg::PlanStatus::Timeout;
    case PlanStatus::kStartInvalid:
      return plr::msg::PlanStatus::StartInvalid;
    case PlanStatus::kGoalInvalid:
      return plr::msg::PlanStatus::GoalInvalid;
    case PlanStatus::kNoPath:
      return plr::msg::PlanStatus::NoPath;
    case PlanStatus::kInvalidRequest:
      return plr::msg::PlanStatus::InvalidRequest;
  }
  return plr::msg::PlanStatus::InvalidRequest;
}

// The requests of a run share their trailer: its octree is parsed once, not
// per request (tens of ms, and OctoMap's reader prints a line each time).
std::shared_ptr<const octomap::OcTree> parse_octree(std::string_view bytes, double resolution) {
  static std::mutex m;
  static std::string last_bytes;
  static std::shared_ptr<const octomap::OcTree> last;
  std::lock_guard lock(m);
  if (last && bytes == last_bytes) return last;
  auto tree = std::make_shared<octomap::OcTree>(resolution);
  std::istringstream in{std::string(bytes)};
  if (!tree->readBinary(in)) return nullptr;
  last_bytes = bytes;
  last = std::move(tree);
  return last;
}

DecodedPlanRequest decode(const plr::msg::PlanRequest& r) {
  DecodedPlanRequest d;
  PlanQuery& q = d.query;
  const int mode = static_cast<int>(r.mode());
  if (mode < 1 || mode > 6) bad("mode", "unknown mode " + std::to_string(mode));
  q.mode = static_cast<PlanMode>(mode);
  q.start = to_joint_vector(r.start(), "start");
  if (r.has_goal_pose()) {
    if (r.goal_pose() == nullptr) bad("goal_pose", "has_goal_pose is set but goal_pose is missing");
    const Eigen::Isometry3d pose = to_pose(*r.goal_pose());
    const Eigen::Vector3d n = pose.linear().col(0);
    PoseGoal g;
    // The plate is always vertical: only the yaw of its normal is a goal.
    g.target = {pose.translation(), std::atan2(n.y(), n.x())};
    q.goal = g;
  } else if (r.goal_joints() != nullptr && r.goal_joints()->size() > 0) {
    JointGoal g;
    g.q = to_joint_vector(r.goal_joints(), "goal_joints");
    q.goal = g;
  }
  q.time_limit_s = r.timeout_s();
  q.max_expansions = r.max_expansions();
  if (const auto* eps = r.epsilons(); eps != nullptr && eps->size() > 0) {
    q.eps_initial = sim::element(*eps, 0);
    q.eps_final = sim::element(*eps, eps->size() - 1);
    q.eps_decrement =
        eps->size() > 1 ? std::max(1e-3, (q.eps_initial - q.eps_final) / (eps->size() - 1)) : 1.0;
  }
  const plr::msg::WorldState* w = r.world();
  if (w == nullptr) bad("world", "missing");
  if (const auto* t = w->trailer_size()) {
    if (t->x() > 0 && t->y() > 0 && t->z() > 0) d.world.trailer = {t->x(), t->y(), t->z()};
  }
  if (const auto* boxes = w->boxes()) {
    for (flatbuffers::uoffset_t i = 0; i < boxes->size(); ++i) {
      const plr::msg::BoxState state = sim::element(*boxes, i);
      const plr::msg::BoxState* b = &state;
      Box box;
      box.id = b->id();
      box.size = Eigen::Vector3d(b->size().x(), b->size().y(), b->size().z());
      if (!(box.size.minCoeff() > 0.0))
        bad("world.boxes", "box " + std::to_string(box.id) + " has a bad size");
      box.pose = to_pose(b->pose());
      box.mass = b->mass();
      d.world.boxes.push_back(box);
    }
  }
  if (const auto* bytes = w->octree(); bytes != nullptr && bytes->size() > 0) {
    d.octree =
        parse_octree(std::string_view(reinterpret_cast<const char*>(bytes->data()), bytes->size()),
                     w->octree_resolution() > 0 ? w->octree_resolution() : 0.05);
    if (!d.octree) bad("world.octree", "not an OctoMap binary tree");
  }
  if (const auto* held = r.held_box_ids()) {
    for (std::uint32_t id : *held) {
      const auto it = std::find_if(d.world.boxes.begin(), d.world.boxes.end(),
                                   [&](const Box& b) { return b.id == id; });
      if (it == d.world.boxes.end())
        bad("held_box_ids", "box " + std::to_string(id) + " is not in the world");
      q.held_boxes.push_back(*it);
    }
  }
  return d;
}

}  // namespace

plr::Expected<DecodedPlanRequest> decode_plan_request(const plr::msg::PlanRequest& request) {
  try {
    return decode(request);
  } catch (const BadField& e) {
    return plr::make_error(PLR_ERR_INVALID, e.what);
  }
}

void encode_plan_response(const PlanResult& result, const std::string& planner, double sample_dt,
                          flatbuffers::FlatBufferBuilder& out) {
  std::vector<flatbuffers::Offset<plr::msg::TrajectoryPoint>> points;
  if (!result.trajectory.empty()) {
    for (const auto& [t, s] : result.trajectory.sampled(sample_dt)) {
      const std::vector<double> pos(s.position.data(), s.position.data() + kNumJoints);
      const std::vector<double> vel(s.velocity.data(), s.velocity.data() + kNumJoints);
      points.push_back(plr::msg::CreateTrajectoryPointDirect(out, t, &pos, &vel));
    }
  }
  const auto traj = plr::msg::CreateTrajectoryDirect(out, &points);
  const PlanStats& st = result.stats;
  const auto stats = plr::msg::CreatePlanStats(
      out, st.expansions, 1e3 * st.first_solution_s, 1e3 * st.planning_time_s, st.final_eps,
      st.cost, st.escaped, 1e3 * st.escape_time_s, st.budget_exhausted, st.time_limit_hit);
  out.Finish(plr::msg::CreatePlanResponseDirect(out, to_msg(result.status), result.message.c_str(),
                                                traj, stats, planner.c_str()));
}

void encode_plan_request(const PlanQuery& query, const sim::World& world,
                         flatbuffers::FlatBufferBuilder& out) {
  const std::vector<double> start(query.start.data(), query.start.data() + kNumJoints);
  std::vector<double> goal_joints;
  std::optional<plr::msg::Pose> goal_pose;
  if (const auto* jg = std::get_if<JointGoal>(&query.goal)) {
    goal_joints.assign(jg->q.data(), jg->q.data() + kNumJoints);
  } else if (const auto* pg = std::get_if<PoseGoal>(&query.goal)) {
    goal_pose = to_msg(pg->target);
  }
  // The schedule eps_initial, eps_initial - eps_decrement, ..., eps_final.
  std::vector<double> epsilons{query.eps_initial};
  while (epsilons.back() - query.eps_decrement > query.eps_final + 1e-9 && epsilons.size() < 64)
    epsilons.push_back(epsilons.back() - query.eps_decrement);
  if (query.eps_final < epsilons.back()) epsilons.push_back(query.eps_final);
  std::vector<std::uint32_t> held;
  for (const Box& b : query.held_boxes) held.push_back(b.id);
  std::vector<plr::msg::BoxState> boxes;
  for (const Box& b : world.boxes) {
    const bool ignored = std::find(query.ignored_boxes.begin(), query.ignored_boxes.end(), b.id) !=
                         query.ignored_boxes.end();
    if (ignored && std::find(held.begin(), held.end(), b.id) == held.end()) continue;
    boxes.emplace_back(b.id, plr::msg::Vec3(b.size.x(), b.size.y(), b.size.z()), to_msg(b.pose),
                       b.mass);
  }
  const plr::msg::Vec3 trailer(world.trailer.width, world.trailer.height, world.trailer.depth);
  const auto w = plr::msg::CreateWorldStateDirect(out, 0, &trailer, nullptr, 0.0, &boxes);
  out.Finish(plr::msg::CreatePlanRequestDirect(
      out, static_cast<plr::msg::PlanMode>(query.mode), &start,
      goal_joints.empty() ? nullptr : &goal_joints, goal_pose ? &*goal_pose : nullptr,
      goal_pose.has_value(), query.time_limit_s, &epsilons, w, &held, query.max_expansions));
}

plr::Expected<DecodedPlanResponse> decode_plan_response(const plr::msg::PlanResponse& response) {
  auto bad = [](const std::string& field, const std::string& why) {
    return plr::make_error(PLR_ERR_INVALID, "PlanResponse." + field + ": " + why);
  };
  DecodedPlanResponse d;
  const int status = static_cast<int>(response.status());
  if (status < 0 || status > static_cast<int>(PlanStatus::kInvalidRequest))
    return bad("status", "unknown status " + std::to_string(status));
  d.status = static_cast<PlanStatus>(status);
  if (response.message()) d.message = response.message()->str();
  if (response.planner()) d.planner = response.planner()->str();
  if (const auto* t = response.trajectory(); t && t->points()) {
    for (const auto* p : *t->points()) {
      if (p->positions() == nullptr || p->positions()->size() != kNumJoints)
        return bad("trajectory", "every point needs 8 positions");
      TimedPoint tp;
      tp.time_s = p->time_s();
      for (int j = 0; j < kNumJoints; ++j) tp.position[j] = sim::element(*p->positions(), j);
      if (p->velocities() && p->velocities()->size() == kNumJoints)
        for (int j = 0; j < kNumJoints; ++j) tp.velocity[j] = sim::element(*p->velocities(), j);
      if (!d.points.empty() && tp.time_s < d.points.back().time_s)
        return bad("trajectory", "times must not decrease");
      d.points.push_back(tp);
    }
  }
  if (const auto* st = response.stats()) {
    d.stats.expansions = st->expansions();
    d.stats.first_solution_s = 1e-3 * st->first_solution_ms();
    d.stats.planning_time_s = 1e-3 * st->planning_ms();
    d.stats.final_eps = st->final_epsilon();
    d.stats.cost = st->cost();
    d.stats.escaped = st->m6_used();
    d.stats.escape_time_s = 1e-3 * st->escape_ms();
    d.stats.budget_exhausted = st->budget_exhausted();
    d.stats.time_limit_hit = st->time_limit_hit();
  }
  return d;
}

}  // namespace plr::planning
