#include "plr/episode/rules.hpp"

#include <fmt/format.h>

namespace plr::episode {

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

void RunRules::record(sim::Action action, const actions::Outcome& outcome) {
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

}  // namespace plr::episode
