#include "plr/episode/left.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "plr/actions/instantiate.hpp"
#include "plr/sim/observation.hpp"

namespace plr::episode {

const char* to_string(LeftReason reason) {
  switch (reason) {
    case LeftReason::kGivenUp:
      return "given up";
    case LeftReason::kUnplanned:
      return "no motion planned";
    case LeftReason::kOnRobot:
      return "on the robot";
    case LeftReason::kBehind:
      return "behind the robot";
    case LeftReason::kNoFace:
      return "no face the plate seals on";
    case LeftReason::kOutOfReach:
      return "out of reach";
    case LeftReason::kBlocked:
      return "blocked";
  }
  return "?";
}

namespace {

constexpr double kTouch = 0.02;   // m: a box this close above another rests on it
constexpr double kInFront = 1.0;  // m: boxes further before a box are not named as in its way

bool overlap(double a0, double a1, double b0, double b1) {
  return a0 < b1 && b0 < a1;
}

bool pickable_alone(const sim::World& world, const sim::Box& box, const sim::JointVector& q,
                    const actions::ActionModel& model) {
  sim::World alone;
  alone.trailer = world.trailer;
  alone.boxes.push_back(box);
  const auto& obs = model.options().observation;
  const sim::SceneAnalysis scene = sim::analyse(alone, obs);
  for (int a = 0; a < sim::kNumActions; ++a) {
    const auto action = static_cast<sim::Action>(a);
    if (sim::kind(action) != sim::ActionKind::kPick) continue;
    if (!actions::pick_candidates(alone, scene, action, obs, model.robot(),
                                  model.options().geometry, q, 1, {})
             .empty())
      return true;
  }
  return false;
}

// The boxes in front of `b` (between it and the robot, overlapping its
// outline across) and those resting on it.
std::string in_the_way(const sim::World& world, const sim::Box& box) {
  const sim::Bounds b = sim::bounds(box);
  std::vector<std::uint32_t> front, top;
  for (const auto& other : world.boxes) {
    if (other.id == box.id) continue;
    const sim::Bounds o = sim::bounds(other);
    if (!overlap(o.y0, o.y1, b.y0, b.y1)) continue;
    if (o.x1 <= b.x0 + kTouch && o.x1 > b.x0 - kInFront && overlap(o.z0, o.z1, b.z0, b.z1))
      front.push_back(other.id);
    else if (o.z0 >= b.z1 - kTouch && overlap(o.x0, o.x1, b.x0, b.x1))
      top.push_back(other.id);
  }
  std::string out;
  if (!front.empty()) out = fmt::format("in front: {}", fmt::join(front, ", "));
  if (!top.empty())
    out += fmt::format("{}resting on it: {}", out.empty() ? "" : "; ", fmt::join(top, ", "));
  return out.empty() ? "no pick region takes it" : out;
}

// The robot's links a box lying on the robot touches.
std::string links_under(const sim::World& world, std::uint32_t id, const sim::RobotModel& robot,
                        const sim::JointVector& q) {
  std::vector<std::string> names;
  for (const auto& link : robot.links()) {
    const auto on = actions::boxes_touching(world, robot, q, {link.name});
    if (std::find(on.begin(), on.end(), id) != on.end()) names.push_back(link.name);
  }
  return fmt::format("on {}", fmt::join(names, ", "));
}

}  // namespace

std::vector<LeftBox> boxes_left(const sim::World& world, const sim::JointVector& q,
                                const actions::Memory& memory, const actions::ActionModel& model) {
  const std::vector<std::uint32_t> on_robot = actions::boxes_on_robot(world, model.robot(), q);
  std::vector<LeftBox> out;
  for (const auto& box : world.boxes) {
    LeftBox left{box.id, LeftReason::kBlocked, {}};
    if (const auto g = memory.grips.find(box.id); g != memory.grips.end() && g->second.given_up) {
      left.reason = LeftReason::kGivenUp;
      left.detail = g->second.why;
    } else if (std::find(on_robot.begin(), on_robot.end(), box.id) != on_robot.end()) {
      left.reason = LeftReason::kOnRobot;
      left.detail = links_under(world, box.id, model.robot(), q);
    } else if (actions::behind_robot(box, q)) {
      left.reason = LeftReason::kBehind;
      left.detail = fmt::format("front edge at x {:.2f} m", q[sim::kBaseX]);
    } else if (const auto u = memory.unreached.find(box.id); u != memory.unreached.end()) {
      left.reason = LeftReason::kUnplanned;
      left.detail = u->second;
    } else if (!actions::has_sealable_face(box)) {
      left.reason = LeftReason::kNoFace;
    } else if (!pickable_alone(world, box, q, model)) {
      left.reason = LeftReason::kOutOfReach;
    } else {
      left.detail = in_the_way(world, box);
    }
    out.push_back(std::move(left));
  }
  return out;
}

std::map<std::string, std::uint32_t> count_by_reason(const std::vector<LeftBox>& left) {
  std::map<std::string, std::uint32_t> out;
  for (const auto& l : left) ++out[to_string(l.reason)];
  return out;
}

}  // namespace plr::episode
