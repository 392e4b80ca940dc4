#include "plr/actions/episode.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "plr/actions/instantiate.hpp"
#include "plr/sim/observation.hpp"

namespace plr::actions {

std::optional<std::string> RunRules::stop(std::size_t boxes) const {
  if (boxes == 0) return "trailer empty";
  if (limits_.max_actions != 0 && actions_ >= limits_.max_actions)
    return fmt::format("action limit ({})", limits_.max_actions);
  if (limits_.max_robot_time_s > 0 && robot_time_s_ >= limits_.max_robot_time_s)
    return fmt::format("robot-time horizon ({:g} s)", limits_.max_robot_time_s);
  if (excluded_.size() == static_cast<std::size_t>(sim::kNumActions))
    return fmt::format("no action moves a box: all {} tried since the last progress",
                       sim::kNumActions);
  if (limits_.max_idle_actions != 0 && idle_ >= limits_.max_idle_actions)
    return fmt::format("no progress in {} actions", idle_);
  return std::nullopt;
}

void RunRules::record(sim::Action action, const Outcome& outcome) {
  ++actions_;
  robot_time_s_ += outcome.robot_time_s;
  if (outcome.boxes > 0) {
    excluded_.clear();
    idle_ = 0;
    rounds_ = 0;
    shifted_ = false;
    return;
  }
  ++idle_;
  shifted_ = shifted_ || outcome.shifted > 0;
  if (!outcome.applicable || !outcome.failed_grasp)
    excluded_.insert(static_cast<std::uint8_t>(action));
  if (excluded_.size() == static_cast<std::size_t>(sim::kNumActions) && shifted_ &&
      rounds_ < kExtraRounds) {
    excluded_.clear();
    idle_ = 0;
    shifted_ = false;
    ++rounds_;
  }
}

bool RunRules::excluded(sim::Action action) const {
  return excluded_.count(static_cast<std::uint8_t>(action)) > 0;
}

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
                    const ActionModel& model) {
  sim::World alone;
  alone.trailer = world.trailer;
  alone.boxes.push_back(box);
  const auto& obs = model.options().observation;
  const sim::SceneAnalysis scene = sim::analyse(alone, obs);
  for (int a = 0; a < sim::kNumActions; ++a) {
    const auto action = static_cast<sim::Action>(a);
    if (sim::kind(action) != sim::ActionKind::kPick) continue;
    if (!pick_candidates(alone, scene, action, obs, model.robot(), model.options().geometry, q, 1,
                         {})
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
    const auto on = boxes_touching(world, robot, q, {link.name});
    if (std::find(on.begin(), on.end(), id) != on.end()) names.push_back(link.name);
  }
  return fmt::format("on {}", fmt::join(names, ", "));
}

}  // namespace

std::vector<LeftBox> boxes_left(const sim::World& world, const sim::JointVector& q,
                                const Memory& memory, const ActionModel& model) {
  const std::vector<std::uint32_t> on_robot = boxes_on_robot(world, model.robot(), q);
  std::vector<LeftBox> out;
  for (const auto& box : world.boxes) {
    LeftBox left{box.id, LeftReason::kBlocked, {}};
    if (const auto g = memory.grips.find(box.id); g != memory.grips.end() && g->second.given_up) {
      left.reason = LeftReason::kGivenUp;
      left.detail = g->second.why;
    } else if (std::find(on_robot.begin(), on_robot.end(), box.id) != on_robot.end()) {
      left.reason = LeftReason::kOnRobot;
      left.detail = links_under(world, box.id, model.robot(), q);
    } else if (behind_robot(box, q)) {
      left.reason = LeftReason::kBehind;
      left.detail = fmt::format("front edge at x {:.2f} m", q[sim::kBaseX]);
    } else if (const auto u = memory.unreached.find(box.id); u != memory.unreached.end()) {
      left.reason = LeftReason::kUnplanned;
      left.detail = u->second;
    } else if (!has_sealable_face(box)) {
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

StrategySource hardcoded_source(const sim::HardcodedParams& h) {
  return [h](const Perceived&, const sim::SceneAnalysis& scene,
             const RunRules& rules) -> plr::Expected<StrategyChoice> {
    for (const sim::Action a : sim::hardcoded_ranking(scene, h)) {
      if (rules.excluded(a)) continue;
      sim::Strategy s;
      s.name = "H";
      s.nodes.push_back({a, {}});
      return StrategyChoice{std::move(s), "hardcoded", {}};
    }
    return StrategyChoice{std::nullopt, "hardcoded", "every action of H's ranking moved nothing"};
  };
}

plr::Expected<Episode> run_strategies(const ActionModel& model, Backend& backend,
                                      const StrategySource& source, const RunLimits& limits,
                                      const std::function<void(const EpisodeStep&)>& on_step) {
  Episode e;
  RunRules rules(limits);
  Memory memory;
  std::optional<std::uint32_t> unloaded_at_start;
  sim::Strategy strategy;
  std::string from;
  bool blind = false;
  std::optional<std::uint32_t> node;
  for (;;) {
    auto seen = backend.observe();
    if (!seen) return seen.error();
    if (!unloaded_at_start) {
      unloaded_at_start = seen->unloaded;
      e.boxes_total = static_cast<std::uint32_t>(seen->world.boxes.size());
    }
    e.boxes_unloaded = seen->unloaded - *unloaded_at_start;
    std::optional<std::string> why = rules.stop(seen->world.boxes.size());
    const sim::SceneAnalysis scene = why ? sim::SceneAnalysis{} : model.scene(*seen, memory);
    if (!why) {
      // After an action that moved nothing, the tree is not followed
      // blindly: the source is asked again, its rules telling what failed.
      const auto child = node && (blind || rules.fresh()) ? strategy.next(*node, *scene.observation)
                                                          : std::nullopt;
      if (child) {
        node = child;
        ++e.strategy_steps;
      } else {
        auto choice = source(*seen, scene, rules);
        if (!choice) return choice.error();
        ++e.strategies_asked;
        if (!choice->strategy) {
          why = choice->why;
        } else {
          strategy = std::move(*choice->strategy);
          from = std::move(choice->source);
          blind = choice->blind;
          node = strategy.root;
        }
      }
    }
    if (why) {
      e.stop_reason = std::move(*why);
      e.left = boxes_left(seen->world, seen->q, memory, model);
      e.final_world = std::move(seen->world);
      return e;
    }
    const sim::Action action = strategy.nodes[*node].action;
    std::vector<std::string> notes;
    Reporter reporter;
    if (on_step) reporter.note = [&notes](const std::string& line) { notes.push_back(line); };
    auto out = model.run(action, backend, memory, reporter);
    if (!out) return out.error();
    rules.record(action, *out);
    ++e.actions;
    e.robot_time_s += out->robot_time_s;
    e.robot_trailer_contacts += out->robot_trailer_contacts;
    e.failed_grasps += out->failed_grasp ? 1 : 0;
    if (on_step)
      on_step(EpisodeStep{from, action, *scene.observation, scene.wall_height, scene.pile_height,
                          scene.pile_depth, *out, std::move(notes)});
  }
}

plr::Expected<Episode> run_hardcoded(const ActionModel& model, Backend& backend,
                                     const sim::HardcodedParams& h, const RunLimits& limits,
                                     const std::function<void(const EpisodeStep&)>& on_step) {
  return run_strategies(model, backend, hardcoded_source(h), limits, on_step);
}

}  // namespace plr::actions
