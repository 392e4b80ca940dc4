#include "plr/planning/plan_query.hpp"

#include <cmath>

namespace plr::planning {

using namespace plr::sim;

const char* to_string(PlanMode mode) {
  switch (mode) {
    case PlanMode::kArm:
      return "M1 arm";
    case PlanMode::kArmBase:
      return "M2 arm+base";
    case PlanMode::kNose:
      return "M3 nose";
    case PlanMode::kArmCartesian:
      return "M4 arm line";
    case PlanMode::kBaseLine:
      return "M5 base line";
    case PlanMode::kEscape:
      return "M6 escape";
  }
  return "unknown";
}

const char* to_string(PlanStatus status) {
  switch (status) {
    case PlanStatus::kSolved:
      return "solved";
    case PlanStatus::kTimeout:
      return "timeout";
    case PlanStatus::kStartInvalid:
      return "start invalid";
    case PlanStatus::kGoalInvalid:
      return "goal invalid";
    case PlanStatus::kNoPath:
      return "no path";
    case PlanStatus::kInvalidRequest:
      return "invalid request";
  }
  return "unknown";
}

std::vector<int> planned_joints(PlanMode mode) {
  switch (mode) {
    case PlanMode::kArm:
    case PlanMode::kArmCartesian:
      return {kArm1, kArm2, kArm3, kArm4};
    case PlanMode::kArmBase:
      return {kBaseX, kArm1, kArm2, kArm3, kArm4};
    case PlanMode::kNose:
      return {kNose1, kNose2, kNose3};
    case PlanMode::kBaseLine:
      return {kBaseX};
    case PlanMode::kEscape:
      return {kBaseX, kArm1, kArm2, kArm3, kArm4, kNose1};
  }
  return {};
}

plr::Status check_query(const PlanQuery& q, const RobotModel& robot) {
  auto bad = [](std::string why) { return plr::make_error(PLR_ERR_INVALID, std::move(why)); };
  const std::string mode = to_string(q.mode);
  if (mode == "unknown")
    return bad("unknown plan mode " + std::to_string(static_cast<int>(q.mode)));
  if (!q.start.allFinite()) return bad("start configuration has a non-finite value");
  if (!(q.time_limit_s > 0.0) || !std::isfinite(q.time_limit_s))
    return bad("time_limit_s must be positive and finite");
  if (!(q.improve_time_s >= 0.0)) return bad("improve_time_s must be >= 0");
  if (!(q.eps_initial >= 1.0) || !(q.eps_final >= 1.0) || q.eps_final > q.eps_initial ||
      !(q.eps_decrement > 0.0)) {
    return bad("epsilon schedule needs eps_initial >= eps_final >= 1 and eps_decrement > 0");
  }
  const bool joint = std::holds_alternative<JointGoal>(q.goal);
  const bool pose = std::holds_alternative<PoseGoal>(q.goal);
  switch (q.mode) {
    case PlanMode::kNose:
    case PlanMode::kBaseLine:
      if (!joint) return bad(mode + " needs a joint goal");
      break;
    case PlanMode::kArmCartesian:
      if (!pose) return bad(mode + " needs a pose goal");
      break;
    case PlanMode::kArm:
    case PlanMode::kArmBase:
      if (!joint && !pose) return bad(mode + " needs a joint or pose goal");
      break;
    case PlanMode::kEscape:
      if (joint || pose) return bad(mode + " takes no goal");
      break;
  }
  if (joint) {
    const JointGoal& g = std::get<JointGoal>(q.goal);
    if (!g.q.allFinite()) return bad("joint goal has a non-finite value");
    if (!(g.tolerance > 0.0)) return bad("joint goal tolerance must be positive");
    for (int j : planned_joints(q.mode)) {
      const JointLimits& l = robot.limits(j);
      if (g.q[j] < l.lower || g.q[j] > l.upper) {
        return bad(std::string("joint goal ") + kJointNames[j] + " = " + std::to_string(g.q[j]) +
                   " is beyond limits [" + std::to_string(l.lower) + ", " +
                   std::to_string(l.upper) + "]");
      }
    }
  }
  if (pose) {
    const PoseGoal& g = std::get<PoseGoal>(q.goal);
    if (!g.target.position.allFinite() || !std::isfinite(g.target.yaw))
      return bad("pose goal has a non-finite value");
    if (!(g.position_tolerance > 0.0) || !(g.yaw_tolerance > 0.0))
      return bad("pose goal tolerances must be positive");
  }
  for (const Box& b : q.held_boxes) {
    if (!(b.size.minCoeff() > 0.0) || !b.size.allFinite())
      return bad("held box " + std::to_string(b.id) + " has a bad size");
  }
  return {};
}

QueryScope::QueryScope(CollisionChecker& checker, const PlanQuery& query) : checker_(checker) {
  checker_.detach_all();
  checker_.clear_ignored_boxes();
  for (std::uint32_t id : query.ignored_boxes) checker_.ignore_box(id);
  for (const Box& b : query.held_boxes) checker_.attach_box(b, query.start);
}

QueryScope::~QueryScope() {
  checker_.detach_all();
  checker_.clear_ignored_boxes();
}

}  // namespace plr::planning
